"""Affine transforms for scene objects: object -> world as a 3x4 matrix [A | t] (row-major, like the C side).

Two ways to write one in a scene (see README.md, "Rendering scenes"):
  {scale: s | [sx, sy, sz], rotate: [rx, ry, rz] | {axis: [x, y, z], angle: deg}, translate: [x, y, z]}
      applied in that order (scale, then rotate, then translate), each optional;
  {position: [x, y, z], axes: [u, v, w]}
      the piriform paper's form: u, v, w are the images of the object's x, y, z axes (the columns of A), so
      they carry orientation and size; the position is where the object's origin goes.
A list of such mappings composes them, the first applied first.
"""

from __future__ import annotations

import math
from typing import Any, Sequence

import numpy as np

from .errors import UserError

IDENTITY = np.hstack([np.eye(3), np.zeros((3, 1))])


def _vec3(source: str, key: str, value: Any) -> np.ndarray:
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise UserError(source, f"{key}: expected a list of three numbers")
    out = []
    for v in value:
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise UserError(source, f"{key}: expected a list of three finite numbers")
        out.append(float(v))
    return np.array(out)


def _number(source: str, key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(source, f"{key}: expected a finite number")
    return float(value)


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
            m = compose(parse_transform(source, f"{key}[{i}]", step), m)
        return m
    if not isinstance(raw, dict):
        raise UserError(source, f"{key}: expected a mapping (scale/rotate/translate or position/axes) or a list")
    if "axes" in raw or "position" in raw:
        extra = set(raw) - {"position", "axes"}
        if extra:
            raise UserError(source, f"{key}.{sorted(extra)[0]}: not allowed with position/axes")
        if "axes" not in raw:
            raise UserError(source, f"{key}: 'position' needs 'axes' (three vectors u, v, w)")
        axes = raw["axes"]
        if not isinstance(axes, list) or len(axes) != 3:
            raise UserError(source, f"{key}.axes: expected three vectors [u, v, w]")
        cols = [_vec3(source, f"{key}.axes[{i}]", a) for i, a in enumerate(axes)]
        pos = _vec3(source, f"{key}.position", raw.get("position", [0, 0, 0]))
        m = affine(np.column_stack(cols), pos)
    else:
        extra = set(raw) - {"scale", "rotate", "translate"}
        if extra:
            raise UserError(source, f"{key}.{sorted(extra)[0]}: unknown key (allowed: scale, rotate, translate, "
                                    "or position + axes)")
        lin = np.eye(3)
        if "scale" in raw:
            s = raw["scale"]
            sv = np.full(3, _number(source, f"{key}.scale", s)) if not isinstance(s, list) else \
                _vec3(source, f"{key}.scale", s)
            lin = np.diag(sv) @ lin
        if "rotate" in raw:
            r = raw["rotate"]
            if isinstance(r, dict):
                extra = set(r) - {"axis", "angle"}
                if extra or "axis" not in r or "angle" not in r:
                    raise UserError(source, f"{key}.rotate: expected {{axis: [x, y, z], angle: degrees}}")
                axis = _vec3(source, f"{key}.rotate.axis", r["axis"])
                if not np.linalg.norm(axis) > 0:
                    raise UserError(source, f"{key}.rotate.axis: must not be zero")
                rot = rotation_axis_angle(axis, _number(source, f"{key}.rotate.angle", r["angle"]))
            else:
                rot = rotation_xyz(_vec3(source, f"{key}.rotate", r))
            lin = rot @ lin
        t = _vec3(source, f"{key}.translate", raw["translate"]) if "translate" in raw else np.zeros(3)
        m = affine(lin, t)
    check_invertible(source, key, m)
    return m


def check_invertible(source: str, key: str, m: np.ndarray) -> None:
    a = m[:, :3]
    scale = float(np.abs(a).max())
    if not scale > 0 or abs(float(np.linalg.det(a))) <= 1e-12 * scale**3:
        raise UserError(source, f"{key}: the transform is singular (flattens the object); "
                                "axes must be linearly independent and scales non-zero")


def invert(m: np.ndarray) -> np.ndarray:
    ai = np.linalg.inv(m[:, :3])
    return affine(ai, -ai @ m[:, 3])
