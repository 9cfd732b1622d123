"""Does an exact polynomial have a real root in a closed interval? Integer arithmetic, Descartes' rule of signs
and bisection (the Vincent-Collins-Akritas scheme), for the exact verdicts of bench/povray_compare.py.

The polynomial (rational coefficients, lowest power first) is scaled to integers and mapped onto the unit
interval: P(y) = d^n p(a + (b - a) y) for y in [0, 1]. The number of sign changes in the coefficients of
(1 + x)^n P(1 / (1 + x)) bounds the number of roots of P in (0, 1) from above and has the same parity
(Descartes' rule after the Moebius map y = 1 / (1 + x)): none means no root, an odd count means at least one.
Otherwise [0, 1] is halved (P(y / 2) and P((1 + y) / 2), scaled by 2^n: integers again) and the halves are
examined, with every split point checked exactly. A root of even multiplicity (a tangent ray) keeps an even
count on every piece around it; after MAX_DEPTH halvings the square-free part of p (SymPy's gcd over the
integers) replaces p, on which the bisection terminates. All operations are on Python integers: the cost
grows like n^2 per piece, where rational Sturm sequences grow their coefficients with every remainder.
"""

from __future__ import annotations

import math
from fractions import Fraction

MAX_DEPTH = 48


def _integer_poly(coeffs: list[Fraction]) -> list[int]:
    c = [Fraction(v) for v in coeffs]
    while len(c) > 1 and c[-1] == 0:
        c.pop()
    den = 1
    for v in c:
        den = den * v.denominator // math.gcd(den, v.denominator)
    ints = [int(v * den) for v in c]
    g = 0
    for v in ints:
        g = math.gcd(g, v)
    return [v // g for v in ints] if g > 1 else ints


def _on_interval(p: list[int], a: Fraction, b: Fraction) -> list[int]:
    """Integer coefficients of D^n p(a + (b - a) y) (D: a common denominator of a and b - a)."""
    h = b - a
    den = a.denominator * h.denominator // math.gcd(a.denominator, h.denominator)
    an, hn = int(a * den), int(h * den)
    n = len(p) - 1
    q = [p[n]]
    dk = 1
    for k in range(n - 1, -1, -1):  # q <- q (an + hn y) + p_k den^(n - k)
        dk *= den
        nq = [0] * (len(q) + 1)
        for i, v in enumerate(q):
            nq[i] += v * an
            nq[i + 1] += v * hn
        nq[0] += p[k] * dk
        q = nq
    return q


def _taylor1(p: list[int]) -> list[int]:
    """Coefficients of p(y + 1)."""
    t = list(p)
    n = len(t) - 1
    for i in range(n):
        for k in range(n - 1, i - 1, -1):
            t[k] += t[k + 1]
    return t


def _variations(p: list[int]) -> int:
    """Sign changes of (1 + x)^n p(1 / (1 + x)): bounds the roots of p in (0, 1)."""
    r = _taylor1(p[::-1])
    signs = [v > 0 for v in r if v != 0]
    return sum(1 for s, t in zip(signs, signs[1:]) if s != t)


def _halves(p: list[int]) -> tuple[list[int], list[int]]:
    """2^n p(y / 2) and 2^n p((1 + y) / 2)."""
    n = len(p) - 1
    left = [v << (n - k) for k, v in enumerate(p)]
    return left, _taylor1(left)


def _any_root_unit(p: list[int], depth: int, max_depth: int) -> bool | None:
    """A root of p in [0, 1]? None when max_depth halvings did not decide (a multiple root)."""
    if p[0] == 0 or sum(p) == 0:
        return True
    v = _variations(p)
    if v == 0:
        return False
    if v % 2 == 1:
        return True
    if depth >= max_depth:
        return None
    left, right = _halves(p)
    if right[0] == 0:  # the split point
        return True
    undecided = False
    for half in (left, right):
        r = _any_root_unit(half, depth + 1, max_depth)
        if r:
            return True
        undecided |= r is None
    return None if undecided else False


def _squarefree(p: list[int]) -> list[int]:
    import sympy

    x = sympy.Symbol("x")
    poly = sympy.Poly(list(reversed(p)), x, domain="ZZ").sqf_part()
    return [int(v) for v in reversed(poly.all_coeffs())]


def root_bound(p: list[int]) -> Fraction:
    """Cauchy's bound: every real root has |x| < 1 + max |p_k / p_n|."""
    return 1 + Fraction(max(abs(v) for v in p[:-1]), abs(p[-1])) if len(p) > 1 else Fraction(0)


def has_root(coeffs: list[Fraction], lo: Fraction, hi: Fraction | None = None) -> bool:
    """True when sum coeffs[k] t^k has a real root t with lo <= t <= hi (hi None: no upper end); a root of any
    multiplicity counts. The zero polynomial has every t as a root."""
    p = _integer_poly(coeffs)
    if len(p) == 1:
        return p[0] == 0
    lo = Fraction(lo)
    hi = root_bound(p) if hi is None else Fraction(hi)
    if hi < lo:
        return False
    if hi == lo:
        return sum(Fraction(v) * lo**k for k, v in enumerate(p)) == 0
    r = _any_root_unit(_on_interval(p, lo, hi), 0, MAX_DEPTH)
    if r is None:  # square-free, the halving separates any two distinct roots (closer than 2^-48: slowly)
        r = _any_root_unit(_on_interval(_squarefree(p), lo, hi), 0, 4 * MAX_DEPTH)
    return bool(r)
