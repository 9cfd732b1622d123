"""Does a ray truly meet a shape inside its box? Decided in exact rational arithmetic.

The ray's origin and direction (doubles or floats, taken exactly as the rationals they are) and the shape's
params (doubles, likewise) give f(o + t d) over Q, scaled to integer coefficients; the box clip of the ray is
computed exactly; Descartes' rule with bisection (implgen.roots.descartes) says whether a real root lies in
the clipped interval, a tangent (even) root included. A shape placed by a 3x4 matrix (Placed) takes the world ray
into its own space in rationals; ExactJudge decides which of several placed shapes a ray meets first. This is the
judge of bench/povray_compare.py's disputed pixels, of the Embree checks (bench/embree_scenes.py) and of the GLSL
checks (implgen.measure.glslcheck, bench/glsl_compare.py).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from implgen.abi import grown_box
from implgen.roots.descartes import has_root
from implgen.spec.parse import exact_polynomial, param_symbol

Terms = list[tuple[tuple[int, int, int], Fraction]]  # ((i, j, k), c): c x^i y^j z^k


def exact_terms(spec, params: Mapping[str, float]) -> Terms:
    """f's monomials over Q with the params substituted (each double taken exactly)."""
    import sympy

    subs = {param_symbol(k): sympy.Rational(Fraction(float(v))) for k, v in params.items()}
    poly = exact_polynomial(spec.f.xreplace(subs), [])
    return [(tuple(int(e) for e in m), Fraction(int(c.numerator), int(c.denominator))) for m, c in poly.terms()]


def _mul(a: list[int], b: list[int]) -> list[int]:
    out = [0] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        if x:
            for j, y in enumerate(b):
                out[i + j] += x * y
    return out


def integer_ray_poly(terms: Terms, deg: int, oo: Sequence[Fraction], dd: Sequence[Fraction]) -> list[int]:
    """Integer coefficients (lowest first) of a positive multiple of f(o + t d): with o = A / D and d = B / D
    over one denominator D, D^deg f(o + t d) = sum c_m D^(deg - |m|) prod_k (A_k + B_k t)^(m_k), and the c_m
    are scaled to integers: all in Python integers, no gcd."""
    den = 1
    for v in (*oo, *dd, *(c for _, c in terms)):
        den = den * v.denominator // math.gcd(den, v.denominator)
    lin = [[int(oo[k] * den), int(dd[k] * den)] for k in range(3)]
    powers = []
    for k in range(3):
        pw = [[1]]
        for _ in range(deg):
            pw.append(_mul(pw[-1], lin[k]))
        powers.append(pw)
    acc = [0] * (deg + 1)
    dpow = [den**e for e in range(deg + 2)]
    for (i, j, k), c in terms:
        scale = int(c * den) * dpow[deg - (i + j + k)]
        p = _mul(_mul(powers[0][i], powers[1][j]), powers[2][k])
        for e, v in enumerate(p):
            acc[e] += scale * v
    return acc


def padded_box(box) -> list[tuple[Fraction | None, Fraction | None]] | None:
    """The spec box grown in doubles as runtime_c/shape.c grows it (implgen.abi.grown_box; the POV-Ray
    exporter's clipped_by too), as exact rationals; None bounds for infinite ones."""
    if box is None:
        return None
    lo, hi = grown_box(box)
    return [
        (Fraction(float(a)) if np.isfinite(a) else None, Fraction(float(b)) if np.isfinite(b) else None)
        for a, b in zip(lo, hi)
    ]


def box_span(
    box, oo: Sequence[Fraction], dd: Sequence[Fraction], t0: Fraction = Fraction(0), t1: Fraction | None = None
) -> tuple[Fraction, Fraction | None] | None:
    """[t0, t1] (t1 None: unbounded) narrowed to where o + t d is inside the box, exactly; None when empty."""
    for k, (lo, hi) in enumerate(box or []):
        for bound, is_lo in ((lo, True), (hi, False)):
            if bound is None:
                continue
            if dd[k] == 0:
                if (oo[k] < bound) if is_lo else (oo[k] > bound):
                    return None
                continue
            t = (bound - oo[k]) / dd[k]
            entering = (dd[k] > 0) == is_lo
            if entering:
                t0 = max(t0, t)
            else:
                t1 = t if t1 is None else min(t1, t)
    if t1 is not None and t1 < t0:
        return None
    return t0, t1


def _exact(v) -> Fraction:
    return v if isinstance(v, Fraction) else Fraction(float(v))


_IDENTITY = tuple(tuple(Fraction(int(i == j)) for j in range(3)) for i in range(3))
_ZERO = (Fraction(0),) * 3


@dataclass(frozen=True)
class Placed:
    """One shape placed in the world, exactly: f's monomials over Q, its degree, its box (padded_box's form, or
    None) and the world -> object map x_obj = inv (x_world - shift), all in rationals."""

    terms: Terms
    degree: int
    box: list[tuple[Fraction | None, Fraction | None]] | None
    inv: tuple[tuple[Fraction, ...], ...] = _IDENTITY
    shift: tuple[Fraction, ...] = _ZERO

    @classmethod
    def of(cls, spec, params: Mapping[str, float], matrix=None) -> Placed:
        """`spec` with `params` (doubles), its box padded as the C runtime pads it, placed by the object -> world
        3x4 `matrix` of doubles (None: where it stands), each double taken exactly."""
        terms, box = exact_terms(spec, params), padded_box(spec.box(params))
        if matrix is None:
            return cls(terms, spec.degree, box)
        import sympy

        m = [Fraction(float(v)) for v in np.asarray(matrix, dtype=float).reshape(12)]
        inv = sympy.Matrix(3, 3, [sympy.Rational(m[4 * i + j]) for i in range(3) for j in range(3)]).inv()
        inv_f = tuple(tuple(Fraction(int(inv[i, j].p), int(inv[i, j].q)) for j in range(3)) for i in range(3))
        shift = tuple(m[4 * i + 3] for i in range(3))
        return cls(terms, spec.degree, box, inv_f, shift)

    def object_ray(self, o, d) -> tuple[list[Fraction], list[Fraction]]:
        """The world ray o + t d (numbers taken exactly) in the object's space, exactly: the same t."""
        ow = [Fraction(float(v)) - self.shift[k] for k, v in enumerate(o)]
        dw = [Fraction(float(v)) for v in d]
        oo = [sum(self.inv[i][j] * ow[j] for j in range(3)) for i in range(3)]
        dd = [sum(self.inv[i][j] * dw[j] for j in range(3)) for i in range(3)]
        return oo, dd

    def ray_poly(self, o, d) -> list[int]:
        """Integer coefficients (lowest first) of a positive multiple of f along the world ray o + t d."""
        return integer_ray_poly(self.terms, self.degree, *self.object_ray(o, d))

    def meets(self, o, d, t0=0, t1=None) -> bool:
        """Does f(o + t d) = 0 have a real root, a tangent (even) one included, with t in [t0, t1] (t1 None or
        infinite: unbounded) and o + t d inside the box? Every number is taken exactly."""
        oo, dd = self.object_ray(o, d)
        hi = None if t1 is None or not math.isfinite(t1) else _exact(t1)
        span = box_span(self.box, oo, dd, _exact(t0), hi)
        return span is not None and has_root(integer_ray_poly(self.terms, self.degree, oo, dd), *span)


class ExactJudge:
    """Which of several placed shapes does a ray truly meet first? The judge of a ray's first hit where two
    tracers disagree (bench/povray_compare.py, bench/embree_scenes.py)."""

    def __init__(self, objects: Sequence[Placed]):
        self.objects = list(objects)

    def hits(self, o, d, t0=0, t1=None) -> bool:
        """Does any object meet o + t d for t in [t0, t1]?"""
        return any(obj.meets(o, d, t0, t1) for obj in self.objects)

    def right(self, claim: tuple[int, float], other: tuple[int, float], o, d, rel: float = 1e-9) -> bool:
        """Is the claim (object index, t; index -1: a miss) true where the other answer disagrees: its object
        meets the ray within rel of t, and the other answer's object does not meet it before?"""
        obj, t = claim
        oobj, _ = other
        if obj < 0:  # a miss: the other object is not met at all
            return oobj < 0 or not self.objects[oobj].meets(o, d)
        near = Fraction(t * (1 - rel))
        if not self.objects[obj].meets(o, d, near, Fraction(t * (1 + rel))):
            return False
        return oobj < 0 or oobj == obj or not self.objects[oobj].meets(o, d, 0, near)
