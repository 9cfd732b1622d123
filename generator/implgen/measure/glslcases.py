"""The ray sets the GLSL is checked on (tests/test_glsl_browser.py, bench/glsl_compare.py): every example shape
through a camera, Chmutov surfaces of degree 12 to 24 in two forms, a torus from 10^3 units, grazing rays.

Chmutov surfaces T_n(x) + T_n(y) + T_n(z) = 0 come in the power form bench/scenes/ uses (the expanded Chebyshev
polynomial: coefficients up to 2^(n-1), which cancel at |x| near 1 by a factor of about (1 + sqrt 2)^n / 2) and
in a nested form, T_mn = T_m(T_n), written as compositions of T_2(u) = 2u^2 - 1, T_3(u) = u(4u^2 - 3) and
T_5(u) = u(16u^4 - 20u^2 + 5), which is well conditioned in float. Same surface, two trees: the GLSL
evaluates the tree as written (docs/glsl.md, "What the form of f does").
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.polynomial import chebyshev

from implgen.measure.glslcheck import Case, camera_rays, make_case, sphere_interval
from implgen.spec.entry import load_spec, parse_spec

VIEW = np.array([0.55, 0.45, 0.7]) / np.linalg.norm([0.55, 0.45, 0.7])
CLIP_RADIUS = 2.0  # the clip sphere around the origin for shapes without a box on every axis


def _t2(u: str) -> str:
    return f"(2*({u})^2 - 1)"


def _nested(n: int, v: str) -> str:
    """T_n(v) as a composition, for n in 12, 16, 20, 24."""
    t4 = _t2(_t2(v))
    t8 = _t2(t4)
    if n == 12:
        return f"{t4}*(4*{t4}^2 - 3)"
    if n == 16:
        return _t2(t8)
    if n == 20:
        return f"{t4}*(16*{t4}^4 - 20*{t4}^2 + 5)"
    if n == 24:
        return f"{t8}*(4*{t8}^2 - 3)"
    raise ValueError(n)


def _power(n: int) -> str:
    """T_n(x) + T_n(y) + T_n(z) expanded, grouped by power as bench/scenes/chmutov16.yaml writes it."""
    c = chebyshev.cheb2poly([0] * n + [1])
    terms = [f"{int(c[0]) * 3}"]
    for k in range(2, n + 1, 2):
        v = int(c[k])
        terms.append(f"{'-' if v < 0 else '+'} {abs(v)}*(x^{k} + y^{k} + z^{k})")
    return " ".join(terms)


def chmutov(n: int, nested: bool):
    """The Chmutov surface of degree n; its box is where T_n(x) <= 3 can hold: |x| <= cosh(acosh(3) / n)."""
    equation = " + ".join(_nested(n, v) for v in "xyz") if nested else _power(n)
    side = float(np.cosh(np.arccosh(3.0) / n)) * 1.001
    box = {a: [-side, side] for a in "xyz"}
    name = f"chmutov{n}{'n' if nested else ''}"
    return parse_spec({"name": name, "equation": equation, "bounds": box}, "<glslcases>")


def view_case(label: str, spec, size: tuple[int, int], distance: float = 3.2, params=None) -> Case:
    """The shape seen along VIEW from `distance` times its radius (the box's half diagonal, or the clip sphere's
    radius when the box is open on some axis, in which case the rays are clipped to that sphere)."""
    params = dict(spec.params if params is None else params)
    box = spec.box(params)
    bounded = box is not None and all(np.isfinite(box))
    if bounded:
        centre = 0.5 * (np.array(box[:3]) + np.array(box[3:]))
        radius = 0.5 * float(np.linalg.norm(np.array(box[3:]) - np.array(box[:3])))
    else:
        centre, radius = np.zeros(3), CLIP_RADIUS
    eye = centre + distance * radius * VIEW
    fov = 2.0 * np.degrees(np.arctan(1.05 * radius / (distance * radius)))
    o, d = camera_rays(eye, centre, (0.0, 1.0, 0.0), fov, size)
    if bounded:
        return make_case(label, spec, o, d, 0.0, np.inf, params)
    tmin, tmax = sphere_interval(o, d, (0.0, 0.0, 0.0), CLIP_RADIUS)
    return make_case(label, spec, o, d, tmin, tmax, params)


def example_cases(shapes_dir: Path, size: tuple[int, int]) -> list[Case]:
    return [view_case(p.stem, load_spec(p), size) for p in sorted(Path(shapes_dir).glob("*.yaml"))]


def high_degree_cases(size: tuple[int, int], forms: tuple[bool, ...] = (True, False)) -> list[Case]:
    """Chmutov 12, 16, 20, 24, nested and (unless forms says otherwise) power form."""
    out = []
    for n in (12, 16, 20, 24):
        for nested in forms:
            spec = chmutov(n, nested)
            out.append(view_case(spec.name, spec, size))
    return out


def far_torus_case(shapes_dir: Path, size: tuple[int, int], distance: float = 1.0e3) -> Case:
    """torus_y (a = 1, b = 0.3) seen from `distance` units through a telephoto lens that keeps the framing."""
    spec = load_spec(Path(shapes_dir) / "torus_y.yaml")
    params = {"a": 1.0, "b": 0.3}
    box = np.array(spec.box(params))
    radius = 0.5 * float(np.linalg.norm(box[3:] - box[:3]))
    return view_case(f"torus_y at {distance:g}", spec, size, distance / radius, params)


def grazing_case(shapes_dir: Path, width: int, delta: float = 1.0e-3) -> Case:
    """Rays along x at heights z = r + k delta, k = -3..3, over torus_z (R = 1, r = 0.25): the row k = 0 touches
    the top circle of the tube exactly (f = (x^2 + y^2 - 1)^2 >= 0 on that plane, a double root), the rows
    below cross the tube (hits), the rows above pass over it (misses). Columns: y from -1.2 to 1.2."""
    spec = load_spec(Path(shapes_dir) / "torus_z.yaml")
    ks = np.arange(-3, 4)
    ys = np.linspace(-1.2, 1.2, width)
    o = np.zeros((len(ks), width, 3))
    o[..., 0] = -3.0
    o[..., 1] = ys[None, :]
    o[..., 2] = 0.25 + ks[:, None] * delta
    d = np.zeros_like(o)
    d[..., 0] = 1.0
    return make_case("torus_z grazing", spec, o, d, 0.0, np.inf, {"R": 1.0, "r": 0.25})
