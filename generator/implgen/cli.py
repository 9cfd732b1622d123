"""Command line: only orchestrates the modules that do the work.

    implgen SPEC.yaml [SPEC.yaml ...] --lang c|python|all [-o DIR]   generate intersectors
    implgen render SCENE.yaml -o OUT.png [...]                       render a scene
    implgen view [SPEC.yaml | SCENE.yaml] [--port --host --no-browser]  the interactive viewer
    implgen bench solvers|gen|render [...]                           measure
    implgen demo                                                     the main job of `make demo`

Bad input (UserError) becomes one line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any

from implgen.errors import UserError

# Subcommands live in their own modules; imported lazily so `implgen SPEC` stays quick.
_COMMANDS: dict[str, str] = {
    "render": "implgen.animation.command:main",
    "demo": "implgen.demo:main",
    "view": "implgen.view.command:main",
    "cache": "implgen.compile.command:main",
}
_BENCHES: dict[str, str] = {
    "solvers": "implgen.bench.solvers:main",
    "gen": "implgen.bench.gen:main",
    "render": "implgen.bench.render:main",
}


class ArgumentParser(argparse.ArgumentParser):
    """argparse for every implgen command: a bad option is a UserError (one line naming `label`, or the
    command, and exit status 2), never argparse's usage text and its own exit."""

    def __init__(self, *args: Any, label: str | None = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.label = label or self.prog

    def error(self, message: str) -> Any:
        raise UserError(self.label, message)


def _resolve(target: str) -> Callable[[Sequence[str]], int]:
    module, func = target.split(":")
    return getattr(importlib.import_module(module), func)


def run(argv: Sequence[str]) -> int:
    argv = list(argv)
    if argv and argv[0] in _COMMANDS:
        return _resolve(_COMMANDS[argv[0]])(argv[1:])
    if argv and argv[0] == "bench":
        if len(argv) < 2 or argv[1] not in _BENCHES:
            raise UserError("bench", f"choose one of: {', '.join(_BENCHES)}")
        return _resolve(_BENCHES[argv[1]])(argv[2:])
    return _resolve("implgen.codegen.command:main")(argv)


def quiet_blas() -> None:
    """NumPy's OpenBLAS starts a thread per core when it is imported, and each spins for ~0.1 s (again after
    every large product) -- on the cores the render's threads need (bench/blas_threads.py measures what that
    costs a render). implgen's linear algebra is 3x3, so one BLAS thread is plenty. Set before NumPy is
    first imported (a subcommand's import); a value the user exported is left alone."""
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def main(argv: Sequence[str] | None = None) -> int:
    quiet_blas()
    try:
        code = run(sys.argv[1:] if argv is None else argv)
    except UserError as err:
        print(f"implgen: error: {err}", file=sys.stderr)
        code = 2
    except KeyboardInterrupt:
        print("implgen: interrupted", file=sys.stderr)
        code = 130
    if argv is None:
        sys.exit(code)
    return code


if __name__ == "__main__":
    main()
