"""The contract every backend keeps, and what their printers share.

A backend (one folder under codegen/backends/, `<lang>/backend.py` defining BACKEND) is a `Backend`: its name
(the `--lang` value, which also names its template folder under the top-level templates/), the files it
writes, the SymPy printer that prints the derivation's blocks into them, and optionally a function of the
derivation giving the templates more variables. emit.py has no per-language branches. Every printer writes
only finite double constants: a constant beyond double range (from an equation's coefficients) raises
ConstantRangeError, which generation turns into a one-line error naming the spec. How to add a language:
README.md beside this file.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import sympy
from sympy.codegen.rewriting import create_expand_pow_optimization
from sympy.printing.codeprinter import CodePrinter

EXPAND_POW = create_expand_pow_optimization(3)  # b**2, b**3 -> b*b, b*b*b; higher powers are chained
EXACT_INT = 2**53  # integers below this are exact in a double


class ConstantRangeError(ValueError):
    """A constant of the generated code is not a finite double (the spec's coefficients are too large)."""


def finite_double(p: int, q: int = 1) -> float:
    """p / q as a double, when p and q are each finite doubles (both are printed as literals)."""
    if max(abs(p).bit_length(), q.bit_length()) > 1023:
        raise ConstantRangeError(
            f"a constant of the generated code ({'beyond' if abs(p) > q else 'below'} double range) comes "
            "from the equation's coefficients"
        )
    return p / q


class FiniteConstants:
    """What every backend's printer shares: rationals are checked to be finite doubles, and infinities are
    spelled the target's way (INF, set by the subclass)."""

    INF = ""

    def _print_Rational(self, expr: sympy.Rational) -> str:  # noqa: N802 -- SymPy's naming
        finite_double(int(expr.p), int(expr.q))
        return super()._print_Rational(expr)  # type: ignore[misc]

    def _print_Infinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return self.INF

    def _print_NegativeInfinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "-" + self.INF


@dataclass(frozen=True)
class Backend:
    """One target language."""

    name: str  # the --lang value, and the name of its folder under templates/ (the design card's templates/<lang>/)
    files: tuple[tuple[str, str], ...]  # (template in that folder, the file it writes: a pattern with {name})
    printer: type[CodePrinter]  # prints the derivation's blocks (each expression) in the target's syntax
    extra: Callable | None = None  # derivation -> more template variables (dict), or None

    def outputs(self) -> list[tuple[str, str]]:
        """(template path under templates/, file name pattern) of every file the backend writes."""
        return [(f"{self.name}/{template}", pattern) for template, pattern in self.files]
