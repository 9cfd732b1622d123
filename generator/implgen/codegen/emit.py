"""Derivation -> source files through a backend (codegen/backends/: a printer and its templates per language).

`generate(spec, langs)` returns {file name: text}; `outputs.write_text_files` puts them on disk atomically.
Output is deterministic (byte-identical on rerun), so the checked-in `generated/` folder can be compared in
tests.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import sympy
from sympy.codegen.rewriting import optimize

from implgen import __version__
from implgen.codegen.backends import LANGS, backend
from implgen.codegen.backends.contract import EXPAND_POW, ConstantRangeError
from implgen.codegen.derive import DIRECTION, ORIGIN, POINT, Block, Derivation, derive
from implgen.codegen.templating import environment
from implgen.errors import UserError
from implgen.spec.parse import Spec


@dataclass(frozen=True)
class PrintedBlock:
    temps: list[tuple[str, str]]
    outputs: list[str]
    inputs: list[str]


def _print_block(block: Block, doprint: Callable[[sympy.Expr], str]) -> PrintedBlock:
    def show(e: sympy.Expr) -> str:
        return doprint(optimize(e, [EXPAND_POW]))

    return PrintedBlock(
        temps=[(s.name, show(e)) for s, e in block.temps],
        outputs=[show(e) for e in block.outputs],
        inputs=[s.name for s in block.inputs],
    )


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
    return int(sum(sympy.count_ops(optimize(e, [EXPAND_POW])) for e in exprs))


def _render(env, template: str, context: dict) -> str:
    return env.get_template(template).render(**context)


def generate(spec: Spec, langs: Iterable[str] = LANGS, derivation: Derivation | None = None) -> dict[str, str]:
    """{file name: text} for the requested languages (backends.LANGS: "c" -> .h and .c, "python" -> .py, "glsl"
    -> .glsl)."""
    chosen = [backend(lang) for lang in langs]  # an unknown language: ValueError, before any work
    derivation = derivation or derive(spec)
    env = environment()
    files: dict[str, str] = {}
    try:
        for b in chosen:
            ctx = _context(derivation, b.printer().doprint)
            if b.extra is not None:
                ctx.update(b.extra(derivation))
            for template, pattern in b.outputs():
                files[pattern.format(name=spec.name)] = _render(env, template, ctx)
    except ConstantRangeError as err:
        raise UserError(spec.source, f"equation: {err}") from None
    return files
