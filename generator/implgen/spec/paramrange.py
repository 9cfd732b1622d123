"""A param's slider range, stated once for the viewer, its exported page and `implgen share`.

The spec's own `ranges` when it names one. Else the span about the default where the surface stays the same kind:
with the other params at their defaults, each coefficient of f (a polynomial in x, y, z) is a polynomial in the
param, and where one of them vanishes the surface changes kind (the torus's (a^2 - b^2)^2 at b = a: the hole
closes). The range runs between the nearest such values below and above the default; a side with none mirrors
the other. A param that f holds only in even powers (a radius: b^2) gives the same surface at -b as at b, so its
range starts at 0. Each end is then moved towards the default until the spec's checks pass there (every
coefficient a finite double, the bounds an ordered box: the torus's box [-b, b] is empty at b = 0), and rounded
inwards to three significant digits of the span. Without any such value, or for a polynomial too large to look
at (MAX_WORK), the default +- max(1, |default|), as before.

The polynomial is the exact one the parser made (spec/parse.py); roots are found in floating point (numpy), which
is all a slider's end needs. The result is kept per spec (a weak reference: it goes with the spec).
"""

from __future__ import annotations

import math
import threading
import weakref
from fractions import Fraction

import numpy as np

from implgen.errors import UserError
from implgen.spec.model import Spec

MAX_WORK = 100_000  # terms of f times params: beyond, the plain default range (the work is Python fractions)
SHRINK = 0.99  # an end the checks refuse moves this share of its distance towards the default, at most CHECKS times
CHECKS = 400

_kept: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_lock = threading.Lock()


def plain_range(value: float) -> tuple[float, float]:
    """The range without anything known of the surface: the value +- max(1, |value|)."""
    span = max(1.0, abs(value))
    return value - span, value + span


def param_ranges(spec: Spec) -> dict[str, tuple[float, float]]:
    """Every param's slider range (see the module's text), kept for the spec."""
    with _lock:
        hit = _kept.get(spec)
    if hit is None:
        hit = {name: spec.ranges.get(name) or _range(spec, name) for name in spec.params}
        with _lock:
            _kept[spec] = hit
    return dict(hit)


def slider_range(spec: Spec, name: str, value: float) -> tuple[float, float]:
    """The param's range, widened to hold `value`."""
    lo, hi = param_ranges(spec)[name]
    return min(lo, value), max(hi, value)


def _coefficients(spec: Spec, name: str) -> tuple[list[list[float]], bool] | None:
    """The coefficients of f's monomials in x, y, z as polynomials in `name` (the other params at their defaults),
    highest power first, and whether f holds `name` only in even powers; None when f is too large to look at."""
    from implgen.spec.parse import exact_polynomial

    names = list(spec.params)
    if not names or len(names) * spec_size(spec) > MAX_WORK:
        return None
    poly = exact_polynomial(spec.f, spec.param_symbols)
    at = names.index(name)
    others = [Fraction(spec.params[p]) if i != at else Fraction(1) for i, p in enumerate(names)]
    groups: dict[tuple, dict[int, Fraction]] = {}
    even = True
    for monom, coeff in poly.terms():
        powers = monom[3:]
        even = even and powers[at] % 2 == 0
        c = Fraction(int(coeff.numerator), int(coeff.denominator))
        for i, e in enumerate(powers):
            if i != at and e:
                c *= others[i] ** e
        group = groups.setdefault(monom[:3], {})
        group[powers[at]] = group.get(powers[at], Fraction(0)) + c
    out = []
    for group in groups.values():
        top = max((e for e, c in group.items() if c), default=0)
        if top > 0:
            out.append([float(group.get(e, 0)) for e in range(top, -1, -1)])
    return out, even


def spec_size(spec: Spec) -> int:
    """The number of terms of f (from the plain data: no SymPy)."""
    return len(spec.param_terms)


def _critical(coefficients: list[list[float]]) -> list[float]:
    """The real values of the param where a coefficient vanishes."""
    out = []
    for c in coefficients:
        scale = max(abs(x) for x in c)
        if not math.isfinite(scale) or scale == 0:
            continue
        for r in np.roots(np.array(c) / scale):
            if abs(r.imag) <= 1e-3 * max(1.0, abs(r.real)):  # a multiple root splits off the real line
                out.append(float(r.real))
    return out


def _range(spec: Spec, name: str) -> tuple[float, float]:
    v = float(spec.params[name])
    found = _coefficients(spec, name)
    if found is None:
        return plain_range(v)
    coefficients, even = found
    eps = 1e-9 * max(1.0, abs(v))
    roots = _critical(coefficients)
    lo = max((r for r in roots if r < v - eps), default=-math.inf)
    hi = min((r for r in roots if r > v + eps), default=math.inf)
    if even and v >= 0:  # -v draws what v draws: one sign is enough
        lo, hi = max(lo, 0.0), hi if v > 0 or math.isfinite(hi) else 1.0
    elif even:
        hi = min(hi, 0.0)
    if math.isinf(lo) and math.isinf(hi):
        return plain_range(v)
    lo = lo if math.isfinite(lo) else v - (hi - v)
    hi = hi if math.isfinite(hi) else v + (v - lo)
    lo, hi = _checked(spec, name, v, lo), _checked(spec, name, v, hi)
    if hi - lo < 1e-3 * max(1.0, abs(v)):
        return plain_range(v)
    return _rounded(lo, hi, v)


def _checked(spec: Spec, name: str, v: float, end: float) -> float:
    """`end`, moved towards v until the spec's checks pass there (v itself passes: it is the default)."""
    for _ in range(CHECKS):
        try:
            spec.check_values({name: end}, "ranges", name)
            return end
        except UserError:
            end = v + (end - v) * SHRINK
    return v


def _rounded(lo: float, hi: float, v: float) -> tuple[float, float]:
    """The ends rounded inwards to three significant digits of the span, still holding v."""
    step = 10.0 ** (math.floor(math.log10(hi - lo)) - 2)
    a, b = math.ceil(lo / step - 1e-4) * step, math.floor(hi / step + 1e-4) * step  # a root's float noise kept out
    a, b = float(f"{min(a, v):.12g}"), float(f"{max(b, v):.12g}")
    return (a, b) if a < b else (lo, hi)
