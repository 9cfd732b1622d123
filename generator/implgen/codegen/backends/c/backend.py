"""The C backend: C99 source and header (templates/c/), linked against runtime_c/."""

from __future__ import annotations

import sympy
from sympy.printing.c import C99CodePrinter

from implgen.codegen.backends.c.errbound import c_extra
from implgen.codegen.backends.contract import EXACT_INT, Backend, FiniteConstants, finite_double


class CPrinter(FiniteConstants, C99CodePrinter):
    """C99 printer: integers that a C `int`/`long` might not hold exactly are written as doubles."""

    INF = "INFINITY"

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802
        value = int(expr)
        if abs(value) < 2**31:
            return str(value)
        return repr(finite_double(value)) if abs(value) < EXACT_INT else f"{finite_double(value):.17g}"


BACKEND = Backend("c", (("shape.h.j2", "{name}.h"), ("shape.c.j2", "{name}.c")), CPrinter, c_extra)
