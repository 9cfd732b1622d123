"""The Python backend: one NumPy-broadcasting module (templates/python/) on implgen.raycast."""

from __future__ import annotations

import sympy
from sympy.printing.pycode import PythonCodePrinter

from implgen.codegen.backends.contract import EXACT_INT, Backend, FiniteConstants, finite_double


class PyPrinter(FiniteConstants, PythonCodePrinter):
    """Python printer for NumPy-broadcasting arithmetic (plain operators, floats for huge integers)."""

    INF = "math.inf"

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802
        value = int(expr)
        return str(value) if abs(value) < EXACT_INT else f"{finite_double(value):.17g}"


BACKEND = Backend("python", (("shape.py.j2", "{name}.py"),), PyPrinter)
