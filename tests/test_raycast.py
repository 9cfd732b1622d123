"""implgen.raycast (the Python twin of ig_shape_roots) on a torus, against exact root isolation of the ray
polynomial expanded in exact rational arithmetic at the ray's own (unshifted) origin."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import sympy as sp

from implgen.raycast import all_hits, nearest_hit

A, B = 1.0, 0.4
BOX = np.array([-1.4, -0.4, -1.4, 1.4, 0.4, 1.4])


def torus_coeffs(o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Suffern eq. 19.22, vectorised; lowest power first."""
    dd = (d * d).sum(-1)
    e = (o * o).sum(-1) - A * A - B * B
    f = (o * d).sum(-1)
    fa = 4 * A * A
    return np.stack(
        [
            e * e - fa * (B * B - o[..., 1] ** 2),
            4 * f * e + 2 * fa * o[..., 1] * d[..., 1],
            2 * dd * e + 4 * f * f + fa * d[..., 1] ** 2,
            4 * dd * f,
            dd * dd,
        ],
        axis=-1,
    )


def exact_nearest(o: np.ndarray, d: np.ndarray) -> float:
    """Nearest t >= 0 where the exact ray (rationals of the doubles) meets the exact torus."""
    t = sp.Symbol("t")
    a, b = sp.Rational(Fraction(A)), sp.Rational(Fraction(B))
    x, y, z = (sp.Rational(Fraction(float(o[k]))) + t * sp.Rational(Fraction(float(d[k]))) for k in range(3))
    s = x * x + y * y + z * z
    f = sp.Poly(sp.expand(s * s - 2 * (a * a + b * b) * s + 4 * a * a * y * y + (a * a - b * b) ** 2), t)
    roots = [float((lo + hi) / 2) for (lo, hi), _ in f.intervals(eps=sp.Rational(1, 10**18)) if hi >= 0]
    return min(roots) if roots else np.inf


def random_rays(n: int, dist: float, rng: np.random.Generator):
    target = rng.uniform(-1, 1, size=(n, 3)) * [1.5, 0.5, 1.5]
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return target - dist * d, d * rng.uniform(0.5, 2.0, size=(n, 1))  # non-unit directions


def test_nearest_hit_against_exact_reference_near_and_far() -> None:
    rng = np.random.default_rng(1)
    for dist in (5.0, 1e4):
        o, d = random_rays(12, dist, rng)
        got = nearest_hit(torus_coeffs, BOX, o, d, 0.0, np.inf)
        for i in range(len(o)):
            want = exact_nearest(o[i], d[i])
            if np.isinf(want):
                assert np.isinf(got[i])
            else:
                assert abs(got[i] - want) <= 1e-12 * want, (dist, got[i], want)


def test_far_rays_reproduce_near_rays() -> None:
    rng = np.random.default_rng(2)
    o, d = random_rays(5000, 5.0, rng)
    u = d / np.linalg.norm(d, axis=1, keepdims=True)
    far = o - (1e4 - 5.0) * u
    tn = nearest_hit(torus_coeffs, BOX, o, d, 0.0, np.inf)
    tf = nearest_hit(torus_coeffs, BOX, far, d, 0.0, np.inf)
    hit = np.isfinite(tn)
    np.testing.assert_array_equal(hit, np.isfinite(tf))
    assert hit.sum() > 1000
    pn = o[hit] + tn[hit, None] * d[hit]
    pf = far[hit] + tf[hit, None] * d[hit]
    assert np.abs(pn - pf).max() <= 1e-9
    # and the shift is what makes it work: expanded at the far origin, the same rays go wrong
    from implgen.roots.solvers import real_roots_batch

    r, k = real_roots_batch(torus_coeffs(far, d), 0.0, np.inf)
    assert ((k > 0) != hit).sum() > 100


def test_all_hits_box_none_and_broadcasting() -> None:
    o, d = np.array([-5.0, 0.0, 0.0]), np.array([2.0, 0.0, 0.0])
    want = [(5 - 1.4) / 2, (5 - 0.6) / 2, (5 + 0.6) / 2, (5 + 1.4) / 2]
    np.testing.assert_allclose(all_hits(torus_coeffs, BOX, o, d, 0.0, np.inf), want, rtol=1e-14)
    np.testing.assert_allclose(all_hits(torus_coeffs, None, o, d, 0.0, np.inf), want, rtol=1e-14)
    np.testing.assert_allclose(all_hits(torus_coeffs, BOX, o, d, 2.0, 2.9), want[1:3], rtol=1e-14)
    t = nearest_hit(torus_coeffs, BOX, o, d, 0.0, np.inf)
    assert np.shape(t) == () and abs(float(t) - want[0]) <= 1e-14
    os_ = np.stack([o, o + [0, 5, 0], o])
    ts = nearest_hit(torus_coeffs, BOX, os_, d, np.array([0.0, 0.0, 2.0]), np.inf)
    assert ts.shape == (3,) and np.isinf(ts[1]) and abs(ts[2] - want[1]) < 1e-14
    grid = nearest_hit(torus_coeffs, None, np.broadcast_to(o, (2, 4, 3)), d, 0.0, np.inf)
    assert grid.shape == (2, 4)
    assert np.isinf(nearest_hit(torus_coeffs, BOX, o, np.zeros(3), 0.0, np.inf))
    assert np.isinf(nearest_hit(torus_coeffs, BOX, [np.nan, 0, 0], d, 0.0, np.inf))
