"""Generated coefficients and gradients against the textbook formulas (seeds 000, 003, 004).

Each reference is written out here by hand from the book, independently of the generator. Both the generated
Python and the generated C (compiled and called) are checked, on 1000 random rays with non-unit directions.
"""

from __future__ import annotations

import numpy as np
import pytest

from conftest import CShapes, load_python_shape, random_rays

N_RAYS = 1000
REL = 1e-12


def _close(got: np.ndarray, want: np.ndarray, rel: float = REL) -> None:
    """Each ray's coefficients agree to `rel` relative to that ray's largest coefficient."""
    scale = np.max(np.abs(want), axis=-1, keepdims=True)
    err = np.max(np.abs(got - want) / scale)
    assert err < rel, f"max relative error {err:.3e}"


def suffern_torus(o, d, a, b):
    """Suffern, Ray Tracing from the Ground Up, listing 19.9 (torus about the y-axis)."""
    x1, y1, z1 = o.T
    d1, d2, d3 = d.T
    sum_d_sqrd = d1 * d1 + d2 * d2 + d3 * d3
    e = x1 * x1 + y1 * y1 + z1 * z1 - a * a - b * b
    f = x1 * d1 + y1 * d2 + z1 * d3
    four_a_sqrd = 4.0 * a * a
    return np.stack(
        [
            e * e - four_a_sqrd * (b * b - y1 * y1),
            4.0 * f * e + 2.0 * four_a_sqrd * y1 * d2,
            2.0 * sum_d_sqrd * e + 4.0 * f * f + four_a_sqrd * d2 * d2,
            4.0 * sum_d_sqrd * f,
            sum_d_sqrd * sum_d_sqrd,
        ],
        axis=-1,
    )


def suffern_torus_eq_19_22(o, d, a, b):
    """The same torus, from the printed equations 19.22 (c_0 as in the listing: e^2 - 4a^2(b^2 - o_y^2))."""
    ox, oy, oz = o.T
    dx, dy, dz = d.T
    dd = dx**2 + dy**2 + dz**2
    od = ox * dx + oy * dy + oz * dz
    oo = ox**2 + oy**2 + oz**2 - (a**2 + b**2)
    return np.stack(
        [
            oo**2 - 4 * a**2 * (b**2 - oy**2),
            4 * oo * od + 8 * a**2 * oy * dy,
            2 * dd * oo + 4 * od**2 + 4 * a**2 * dy**2,
            4 * dd * od,
            dd**2,
        ],
        axis=-1,
    )


def rtn_torus(o, d, R, r):
    """Ray Tracing News 3(7), as quoted in the assignment (torus about the z-axis); A..E highest first."""
    x0, y0, z0 = o.T
    xd, yd, zd = d.T
    A = (xd**2 + yd**2 + zd**2) ** 2
    B = 4 * (x0 * xd + y0 * yd + z0 * zd) * (xd**2 + yd**2 + zd**2)
    C = (
        2 * (xd**2 + yd**2 + zd**2) * (x0**2 + y0**2 + z0**2 - R**2 - r**2)
        + 4 * (x0 * xd + y0 * yd + z0 * zd) ** 2
        + 4 * R**2 * zd**2
    )
    D = 4 * (x0 * xd + y0 * yd + z0 * zd) * (x0**2 + y0**2 + z0**2 - R**2 - r**2) + 8 * R**2 * z0 * zd
    E = (x0**2 + y0**2 + z0**2 - R**2 - r**2) ** 2 - 4 * R**2 * (r**2 - z0**2)
    return np.stack([E, D, C, B, A], axis=-1)


def suffern_cylinder(o, d, r):
    """Suffern eq. 19.17: a = dx^2 + dz^2, b = 2(ox dx + oz dz), c = ox^2 + oz^2 - r^2."""
    a = d[:, 0] ** 2 + d[:, 2] ** 2
    b = 2 * (o[:, 0] * d[:, 0] + o[:, 2] * d[:, 2])
    c = o[:, 0] ** 2 + o[:, 2] ** 2 - r**2
    return np.stack([c, b, a], axis=-1)


def assignment_cone(o, d):
    """The assignment's cone x^2 + y^2 - z^2: A t^2 + B t + C."""
    x0, y0, z0 = o.T
    xd, yd, zd = d.T
    return np.stack([x0**2 + y0**2 - z0**2, 2.0 * (x0 * xd + y0 * yd - z0 * zd), xd**2 + yd**2 - zd**2], axis=-1)


def sphere_abc(o, d, r):
    return np.stack([np.sum(o * o, -1) - r * r, 2 * np.sum(o * d, -1), np.sum(d * d, -1)], axis=-1)


def piriform_expanded(o, d):
    """(X^4 - X^3) + Y^2 + Z^2 with X = x0 + t x1 etc., expanded by the binomial theorem (seed 004)."""
    x0, y0, z0 = o.T
    x1, y1, z1 = d.T
    c4 = x1**4
    c3 = 4 * x0 * x1**3 - x1**3
    c2 = 6 * x0**2 * x1**2 - 3 * x0 * x1**2 + y1**2 + z1**2
    c1 = 4 * x0**3 * x1 - 3 * x0**2 * x1 + 2 * y0 * y1 + 2 * z0 * z1
    c0 = x0**4 - x0**3 + y0**2 + z0**2
    return np.stack([c0, c1, c2, c3, c4], axis=-1)


CASES = {
    # shape: (reference(o, d), params in declared order)
    "torus_y": (lambda o, d: suffern_torus(o, d, 1.3, 0.4), {"a": 1.3, "b": 0.4}),
    "torus_z": (lambda o, d: rtn_torus(o, d, 1.7, 0.6), {"R": 1.7, "r": 0.6}),
    "cylinder": (lambda o, d: suffern_cylinder(o, d, 0.8), {"r": 0.8}),
    "cone": (assignment_cone, {}),
    "sphere": (lambda o, d: sphere_abc(o, d, 1.5), {"r": 1.5}),
    "piriform": (piriform_expanded, {}),
}


@pytest.fixture(scope="module")
def cshapes() -> CShapes:
    return CShapes(list(CASES))


@pytest.mark.parametrize("name", list(CASES))
def test_python_coefficients_match_textbook(name, rng):
    reference, params = CASES[name]
    module = load_python_shape(name)
    o, d = random_rays(rng, N_RAYS)
    _close(module.coeffs(o, d, **params), reference(o, d))


@pytest.mark.parametrize("name", list(CASES))
def test_c_coefficients_match_textbook(name, rng, cshapes):
    reference, params = CASES[name]
    module = load_python_shape(name)
    o, d = random_rays(rng, N_RAYS)
    got = np.array([cshapes.coeffs(name, module.DEGREE, o[i], d[i], list(params.values())) for i in range(N_RAYS)])
    _close(got, reference(o, d))


def test_suffern_listing_equals_equation_19_22(rng):
    # Guards the reference itself: the book's two forms must agree before we compare against them.
    o, d = random_rays(rng, N_RAYS)
    _close(suffern_torus(o, d, 1.3, 0.4), suffern_torus_eq_19_22(o, d, 1.3, 0.4))


def test_torus_gradient_matches_suffern_normal(rng, cshapes):
    a, b = 1.3, 0.4
    p = rng.uniform(-2, 2, (N_RAYS, 3))
    s = np.sum(p * p, -1) - (a * a + b * b)
    want = np.stack([4 * p[:, 0] * s, 4 * p[:, 1] * (s + 2 * a * a), 4 * p[:, 2] * s], -1)
    module = load_python_shape("torus_y")
    _close(module.gradient(p, a=a, b=b), want)
    got = np.array([cshapes.gradient("torus_y", q, [a, b]) for q in p])
    _close(got, want)


def test_piriform_gradient_matches_paper(rng, cshapes):
    p = rng.uniform(-1, 2, (N_RAYS, 3))
    x, y, z = p.T
    want = np.stack([4 * x**3 - 3 * x**2, 2 * y, 2 * z], -1)
    _close(load_python_shape("piriform").gradient(p), want)
    _close(np.array([cshapes.gradient("piriform", q) for q in p]), want)


def test_piriform_degree_drops_exactly_when_dx_is_zero(cshapes):
    # Seed 004: with d_x = 0 the quartic is really a quadratic; the solver relies on exact zeros.
    c = cshapes.coeffs("piriform", 4, [0.3, 0.1, -0.2], [0.0, 0.7, 0.4])
    assert c[4] == 0.0 and c[3] == 0.0 and c[2] != 0.0


def test_cylinder_leading_coefficient_vanishes_along_axis(cshapes):
    c = cshapes.coeffs("cylinder", 2, [0.3, 5.0, -0.2], [0.0, -2.5, 0.0], [1.0])
    assert c[2] == 0.0 and c[1] == 0.0
