"""Affine transforms for scene objects: object -> world as a 3x4 matrix [A | t] (row-major, like the C side).

Two ways to write one in a scene (docs/formats.md#the-scene-format):
  {scale: s | [sx, sy, sz], rotate: [rx, ry, rz] | {axis: [x, y, z], angle: deg}, translate: [x, y, z]}
      applied in that order (scale, then rotate, then translate), each optional;
  {position: [x, y, z], axes: [u, v, w]}
      the piriform paper's form: u, v, w are the images of the object's x, y, z axes (the columns of A), so
      they carry orientation and size; the position is where the object's origin goes.
A list of such mappings composes them, the first applied first.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from implgen import validate
from implgen.errors import UserError

IDENTITY = np.hstack([np.eye(3), np.zeros((3, 1))])
# Documented range of the linear part: scales (and axis vectors) between 1e-6 and 1e6 in size, also once
# composed, so a transform list cannot multiply its way out of double range.
MAX_SCALE = 1e6
MIN_SCALE = 1e-6


def _vec3(source: str, key: str, value: Any, limit: float = validate.MAX_COORDINATE) -> np.ndarray:
    return np.array(validate.vector(source, key, value, -limit, limit))


def _number(source: str, key: str, value: Any, limit: float = validate.MAX_COORDINATE) -> float:
    return validate.number(source, key, value, -limit, limit)


def _scale(source: str, key: str, value: Any) -> np.ndarray:
    sv = (
        _vec3(source, key, value, MAX_SCALE)
        if isinstance(value, list)
        else np.full(3, _number(source, key, value, MAX_SCALE))
    )
    if np.abs(sv).min() < MIN_SCALE:
        raise UserError(
            source, f"{key}: a scale must be at least {MIN_SCALE:g} in size (a zero scale flattens the object)"
        )
    return sv


def affine(linear: np.ndarray, translation: np.ndarray | Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    return np.hstack([np.asarray(linear, float), np.asarray(translation, float).reshape(3, 1)])


def compose(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    """outer after inner (both 3x4)."""
    a = outer[:, :3] @ inner[:, :3]
    t = outer[:, :3] @ inner[:, 3] + outer[:, 3]
    return affine(a, t)


def rotation_axis_angle(axis: np.ndarray, degrees: float) -> np.ndarray:
    """Rodrigues' formula: right-handed rotation by `degrees` about `axis`."""
    n = float(np.linalg.norm(axis))
    x, y, z = axis / n
    th = math.radians(degrees)
    c, s = math.cos(th), math.sin(th)
    k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def rotation_xyz(angles: np.ndarray) -> np.ndarray:
    """Rotate about x, then y, then z (degrees)."""
    rx = rotation_axis_angle(np.array([1.0, 0, 0]), angles[0])
    ry = rotation_axis_angle(np.array([0, 1.0, 0]), angles[1])
    rz = rotation_axis_angle(np.array([0, 0, 1.0]), angles[2])
    return rz @ ry @ rx


def parse_transform(source: str, key: str, raw: Any) -> np.ndarray:
    """A validated 3x4 object -> world matrix (UserError naming `key` on bad input)."""
    if raw is None:
        return IDENTITY.copy()
    if isinstance(raw, list):
        m = IDENTITY.copy()
        for i, step in enumerate(raw):
            if not isinstance(step, dict):  # a list holds mappings; lists do not nest
                raise UserError(source, f"{key}[{i}]: expected a mapping (scale/rotate/translate or position/axes)")
            m = compose(parse_transform(source, f"{key}[{i}]", step), m)
            check_matrix(source, key, m)  # the composition so far, before it can grow any further
        return m
    if not isinstance(raw, dict):
        raise UserError(source, f"{key}: expected a mapping (scale/rotate/translate or position/axes) or a list")
    if "axes" in raw or "position" in raw:
        extra = set(raw) - {"position", "axes"}
        if extra:
            raise UserError(source, f"{key}.{min(extra, key=str)}: not allowed with position/axes")
        if "axes" not in raw:
            raise UserError(source, f"{key}: 'position' needs 'axes' (three vectors u, v, w)")
        axes = raw["axes"]
        if not isinstance(axes, list) or len(axes) != 3:
            raise UserError(source, f"{key}.axes: expected three vectors [u, v, w]")
        cols = [_vec3(source, f"{key}.axes[{i}]", a, MAX_SCALE) for i, a in enumerate(axes)]
        pos = _vec3(source, f"{key}.position", raw.get("position", [0, 0, 0]))
        m = affine(np.column_stack(cols), pos)
    else:
        extra = set(raw) - {"scale", "rotate", "translate"}
        if extra:
            raise UserError(
                source,
                f"{key}.{min(extra, key=str)}: unknown key (allowed: scale, rotate, translate, or position + axes)",
            )
        lin = np.eye(3)
        if "scale" in raw:
            lin = np.diag(_scale(source, f"{key}.scale", raw["scale"])) @ lin
        if "rotate" in raw:
            r = raw["rotate"]
            if isinstance(r, dict):
                extra = set(r) - {"axis", "angle"}
                if extra or "axis" not in r or "angle" not in r:
                    raise UserError(source, f"{key}.rotate: expected {{axis: [x, y, z], angle: degrees}}")
                axis = _vec3(source, f"{key}.rotate.axis", r["axis"], MAX_SCALE)
                if not np.linalg.norm(axis) > 0:
                    raise UserError(source, f"{key}.rotate.axis: must not be zero")
                rot = rotation_axis_angle(axis, _number(source, f"{key}.rotate.angle", r["angle"]))
            else:
                rot = rotation_xyz(_vec3(source, f"{key}.rotate", r))
            lin = rot @ lin
        t = _vec3(source, f"{key}.translate", raw["translate"]) if "translate" in raw else np.zeros(3)
        m = affine(lin, t)
    check_matrix(source, key, m)
    return m


def check_matrix(source: str, key: str, m: np.ndarray) -> None:
    """An object -> world matrix the tracer can invert: finite, its linear part's singular values (how much
    it stretches along any direction) within [MIN_SCALE, MAX_SCALE], its translation within the coordinate
    range. Also applied to composed transforms (lists, CSG nodes)."""
    if not np.isfinite(m).all():
        raise UserError(source, f"{key}: the composed transform is not finite")
    sigma = np.linalg.svd(m[:, :3], compute_uv=False)
    if not sigma[-1] > 1e-12 * sigma[0]:
        raise UserError(
            source,
            f"{key}: the transform is singular (flattens the object); "
            "axes must be linearly independent and scales non-zero",
        )
    if sigma[0] > MAX_SCALE * (1 + 1e-9) or sigma[-1] < MIN_SCALE * (1 - 1e-9):
        raise UserError(
            source,
            f"{key}: the transform stretches by {sigma[0]:.3g} and shrinks to {sigma[-1]:.3g}"
            f"; both must lie within [{MIN_SCALE:g}, {MAX_SCALE:g}]",
        )
    if np.abs(m[:, 3]).max() > validate.MAX_COORDINATE:
        raise UserError(source, f"{key}: the transform moves the object beyond {validate.MAX_COORDINATE:g}")
