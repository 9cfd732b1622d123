"""A second tree for f, in the Chebyshev basis of its own box, for the GLSL when the user's tree cancels in float.

The GLSL evaluates f in float (24 bits) as a tree (backends/glsl/printer.py). A polynomial typed in expanded form --
the Chmutov surface's T_n(x) written as its monomials -- carries terms of size about (1 + sqrt 2)^n / 2 that
cancel to O(1) on the surface, and float keeps nothing of f there. The same polynomial in the tensor
Chebyshev basis of its box, f = sum c_ijk T_i(u) T_j(v) T_k(w) with u = (x - centre) / half-width, has terms
no larger than f's size on the box, and T_n(u) itself is computed stably by doubling (T_2m = 2 T_m^2 - 1,
T_2m+1 = 2 T_m T_m+1 - u).

Which tree the shader gets is decided by a float error bound: for each tree, the running error bound of its
float evaluation (first order, Higham's section 3.3) at points spread over the box; the Chebyshev tree is
taken when it lowers the median bound sixteenfold (four bits), so a tree the user wrote well (factored,
nested) is kept. Only a spec without params and with a finite box of rational ends can be rewritten: the
coefficients are exact rationals, computed once, here, from f expanded by integer ring arithmetic on its tree
(never SymPy's expansion of the whole expression: 37.7 s on a degree-24 product of six linear factors, 0.3 s so).

The command line computes the form to its end, so what it writes never depends on the machine. The viewer
computes it under `budget` (a deadline and a stop, checked between small steps); past them OverBudget, and
the GLSL keeps f's tree as written (backends/glsl/printer.py).
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from fractions import Fraction
from math import comb

import numpy as np
import sympy
from sympy.polys.domains import ZZ
from sympy.polys.rings import ring

from implgen.spec.parse import X, Y, Z

GAIN = 16.0  # the Chebyshev tree must lower the median error bound by this factor to be chosen
SAMPLES = 2048
MAX_TERMS = 20000  # more Chebyshev coefficients than this: keep the user's tree (the shader would be huge)


@dataclass(frozen=True)
class ChebForm:
    """f = sum over `coeffs` of c * T_i(u) T_j(v) T_k(w), u = (x - centre[0]) / half[0] and so on."""

    centre: tuple[Fraction, Fraction, Fraction]
    half: tuple[Fraction, Fraction, Fraction]
    coeffs: dict[tuple[int, int, int], Fraction]


def _power_to_chebyshev(k: int) -> dict[int, Fraction]:
    """u^k = sum_j a_j T_j(u): a_j = 2^(1-k) C(k, (k-j)/2) for j > 0 of k's parity, a_0 = 2^-k C(k, k/2)."""
    out = {}
    for j in range(k % 2, k + 1, 2):
        a = Fraction(comb(k, (k - j) // 2), 2 ** (k - 1)) if k else Fraction(1)
        out[j] = a / 2 if (j == 0 and k) else a
    return out


def _row(a: int, centre: Fraction, half: Fraction) -> dict[int, Fraction]:
    """x^a with x = centre + half u, in the Chebyshev basis of u: sum_j C(a, j) centre^(a-j) half^j u^j."""
    out: dict[int, Fraction] = {}
    for j in range(a + 1):
        scale = comb(a, j) * centre ** (a - j) * half**j
        if scale:
            for k, c in _power_to_chebyshev(j).items():
                out[k] = out.get(k, Fraction(0)) + scale * c
    return out


def _exact_box(bounds) -> tuple[list[Fraction], list[Fraction]] | None:
    """The box's ends as exact rationals; None unless every axis has two finite rational ends."""
    if bounds is None or any(axis not in bounds for axis in "xyz"):
        return None
    lo, hi = [], []
    for axis in "xyz":
        a, b = bounds[axis]
        if not (a.is_Rational and b.is_Rational) or not a < b:
            return None
        lo.append(Fraction(int(a.p), int(a.q)))
        hi.append(Fraction(int(b.p), int(b.q)))
    return lo, hi


class OverBudget(Exception):
    """The Chebyshev step ran past its budget's deadline, or was stopped (see `budget`)."""


@dataclass
class Budget:
    """A time budget for the Chebyshev step of the GLSL derivations made under it (`budget`)."""

    seconds: float | None  # None: no time limit (a stop only)
    deadline: float  # time.monotonic()
    stop: threading.Event | None = None
    cut: bool = False  # a Chebyshev step ran out of the budget (or was stopped) and the tree as written was kept

    def check(self) -> None:
        if time.monotonic() > self.deadline or (self.stop is not None and self.stop.is_set()):
            self.cut = True
            raise OverBudget


_BUDGET: ContextVar[Budget | None] = ContextVar("implgen_chebform_budget", default=None)


@contextmanager
def budget(seconds: float | None, stop: threading.Event | None = None) -> Iterator[Budget]:
    """Within the block, on this thread, the Chebyshev step of any GLSL derivation stops with OverBudget once
    `seconds` (None: no limit) have passed since the block began, or once `stop` is set: both are checked between
    steps (each node of f's tree, each coefficient, each term), none of which takes long, so the step stops soon
    after. Outside a budget (the command line) the step always runs to its end, so what it writes never depends
    on the machine."""
    held = Budget(seconds, math.inf if seconds is None else time.monotonic() + seconds, stop)
    token = _BUDGET.set(held)
    try:
        yield held
    finally:
        _BUDGET.reset(token)


def _check() -> None:
    held = _BUDGET.get()
    if held is not None:
        held.check()


def _monomials(f: sympy.Expr) -> dict[tuple[int, int, int], Fraction]:
    """f expanded in x, y, z: {exponents: coefficient}, in the order of sympy.Poly(f, x, y, z).terms() (lex,
    highest first) and equal to it. Computed by integer ring arithmetic on f's own tree, each shared subtree
    once, every node an integer polynomial over one denominator: SymPy's expansion of the whole expression
    builds hundreds of thousands of intermediate terms at degree 24 (37.7 s for six linear factors to the 4th
    power), the ring's products stay at their results' size (0.3 s)."""
    R, *gens = ring([X, Y, Z], ZZ)
    memo: dict[sympy.Expr, tuple] = {s: (g, 1) for s, g in zip((X, Y, Z), gens, strict=True)}

    def walk(e: sympy.Expr) -> tuple:
        if e in memo:
            return memo[e]
        _check()
        if e.is_Rational:
            out = (R(int(e.p)), int(e.q))
        elif e.is_Add:
            parts = [walk(a) for a in e.args]
            d = math.lcm(*(q for _, q in parts))
            out = (sum((p * (d // q) for p, q in parts), R.zero), d)
        elif e.is_Mul:
            out = walk(e.args[0])
            for a in e.args[1:]:
                p, q = walk(a)
                out = (out[0] * p, out[1] * q)
        elif e.is_Pow and e.exp.is_Integer and e.exp >= 0:
            p, q = walk(e.base)
            out = (p ** int(e.exp), q ** int(e.exp))
        else:  # the parser builds only sums, products and integer powers of symbols and numbers
            raise ValueError(f"not a polynomial node: {e}")
        memo[e] = out
        return out

    poly, d = walk(f)
    return {m: Fraction(int(c), d) for m, c in poly.terms()}


def chebyshev_form(f: sympy.Expr, bounds) -> ChebForm | None:
    """f in the Chebyshev basis of its box, exactly; None when f has params or the box is not finite."""
    if f.free_symbols - {X, Y, Z}:
        return None
    box = _exact_box(bounds)
    if box is None:
        return None
    centre = tuple((a + b) / 2 for a, b in zip(*box, strict=True))
    half = tuple((b - a) / 2 for a, b in zip(*box, strict=True))
    coeffs = _monomials(f)
    for axis in range(3):  # one variable at a time: x^a = (centre + half u)^a, then u^j in the T basis
        rows = {a: _row(a, centre[axis], half[axis]) for a in {m[axis] for m in coeffs}}
        out: dict[tuple[int, int, int], Fraction] = {}
        for m, c in coeffs.items():
            _check()
            for j, a in rows[m[axis]].items():
                key = m[:axis] + (j,) + m[axis + 1 :]
                out[key] = out.get(key, Fraction(0)) + c * a
        coeffs = {m: c for m, c in out.items() if c != 0}
        if len(coeffs) > MAX_TERMS:
            return None
    return ChebForm(centre, half, coeffs)


# Running error bounds (Higham, "Accuracy and Stability of Numerical Algorithms", 3.3), in units of the unit
# roundoff: each operation's result carries (value, mu), |computed - exact| <~ mu * u to first order.
def _add(a, b):
    v = a[0] + b[0]
    return v, a[1] + b[1] + np.abs(v)


def _mul(a, b):
    v = a[0] * b[0]
    return v, np.abs(a[0]) * b[1] + np.abs(b[0]) * a[1] + np.abs(v)


def _constant(c: float, like: np.ndarray):
    return np.full_like(like, c), np.full_like(like, abs(c))


def _tree_bound(e: sympy.Expr, point: dict, memo: dict):
    """(value, mu) of a float evaluation of e's tree as written (the shader's order: left to right)."""
    if e in memo:
        return memo[e]
    _check()
    if e in point:
        out = (point[e], np.zeros_like(point[e]))
    elif e.is_Number:
        out = _constant(float(e), point[X])
    elif e.is_Add or e.is_Mul:
        op = _add if e.is_Add else _mul
        parts = [_tree_bound(a, point, memo) for a in e.args]
        out = parts[0]
        for part in parts[1:]:
            out = op(out, part)
    else:  # an integer power: the parser builds nothing else
        base, out = _tree_bound(e.base, point, memo), None
        for _ in range(int(e.exp)):
            out = base if out is None else _mul(out, base)
    memo[e] = out
    return out


def _chebyshev_bound(form: ChebForm, coords: list[np.ndarray]):
    """(value, mu) of the Chebyshev tree, in the order backends/glsl/printer.py emits it."""
    tables = []
    for axis, x in enumerate(coords):
        u = _mul(
            _add((x, np.zeros_like(x)), _constant(-float(form.centre[axis]), x)),
            _constant(1 / float(form.half[axis]), x),
        )
        table = {0: _constant(1.0, x), 1: u}
        two, one = _constant(2.0, x), _constant(-1.0, x)
        for n in range(2, max(m[axis] for m in form.coeffs) + 1):  # T_m and T_m+1 come before T_2m, T_2m+1
            m = n // 2
            if n % 2 == 0:
                table[n] = _add(_mul(_mul(table[m], table[m]), two), one)
            else:
                table[n] = _add(_mul(_mul(table[m], table[m + 1]), two), (-u[0], u[1]))
        tables.append(table)
    total = None
    for (i, j, k), c in form.coeffs.items():
        _check()
        term = _mul(_mul(_mul(tables[0][i], tables[1][j]), tables[2][k]), _constant(float(c), coords[0]))
        total = term if total is None else _add(total, term)
    return total


def better_form(f: sympy.Expr, bounds, seed: int = 0) -> ChebForm | None:
    """The Chebyshev form when its float error bound is GAIN times smaller than the user's tree's over the box
    (median over SAMPLES points); None to keep the user's tree."""
    form = chebyshev_form(f, bounds)
    if form is None:
        return None
    rng = np.random.default_rng(seed)
    coords = [
        float(c) + float(h) * rng.uniform(-1.0, 1.0, SAMPLES) for c, h in zip(form.centre, form.half, strict=True)
    ]
    with np.errstate(over="ignore", invalid="ignore"):
        user = _tree_bound(f, {X: coords[0], Y: coords[1], Z: coords[2]}, {})[1]
        cheb = _chebyshev_bound(form, coords)[1]
        ratio = np.median(user / cheb)
    return form if np.isfinite(ratio) and ratio > GAIN else None
