"""The integer Descartes/bisection root test (implgen.roots.descartes) against SymPy's rational Sturm count and
against polynomials with known roots: simple, tangent (double, quadruple), at the interval ends, clustered,
none, and degree 20."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from implgen.roots.descartes import has_root

T = sp.Symbol("t")


def _from_roots(roots, pairs=()) -> list[Fraction]:
    p = sp.Poly(1, T, domain="QQ")
    for r in roots:
        p *= sp.Poly(T - sp.Rational(Fraction(r)), T, domain="QQ")
    for re, im in pairs:
        p *= sp.Poly((T - sp.Rational(Fraction(re))) ** 2 + sp.Rational(Fraction(im)) ** 2, T, domain="QQ")
    return [Fraction(int(c.p), int(c.q)) for c in reversed(p.all_coeffs())]


def _sturm(c: list[Fraction], lo, hi) -> bool:
    p = sp.Poly([sp.Rational(v.numerator, v.denominator) for v in reversed(c)], T, domain="QQ")
    return bool(p.count_roots(sp.Rational(Fraction(lo)), None if hi is None else sp.Rational(Fraction(hi))) > 0)


@pytest.mark.parametrize(
    ("roots", "pairs", "lo", "hi", "want"),
    [
        ([1, 2, 3], (), 0, 10, True),
        ([1, 2, 3], (), 3.5, 10, False),
        ([1, 2, 3], (), 3, 10, True),  # a root at lo
        ([1, 2, 3], (), -5, 1, True),  # a root at hi
        ([0.5, 0.5], (), 0, 1, True),  # tangent: double root, no sign change
        ([0.5, 0.5, 0.5, 0.5], [(0.25, 1)], 0, None, True),  # quadruple
        ([0.5, 0.5], [(1, 2**-40)], 0.75, 2, False),  # a tiny minimum, no root
        ([1, 1 + 2**-50], (), 0.5, 2, True),  # two roots 2^-50 apart
        ([-3, -1], [(2, 1)], 0, None, False),  # roots behind the ray
        ([], [(0, 1), (3, 0.5)], -100, 100, False),
    ],
)
def test_known_cases(roots, pairs, lo, hi, want) -> None:
    c = _from_roots(roots, pairs)
    assert has_root(c, Fraction(lo), None if hi is None else Fraction(hi)) is want
    assert _sturm(c, lo, hi) is want


def test_agrees_with_sturm_on_random_polynomials() -> None:
    rng = np.random.default_rng(7)
    for _ in range(150):
        n = int(rng.integers(2, 9))
        c = [Fraction(float(v)) for v in rng.normal(size=n + 1)]
        if rng.random() < 0.3:  # a double root on purpose
            r = Fraction(int(rng.integers(-8, 8)), 4)
            c = _from_roots([r, r], [(float(rng.uniform(-2, 2)), 0.5)] * (n // 2))
        lo = Fraction(float(rng.uniform(-3, 1)))
        hi = None if rng.random() < 0.3 else lo + Fraction(float(rng.uniform(0, 4)))
        assert has_root(c, lo, hi) == _sturm(c, lo, hi), (c, lo, hi)


def test_degree_20_ray_polynomial() -> None:
    """Chebyshev's T20: 20 simple roots in (-1, 1), none beyond."""
    from numpy.polynomial import chebyshev

    t20 = [Fraction(int(v)) for v in chebyshev.cheb2poly([0] * 20 + [1])]
    # the roots are cos((2k + 1) pi / 40): the smallest positive ones 0.0785 and 0.2334
    assert has_root(t20, Fraction(-1), Fraction(1))
    assert has_root(t20, Fraction(7, 100), Fraction(8, 100))
    assert not has_root(t20, Fraction(0), Fraction(7, 100))
    assert not has_root(t20, Fraction(8, 100), Fraction(23, 100))
    assert not has_root(t20, Fraction(1), None)  # T20(1) = 1 and it grows beyond
    assert has_root(t20, Fraction(-2), None)
