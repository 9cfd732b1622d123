"""Derivation -> source files, one backend per language: a SymPy code printer + Jinja2 templates.

`generate(spec, langs)` returns {file name: text}; `outputs.write_text_files` puts them on disk atomically. Output is
deterministic (byte-identical on rerun), so the checked-in `generated/` folder can be compared in tests.
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Callable, Iterable

import jinja2
import sympy
from sympy.codegen.rewriting import create_expand_pow_optimization, optimize
from sympy.printing.c import C99CodePrinter
from sympy.printing.pycode import PythonCodePrinter

from . import __version__, escape
from .derive import DIRECTION, ORIGIN, POINT, Block, Derivation, derive
from .errors import UserError
from .resources import templates_dir
from .spec import Spec

LANGS = ("c", "python")
_EXPAND_POW = create_expand_pow_optimization(3)  # b**2, b**3 -> b*b, b*b*b; higher powers are chained
_EXACT_INT = 2 ** 53


class ConstantRangeError(ValueError):
    """A constant of the generated code is not a finite double (the spec's coefficients are too large)."""


def _finite_double(p: int, q: int = 1) -> float:
    try:
        return float(Fraction(p, q))
    except OverflowError:
        raise ConstantRangeError(f"a constant of the generated code ({'beyond' if abs(p) > q else 'below'} "
                                 "double range) comes from the equation's coefficients") from None


class CPrinter(C99CodePrinter):
    """C99 printer: integers that a C `int`/`long` might not hold exactly are written as doubles."""

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802 -- SymPy's naming
        value = int(expr)
        if abs(value) < 2 ** 31:
            return str(value)
        return repr(_finite_double(value)) if abs(value) < _EXACT_INT else f"{_finite_double(value):.17g}"

    def _print_Rational(self, expr: sympy.Rational) -> str:  # noqa: N802
        _finite_double(int(expr.p), int(expr.q))
        return super()._print_Rational(expr)

    def _print_Infinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "INFINITY"

    def _print_NegativeInfinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "-INFINITY"


class PyPrinter(PythonCodePrinter):
    """Python printer for NumPy-broadcasting arithmetic (plain operators, floats for huge integers)."""

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802
        value = int(expr)
        return str(value) if abs(value) < _EXACT_INT else f"{_finite_double(value):.17g}"

    def _print_Rational(self, expr: sympy.Rational) -> str:  # noqa: N802
        _finite_double(int(expr.p), int(expr.q))
        return super()._print_Rational(expr)

    def _print_Infinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "math.inf"

    def _print_NegativeInfinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "-math.inf"


@dataclass(frozen=True)
class PrintedBlock:
    temps: list[tuple[str, str]]
    outputs: list[str]
    inputs: list[str]


def _print_block(block: Block, doprint: Callable[[sympy.Expr], str]) -> PrintedBlock:
    def show(e: sympy.Expr) -> str:
        return doprint(optimize(e, [_EXPAND_POW]))

    return PrintedBlock(
        temps=[(s.name, show(e)) for s, e in block.temps],
        outputs=[show(e) for e in block.outputs],
        inputs=[s.name for s in block.inputs],
    )


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
    )
    # Text in comments, docstrings and string literals goes through the filter for the place it lands in.
    env.filters.update(c_comment=escape.c_comment, c_string=escape.c_string, py_doc=escape.py_docstring,
                       py_str=escape.py_string)
    return env


def _context(derivation: Derivation, doprint: Callable[[sympy.Expr], str]) -> dict:
    spec = derivation.spec
    blocks = {
        "coeffs": _print_block(derivation.coeffs, doprint),
        "value": _print_block(derivation.value, doprint),
        "gradient": _print_block(derivation.gradient, doprint),
    }
    if derivation.bounds is not None:
        blocks["bounds"] = _print_block(derivation.bounds, doprint)
    return {
        "version": __version__,
        "spec": spec,
        "source_name": spec.source if spec.source.startswith("<") else Path(spec.source).name,
        "name": spec.name,
        "NAME": spec.name.upper(),
        "degree": spec.degree,
        "params": [(p, f"k_{p}", repr(float(v))) for p, v in spec.params.items()],
        "folded": [(p, repr(v)) for p, v in spec.folded.items()],
        "equation": spec.equation,
        "ops": {k: derivation_ops(derivation, k) for k in ("coeffs", "value", "gradient")},
        "blocks": blocks,
        "origin": [s.name for s in ORIGIN],
        "direction": [s.name for s in DIRECTION],
        "point": [s.name for s in POINT],
    }


def derivation_ops(derivation: Derivation, which: str) -> int:
    """Arithmetic operations of one generated function, powers counted as the multiplications printed."""
    block: Block = getattr(derivation, which)
    exprs = [e for _, e in block.temps] + list(block.outputs)
    return int(sum(sympy.count_ops(optimize(e, [_EXPAND_POW])) for e in exprs))


def _render(env: jinja2.Environment, template: str, context: dict) -> str:
    return env.get_template(template).render(**context)


def generate(spec: Spec, langs: Iterable[str] = LANGS, derivation: Derivation | None = None) -> dict[str, str]:
    """{file name: text} for the requested languages ("c" -> .h and .c, "python" -> .py)."""
    derivation = derivation or derive(spec)
    env = _environment()
    files: dict[str, str] = {}
    try:
        for lang in langs:
            if lang == "c":
                ctx = _context(derivation, CPrinter().doprint)
                files[f"{spec.name}.h"] = _render(env, "c/shape.h.j2", ctx)
                files[f"{spec.name}.c"] = _render(env, "c/shape.c.j2", ctx)
            elif lang == "python":
                ctx = _context(derivation, PyPrinter().doprint)
                files[f"{spec.name}.py"] = _render(env, "python/shape.py.j2", ctx)
            else:
                raise ValueError(f"unknown language {lang!r}")
    except ConstantRangeError as err:
        raise UserError(spec.source, f"equation: {err}") from None
    return files
