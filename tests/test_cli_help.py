"""The command line as people expect it, through the installed `implgen` script: --version, --help listing every
command of the dispatch table, each command's --help with examples, and one line for an unknown command."""

from __future__ import annotations

import ast
import importlib.metadata
import shlex
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

import implgen
from implgen import cli

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "generator" / "implgen"
EXE = Path(sys.executable).parent / "implgen"


def implgen_run(*argv: str) -> subprocess.CompletedProcess:
    return subprocess.run([str(EXE), *argv], capture_output=True, text=True, timeout=120, cwd=ROOT)


def command_words() -> list[tuple[str, ...]]:
    """Every command of the table as a person types it (generating: `implgen SPEC.yaml`), groups included."""
    words = [("SPEC.yaml",)]
    for name, cmd in cli.COMMANDS.items():
        if name.startswith("-"):
            continue
        words.append((name,))
        words += [(name, sub) for sub in cmd.sub]
    return words


def test_version_is_the_packages_one_version():
    p = implgen_run("--version")
    assert (p.returncode, p.stdout, p.stderr) == (0, f"implgen {implgen.__version__}\n", "")
    assert importlib.metadata.version("implgen") == implgen.__version__  # what pip installed
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    if "version" in project["project"]:
        assert project["project"]["version"] == implgen.__version__
    else:
        assert "version" in project["project"]["dynamic"]
        assert project["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "implgen.__version__"}


def test_help_lists_every_command_of_the_dispatch_table():
    p = implgen_run("--help")
    assert p.returncode == 0 and p.stderr == ""
    assert implgen_run("-h").stdout == p.stdout
    lines = p.stdout.splitlines()
    for cmd in [cli.GENERATE, *cli.COMMANDS.values(), *cli.COMMANDS["bench"].sub.values()]:
        if cmd.sub:
            continue
        line = next((x for x in lines if x.strip().startswith(f"implgen {cmd.synopsis} ")), None)
        assert line is not None, f"implgen {cmd.synopsis} is not in --help"
        assert line.rstrip().endswith(cmd.summary)
    for words in command_words():
        assert f"implgen {' '.join(words)}" in p.stdout
    assert "implgen --version" in p.stdout and "examples:" in p.stdout


def test_no_arguments_is_a_usage_error_with_the_list():
    p = implgen_run()
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr == implgen_run("--help").stdout


def test_bench_help_lists_the_benches():
    p = implgen_run("bench", "--help")
    assert p.returncode == 0 and p.stderr == ""
    for name, bench in cli.COMMANDS["bench"].sub.items():
        assert f"implgen bench {name} " in p.stdout and bench.summary in p.stdout
    assert "implgen render" not in p.stdout  # the benches only
    bare = implgen_run("bench")
    assert (bare.returncode, bare.stdout, bare.stderr) == (2, "", p.stdout)


CACHE_WORDS = [("cache", "info"), ("cache", "clear")]  # read without argparse (compile/command.py)


@pytest.mark.parametrize("words", command_words() + CACHE_WORDS, ids=" ".join)
def test_each_commands_help_has_examples(words):
    p = implgen_run(*words, "--help")
    assert p.returncode == 0, p.stderr
    assert p.stderr == "" and "Traceback" not in p.stdout
    assert p.stdout.startswith("usage: implgen")
    examples = p.stdout.split("\nexamples:\n", 1)[1].splitlines()
    commands = [line.strip() for line in examples if line.strip() and not line.strip().startswith("#")]
    assert commands, "no example command line"
    prefix = "implgen" if words == ("SPEC.yaml",) else f"implgen {' '.join(words)}"
    assert all(c.startswith("implgen") for c in commands)
    assert any(c.startswith(prefix) for c in commands), f"no example of {prefix}"
    for c in commands:  # the example files named are the repository's own
        for arg in shlex.split(c):
            if arg.startswith(("examples/", "bench/scenes/")):
                assert list(ROOT.glob(arg)), f"{c}: {arg} does not exist"


@pytest.mark.parametrize(
    "argv, names",
    [
        (["rendr", "scene.yaml"], "rendr: no such command or file"),
        (["bench", "nothing"], "bench nothing: no such command; choose one of: solvers, gen, render"),
        (["--version", "now"], "--version: takes no arguments"),
        (["render", "s.yaml", "-o", "o.png", "--widht", "3"], "unrecognized arguments: --widht"),
    ],
)
def test_an_unknown_command_is_one_line(argv, names):
    p = implgen_run(*argv)
    assert p.returncode == 2 and p.stdout == ""
    assert p.stderr.count("\n") == 1 and p.stderr.startswith("implgen: error: ") and names in p.stderr


def test_a_new_command_in_the_table_is_dispatched_and_listed(monkeypatch, capsys):
    seen = []
    paint = cli.Command("paint WALL", "paint a wall", lambda argv: seen.append(list(argv)) or 0)
    monkeypatch.setitem(cli.COMMANDS, "paint", paint)
    assert cli.main(["paint", "north", "-q"]) == 0 and seen == [["north", "-q"]]
    assert cli.main(["--help"]) == 0
    assert "implgen paint WALL" in capsys.readouterr().out


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            names |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
    return names


def test_cli_is_the_roof_and_args_the_ground_floor():
    for path in PACKAGE.rglob("*.py"):
        assert "implgen.cli" not in _imports(path), f"{path.relative_to(ROOT)} imports implgen.cli"
    assert {n for n in _imports(PACKAGE / "args.py") if n.startswith("implgen")} <= {
        "implgen.errors",
        "implgen.errors.UserError",
    }
