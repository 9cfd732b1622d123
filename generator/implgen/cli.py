"""The `implgen` command, the roof of the package: it only dispatches to the commands, each in a module of its
own, imported when it runs (so `implgen SPEC` stays quick). Nothing imports this module but the console script.

One table, COMMANDS (with GENERATE, the command that needs no name), says which commands there are; the
dispatcher reads it and `implgen --help` is written from it, so a command cannot be left out of the help.

    implgen --help, -h     the list of commands on stdout, exit status 0
    implgen                the same list on stderr, exit status 2 (nothing to do: a usage error)
    implgen --version      `implgen <version>`, exit status 0
    implgen COMMAND --help a command's options and examples (`implgen SPEC.yaml --help` for generating)

Bad input (UserError) becomes one line on stderr and exit status 2, never a traceback.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from implgen import __version__
from implgen.args import examples_text
from implgen.codegen.backends import LANGS
from implgen.errors import UserError

HELP = ("--help", "-h")


@dataclass(frozen=True)
class Command:
    """One line of the help: `synopsis` (what follows `implgen`) and a one-line `summary`. What runs is
    `target` ("module:function" or a function, called with the arguments after the command's words), or, for
    a group such as `bench`, one of its `sub` commands, chosen by the next word."""

    synopsis: str
    summary: str
    target: str | Callable[[Sequence[str]], int] = ""
    sub: dict[str, Command] = field(default_factory=dict)
    examples: tuple[tuple[str, str], ...] = ()  # a group's own --help; a command's are in its parser


def _version(argv: Sequence[str]) -> int:
    if argv:
        raise UserError("--version", f"takes no arguments (got {argv[0]!r})")
    print(f"implgen {__version__}")
    return 0


GENERATE = Command(
    f"SPEC.yaml ... [--lang {'|'.join(LANGS)}|all] [-o DIR]",
    "generate C, Python and GLSL ray intersectors",
    "implgen.codegen.command:main",
)
COMMANDS: dict[str, Command] = {
    "render": Command(
        "render SCENE.yaml -o OUT [options]",
        "render a still or an animation (also on Dask)",
        "implgen.animation.command:main",
    ),
    "view": Command(
        "view [SPEC.yaml | SCENE.yaml] [options]", "the interactive viewer, in the browser", "implgen.view.command:main"
    ),
    "share": Command(
        "share SPEC.yaml -o PAGE.html [options]",
        "one HTML file that draws the shape in any WebGL2 browser, from disk",
        "implgen.share.command:main",
    ),
    "bench": Command(
        "bench COMMAND [options]",
        "measurements: each prints a table and writes it, with the machine, to a results file (bench/README.md).",
        sub={
            "solvers": Command(
                "bench solvers [options]", "measure root solvers: speed against error", "implgen.measure.solvers:main"
            ),
            "gen": Command("bench gen [options]", "measure code generation against degree", "implgen.measure.gen:main"),
            "render": Command(
                "bench render [SCENE.yaml ...] [options]",
                "measure render speed and thread scaling",
                "implgen.measure.render:main",
            ),
        },
        examples=(
            ("the root solvers, small sizes, into out/bench/", "implgen bench solvers --quick -o out/bench"),
            ("a bench's options and examples", "implgen bench render --help"),
        ),
    ),
    "mesh": Command(
        "mesh SPEC.yaml -o OUT.stl|.obj|.ply|.glb [options]",
        "a watertight triangle mesh of the solid f < 0, crossings solved exactly",
        "implgen.mesh.command:main",
    ),
    "demo": Command(
        "demo [--shapes DIR] [-o DIR]",
        "what `make demo` runs: the example shapes, end to end",
        "implgen.demo:main",
    ),
    "cache": Command(
        "cache info|clear", "the build cache: what it holds and its bound; empty it", "implgen.compile.command:main"
    ),
    "--version": Command("--version", "print the version", _version),
}
ROOT = Command(
    "SPEC.yaml ... [options] | implgen COMMAND [options]",
    "Implicit surfaces f(x, y, z) = 0 turned into C and Python ray intersectors, and a C ray tracer.",
    sub=COMMANDS,
    examples=(
        ("the torus as C and Python, into out/", "implgen examples/shapes/torus_z.yaml -o out"),
        ("a picture", "implgen render examples/scenes/glassware.yaml -o glass.png"),
        ("a command's options and examples", "implgen render --help"),
    ),
)


def rows(group: Command) -> list[Command]:
    """The commands a group's help lists, in order: groups inside it are spelled out, one line per command."""
    out = [GENERATE] if group is ROOT else []
    for cmd in group.sub.values():
        out += rows(cmd) if cmd.sub else [cmd]
    return out


def listing(words: tuple[str, ...], group: Command) -> str:
    """The help of the whole command (words == ()) or of a group such as ("bench",)."""
    name = " ".join(("implgen", *words))
    lines = [f"usage: implgen {group.synopsis}", "", group.summary[:1].upper() + group.summary[1:], ""]
    lines.append("commands:")
    table = [(f"implgen {cmd.synopsis}", cmd.summary) for cmd in rows(group)] + [(f"{name} --help, -h", "this list")]
    width = max(len(left) for left, _ in table) + 2
    lines += [f"  {left:<{width}}{right}" for left, right in table]
    lines += ["", f"Options and examples of each: {name} COMMAND --help"]
    if group is ROOT:
        lines[-1] += f" ({name} SPEC.yaml --help for generating)"
    return "\n".join([*lines, "", examples_text(group.examples)])


def _call(target: str | Callable[[Sequence[str]], int], argv: Sequence[str]) -> int:
    if isinstance(target, str):
        module, func = target.split(":")
        target = getattr(importlib.import_module(module), func)
    return target(argv)


def _not_a_typo(word: str) -> None:
    """`implgen rendr ...` would be read as a spec file named rendr: say that there is no such command."""
    if not word.startswith("-") and "." not in word and "/" not in word and not os.path.lexists(word):
        names = ", ".join(n for n in COMMANDS if not n.startswith("-"))
        raise UserError(word, f"no such command or file (the commands: {names}; implgen --help)")


def dispatch(words: tuple[str, ...], group: Command, argv: Sequence[str]) -> int:
    """Run the command `argv` names in `group` (words: the group's own words, () for the whole command)."""
    if not argv:
        print(listing(words, group), file=sys.stderr)
        return 2
    name = argv[0]
    if name in HELP:
        print(listing(words, group))
        return 0
    cmd = group.sub.get(name)
    if cmd is None and group is ROOT:
        _not_a_typo(name)
        return _call(GENERATE.target, argv)
    if cmd is None:
        raise UserError(" ".join((*words, name)), f"no such command; choose one of: {', '.join(group.sub)}")
    if cmd.sub:
        return dispatch((*words, name), cmd, argv[1:])
    return _call(cmd.target, argv[1:])


def run(argv: Sequence[str]) -> int:
    return dispatch((), ROOT, list(argv))


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
