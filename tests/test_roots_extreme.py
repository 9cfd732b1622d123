"""Roots at the edges of the double range, against exact real-root isolation on the rationals of the double
coefficients (implgen.measure.cases.reference): quartics whose roots spread over ~150 decades next to the overflow
limit, and torus ray polynomials written at a far origin, where the double polynomial's roots are what counts."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from implgen.measure.cases.extreme import far_torus_rays, spread_quartics
from implgen.measure.cases.reference import U, exact_roots, reference, score_one
from implgen.roots.solvers import first_root_batch, real_roots, real_roots_batch

ACCURATE = ["auto", "bracket", "bernstein"]


@pytest.mark.parametrize("method", ACCURATE)
def test_quartic_roots_1_10_1e152_1e154(method: str) -> None:
    c = spread_quartics(1, np.random.default_rng(0))[0]
    assert abs(c[0]) > 1e306  # next to the overflow limit
    got = real_roots(c, method=method)
    want = [r.value for r in exact_roots(c)]
    assert len(want) == 4 and len(got) == 4, (got, want)
    for g, w in zip(got, want):
        assert abs(g - w) <= 1e-14 * abs(w), (g, w)
    # mpmath at 60 digits agrees that p changes sign around each root found
    mpmath.mp.dps = 60
    mc = [mpmath.mpf(float(v)) for v in c]
    for g in got:
        lo, hi = mpmath.mpf(g) * (1 - mpmath.mpf(10) ** -13), mpmath.mpf(g) * (1 + mpmath.mpf(10) ** -13)
        assert mpmath.polyval(mc[::-1], lo) * mpmath.polyval(mc[::-1], hi) < 0


@pytest.mark.parametrize("method", ACCURATE)
def test_quartics_spread_over_150_decades(method: str) -> None:
    c = spread_quartics(40, np.random.default_rng(1))
    ref = reference(c)
    roots, counts = real_roots_batch(c, -np.inf, np.inf, method)
    first, fcounts = first_root_batch(c, -np.inf, np.inf, method)
    required = 0
    for i in range(len(c)):
        s = score_one(c[i], -np.inf, np.inf, roots[i, : counts[i]], ref[i])
        assert s.missed == 0 and s.phantom == 0, (method, c[i].tolist(), roots[i, : counts[i]])
        required += s.ref_simple
        assert fcounts[i] == 1 and first[i] == roots[i, 0]
    assert required >= 3 * len(c)  # four real roots each; a few may be too close to count as simple-required


@pytest.mark.parametrize("dist", [1e3, 1e4])
@pytest.mark.parametrize("method", ACCURATE)
def test_far_origin_torus_rays_find_the_double_polynomials_roots(method: str, dist: float) -> None:
    """Coefficients at the far origin carry errors of ~u (dist^2)^2 against field values of ~0.1, so the double
    polynomial's roots are not the torus's (condition numbers 1e10-1e13; at 1e4 most hits vanish): exactly its
    real roots are wanted, as many as the exact isolation finds, each within its conditioning."""
    c, lo, hi = far_torus_rays(60, np.random.default_rng(2), dist)
    ref = reference(c)
    roots, counts = real_roots_batch(c, lo, hi, method)
    first, fcounts = first_root_batch(c, lo, hi, method)
    total = 0
    for i in range(len(c)):
        want = [r for r in ref[i] if lo[i] <= r.value <= hi[i]]
        got = roots[i, : counts[i]]
        assert len(got) == len(want), (method, dist, i, got, [r.value for r in want])
        for g, r in zip(got, want):
            assert r.mult == 1 and abs(g - r.value) <= 8 * U * r.kappa * abs(r.value), (i, g, r)
        total += len(want)
    assert total >= (40 if dist == 1e3 else 3)
    assert np.array_equal(fcounts, (counts > 0).astype(fcounts.dtype))
    assert np.array_equal(first[fcounts > 0], roots[fcounts > 0, 0])
