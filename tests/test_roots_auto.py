"""`auto` on the whole line: bracketing when Newton's inequalities say every root may be real (degree <= 6),
Bernstein subdivision otherwise (runtime_c/roots.c, auto_method). Checked against exact references: polynomials
built from dyadic roots, whose double coefficients are the exact ones (asserted), so the roots are known exactly --
double and quadruple (tangent) roots, a cluster 2^-10 apart, roots over 2^-24 .. 2^12; and that first-root mode
returns bitwise the first root of the full list."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from implgen.roots.solvers import first_root, first_root_batch, real_roots, real_roots_batch


def exact_poly(roots, pairs=()) -> np.ndarray:
    """Coefficients (lowest power first) of prod (x - r) prod ((x - re)^2 + im^2), computed on the rationals;
    asserts that every one is a double exactly."""
    c = [Fraction(1)]
    factors = [[-Fraction(r), Fraction(1)] for r in roots]
    factors += [[Fraction(re) ** 2 + Fraction(im) ** 2, -2 * Fraction(re), Fraction(1)] for re, im in pairs]
    for f in factors:
        out = [Fraction(0)] * (len(c) + len(f) - 1)
        for i, a in enumerate(c):
            for j, b in enumerate(f):
                out[i + j] += a * b
        c = out
    assert all(Fraction(float(v)) == v for v in c), "coefficients not exact in double"
    return np.array([float(v) for v in c])


U = 2.0**-53


def tolerance(c: np.ndarray, r: float, mult: int) -> float:
    """How far a computed root may be from the exact root r of multiplicity mult, from exact arithmetic on the
    double coefficients: a simple root within 8 u kappa |r| (kappa = sum |c_k| |r|^k / (|r| |p'(r)|), its
    condition number); a multiple one within twice the radius where p is below 64 u sum |c_k| |x|^k (where
    the reference counts a report as a root to working precision), p ~ p^(m)(r) (x - r)^m / m! there."""
    from math import factorial

    x = Fraction(r)
    scale = sum(abs(Fraction(float(v))) * abs(x) ** k for k, v in enumerate(c))
    d = [Fraction(float(v)) for v in c]
    for _ in range(mult):  # the mult-th derivative
        d = [k * d[k] for k in range(1, len(d))]
    dm = abs(sum(v * x**k for k, v in enumerate(d)))
    if mult == 1:
        return 8 * U * float(scale / dm) + 1e-300
    return 2.0 * float(64 * U * scale * factorial(mult) / dm) ** (1.0 / mult)


def check_roots(c: np.ndarray, roots: list, got: np.ndarray, what) -> None:
    """got against the exact roots (with multiplicity): each distinct root found, every report near one; a
    multiple root may be reported more than once inside its rounding neighbourhood, a simple one exactly once."""
    want = sorted(set(roots))
    tol = [tolerance(c, w, roots.count(w)) for w in want]
    hits = [[g for g in got if abs(g - w) <= t] for w, t in zip(want, tol)]
    assert all(hits), (what, got, want)
    assert sum(len(h) for h in hits) == got.size, (what, got, want)  # no report away from a root
    assert all(len(h) == 1 for h, w in zip(hits, want) if roots.count(w) == 1), (what, got, want)


def newton_holds(c: np.ndarray) -> bool:
    """Newton's inequalities a_k^2 >= a_(k-1) a_(k+1), a_k = c_k / C(n, k), on the exact rationals."""
    from math import comb

    n = len(c) - 1
    a = [Fraction(float(v)) / comb(n, k) for k, v in enumerate(c)]
    return all(a[k] * a[k] >= a[k - 1] * a[k + 1] for k in range(1, n))


# name, real roots (with multiplicity), complex pairs (re, im)
REAL_ROOTED = [
    ("double root", [0.75, 0.75, -2.0, 3.5], []),
    ("two double roots", [-1.0, -1.0, 2.0, 2.0], []),
    ("quadruple root, degree 6", [-1.25] * 4 + [0.5, 2.0], []),
    ("cluster 2^-10 apart", [1.0, 1.0 + 2.0**-10, 1.0 + 2.0**-9, 1.0 + 3 * 2.0**-10, -1.5], []),
    ("roots 2^-24 .. 2^12", [2.0**-24, -(2.0**-12), 1.0, 2.0**12], []),
    ("cubic with a double root", [0.5, 0.5, -3.0], []),
    ("degree 6, simple", [-3.0, -2.0, -0.5, 0.25, 1.5, 3.0], []),
    ("degree 6, triple root", [0.375] * 3 + [-2.0, 1.5, 2.5], []),
]
# whole-line polynomials auto leaves to Bernstein subdivision
NOT_SWITCHED = [
    ("complex pair", [1.0, -2.0], [(0.5, 1.0)], -np.inf, np.inf),
    ("double root beside a complex pair", [0.75, 0.75], [(-1.0, 2.0)], -np.inf, np.inf),
    ("degree 7, real-rooted", [-3.0, -2.0, -1.0, -0.5, 0.25, 1.5, 2.5], [], -np.inf, np.inf),
    ("degree 7, triple root", [0.375] * 3 + [-2.0, -1.0, 1.5, 2.5], [], -np.inf, np.inf),
    ("real-rooted, finite interval", [0.75, 0.75, -2.0, 3.5], [], -4.0, 4.0),
    ("real-rooted, half line", [0.75, 0.75, -2.0, 3.5], [], 0.0, np.inf),
]


@pytest.mark.parametrize(("name", "roots", "pairs"), REAL_ROOTED, ids=[c[0] for c in REAL_ROOTED])
def test_real_rooted_whole_line_goes_to_bracketing(name: str, roots, pairs) -> None:
    c = exact_poly(roots, pairs)
    assert newton_holds(c)  # the mathematical fact the switch relies on: real-rooted => log-concave a_k
    got = {m: real_roots(c, method=m) for m in ("auto", "bracket", "bernstein")}
    np.testing.assert_array_equal(got["auto"], got["bracket"])  # the dispatch
    for m, r in got.items():
        check_roots(c, roots, r, m)
        x = first_root(c, method=m)
        assert x is not None and x == r[0], (m, x, r)


@pytest.mark.parametrize(("name", "roots", "pairs", "lo", "hi"), NOT_SWITCHED, ids=[c[0] for c in NOT_SWITCHED])
def test_other_polynomials_stay_with_bernstein(name: str, roots, pairs, lo: float, hi: float) -> None:
    c = exact_poly(roots, pairs)
    auto, bern = real_roots(c, lo, hi, "auto"), real_roots(c, lo, hi, "bernstein")
    np.testing.assert_array_equal(auto, bern)
    check_roots(c, [r for r in roots if lo <= r <= hi], auto, name)
    if auto.size:
        assert first_root(c, lo, hi, "auto") == auto[0]


def test_dispatch_shows_in_the_last_bits() -> None:
    """Where bracketing and Bernstein disagree in the last bits, auto is bitwise the one the rule picks."""
    deg6 = exact_poly([-2.5, -1.25, -0.5, 0.75, 1.5, 3.0])
    deg7 = exact_poly([-3.0, -2.0, -1.0, -0.5, 0.25, 1.5, 2.5])
    for c, pick in ((deg6, "bracket"), (deg7, "bernstein")):
        other = "bernstein" if pick == "bracket" else "bracket"
        assert not np.array_equal(real_roots(c, method=pick), real_roots(c, method=other))
        np.testing.assert_array_equal(real_roots(c), real_roots(c, method=pick))


def test_random_real_rooted_cubics_to_sextics() -> None:
    """Products of random dyadic roots (some repeated), degree 3-6 on the whole line: exact count and values,
    auto equal to bracketing, first root bitwise the first of the list, in the batch entry points too."""
    rng = np.random.default_rng(12)
    rows, wants = [], []  # wants: the roots with multiplicity
    for _ in range(60):
        n = int(rng.integers(3, 7))
        roots = [float(v) / 8.0 for v in rng.integers(-24, 25, size=n)]
        if rng.random() < 0.5:  # a double or triple root
            roots[1:3] = [roots[0], roots[0]] if rng.random() < 0.5 else [roots[0], roots[1]]
        c = exact_poly(roots)
        rows.append(np.pad(c, (0, 6 - n)))
        wants.append(roots)
    c = np.array(rows)
    auto, counts = real_roots_batch(c, method="auto")
    brk, bcounts = real_roots_batch(c, method="bracket")
    bern, _ = real_roots_batch(c, method="bernstein")
    assert np.array_equal(counts, bcounts) and np.array_equal(auto[~np.isnan(auto)], brk[~np.isnan(brk)])
    differ = sum(not np.array_equal(bern[i], brk[i], equal_nan=True) for i in range(len(c)))
    assert differ >= 10, differ  # the two methods disagree in the last bits there: the check above has teeth
    for i, want in enumerate(wants):
        got = auto[i, : counts[i]]
        check_roots(c[i][: len(want) + 1], want, got, i)
        assert first_root(c[i]) == got[0]


@pytest.mark.parametrize("method", ["bracket", "auto", "bernstein"])
def test_first_root_mode_on_multiple_roots(method: str) -> None:
    """Bracketing's first-root mode stops at the first root of its last level; with multiple roots (two
    polished reports of one triple root can come out in either order) it must still be bitwise the smallest
    of the full list. Degrees 3-12, dyadic roots of multiplicity 1-4, whole line and finite intervals."""
    rng = np.random.default_rng(21)
    triple = exact_poly([-3.0] * 3 + [-2.25, -1.0, 0.375, 0.625])  # reported twice near -3, out of order
    assert real_roots(triple, method="bracket").size == 6
    rows, lo, hi = [np.pad(triple, (0, 5))], [-np.inf], [np.inf]
    for _ in range(300):
        n = int(rng.integers(3, 13))
        roots: list[float] = []
        while len(roots) < n:
            roots += [float(rng.integers(-24, 25)) / 8.0] * int(rng.integers(1, 5))
        rows.append(np.pad(exact_poly(roots[:n]), (0, 12 - n)))
        finite = rng.random() < 0.4
        lo.append(float(rng.uniform(-4, 0)) if finite else -np.inf)
        hi.append(float(rng.uniform(0, 4)) if finite else np.inf)
    c, lo, hi = np.array(rows), np.array(lo), np.array(hi)
    roots, counts = real_roots_batch(c, lo, hi, method)
    first, fcounts = first_root_batch(c, lo, hi, method)
    assert np.array_equal(fcounts, (counts > 0).astype(fcounts.dtype))
    has = counts > 0
    assert has.sum() > 200
    np.testing.assert_array_equal(first[has], roots[has, 0])
