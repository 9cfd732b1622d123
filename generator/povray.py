"""Spec -> POV-Ray `polynomial` object, so POV-Ray can render the same surface for comparison.

POV-Ray wants f expanded into terms `xyz(i,j,k):c` (the coefficient of x^i y^j z^k). We expand exactly in
SymPy's polynomial ring QQ[x, y, z] after substituting the param values, then print each coefficient as the
nearest double (17 significant digits). The `sturm` keyword selects POV-Ray's most careful root solver.
"""

from __future__ import annotations

from fractions import Fraction
from typing import Mapping

import sympy

from .spec import Spec, exact_polynomial, param_symbol

POVRAY_MAX_ORDER = 35  # POV-Ray 3.7's limit for `polynomial`


def polynomial_terms(spec: Spec, values: Mapping[str, float] | None = None) -> list[tuple[tuple[int, int, int], float]]:
    """[((i, j, k), coefficient), ...] of f with the params set (defaults, overridden by `values`)."""
    params = {**spec.params, **(values or {})}
    subs = {param_symbol(k): sympy.Rational(Fraction(float(v))) for k, v in params.items()}
    poly = exact_polynomial(spec.f.xreplace(subs), [])
    terms = [((int(m[0]), int(m[1]), int(m[2])), float(Fraction(int(c.numerator), int(c.denominator))))
             for m, c in poly.terms()]
    return sorted(terms, key=lambda term: (-sum(term[0]), [-e for e in term[0]]))


def polynomial_object(spec: Spec, values: Mapping[str, float] | None = None, sturm: bool = True,
                      indent: str = "  ") -> str:
    """The body of a POV-Ray `polynomial { ... }` block (without material or transform)."""
    if spec.degree > POVRAY_MAX_ORDER:
        raise ValueError(f"POV-Ray polynomials stop at order {POVRAY_MAX_ORDER}")
    lines = [f"polynomial {{ {spec.degree},"]
    terms = polynomial_terms(spec, values)
    for n, ((i, j, k), c) in enumerate(terms):
        sep = "," if n < len(terms) - 1 else ""
        lines.append(f"{indent}xyz({i},{j},{k}):{c:.17g}{sep}")
    if sturm:
        lines.append(f"{indent}sturm")
    lines.append("}")
    return "\n".join(lines)
