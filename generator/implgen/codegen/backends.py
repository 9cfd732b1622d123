"""One backend per target language: a SymPy code printer and the templates it fills, with their file names.

Adding a language means adding a printer here, its templates under templates/<lang>/ and one BACKENDS entry
(with, when its templates need more than the printed blocks, a function of the derivation giving the rest);
emit.py has no per-language branches. Every printer writes only finite double constants: a constant beyond
double range (from an equation's coefficients) raises ConstantRangeError, which generation turns into a
one-line error naming the spec.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import sympy
from sympy.codegen.rewriting import create_expand_pow_optimization
from sympy.printing.c import C99CodePrinter
from sympy.printing.codeprinter import CodePrinter
from sympy.printing.pycode import PythonCodePrinter

from implgen.codegen.glsl import GLSLPrinter, glsl_extra

EXPAND_POW = create_expand_pow_optimization(3)  # b**2, b**3 -> b*b, b*b*b; higher powers are chained
_EXACT_INT = 2**53


class ConstantRangeError(ValueError):
    """A constant of the generated code is not a finite double (the spec's coefficients are too large)."""


def _finite_double(p: int, q: int = 1) -> float:
    """p / q as a double, when p and q are each finite doubles (both are printed as literals)."""
    if max(abs(p).bit_length(), q.bit_length()) > 1023:
        raise ConstantRangeError(
            f"a constant of the generated code ({'beyond' if abs(p) > q else 'below'} double range) comes "
            "from the equation's coefficients"
        )
    return p / q


class _FiniteConstants:
    """What every backend's printer shares: rationals are checked to be finite doubles, and infinities are
    spelled the target's way (INF, set by the subclass)."""

    INF = ""

    def _print_Rational(self, expr: sympy.Rational) -> str:  # noqa: N802 -- SymPy's naming
        _finite_double(int(expr.p), int(expr.q))
        return super()._print_Rational(expr)  # type: ignore[misc]

    def _print_Infinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return self.INF

    def _print_NegativeInfinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "-" + self.INF


class CPrinter(_FiniteConstants, C99CodePrinter):
    """C99 printer: integers that a C `int`/`long` might not hold exactly are written as doubles."""

    INF = "INFINITY"

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802
        value = int(expr)
        if abs(value) < 2**31:
            return str(value)
        return repr(_finite_double(value)) if abs(value) < _EXACT_INT else f"{_finite_double(value):.17g}"


class PyPrinter(_FiniteConstants, PythonCodePrinter):
    """Python printer for NumPy-broadcasting arithmetic (plain operators, floats for huge integers)."""

    INF = "math.inf"

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802
        value = int(expr)
        return str(value) if abs(value) < _EXACT_INT else f"{_finite_double(value):.17g}"


@dataclass(frozen=True)
class Backend:
    printer: type[CodePrinter]
    files: tuple[tuple[str, str], ...]  # (template under templates/, file name pattern with {name})
    extra: Callable | None = None  # derivation -> more template variables (dict), or None


BACKENDS: dict[str, Backend] = {
    "c": Backend(CPrinter, (("c/shape.h.j2", "{name}.h"), ("c/shape.c.j2", "{name}.c"))),
    "python": Backend(PyPrinter, (("python/shape.py.j2", "{name}.py"),)),
    "glsl": Backend(GLSLPrinter, (("glsl/shape.glsl.j2", "{name}.glsl"),), glsl_extra),
}
