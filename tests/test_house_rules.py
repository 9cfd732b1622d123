"""The house rules that a reader notices first: no function in the package or the C runtime over 60 lines
(split into named steps instead), and a README that is a front door of at most 200 lines."""

from __future__ import annotations

import ast
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MAX_LINES = 60


def python_functions(root: Path):
    """(lines, 'path:name') of every function and method under root."""
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text("utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                yield node.end_lineno - node.lineno + 1, f"{path.relative_to(ROOT)}:{node.name}"


def c_functions(path: Path):
    """(lines, 'file:name') of every function defined in a C file formatted by .clang-format (a definition's
    body opens with '{' alone at column 0 and closes with '}' alone at column 0)."""
    lines = path.read_text("utf-8").split("\n")
    start = None
    for i, line in enumerate(lines):
        if line == "{":
            k = i - 1
            while k > 0 and "(" not in lines[k]:
                k -= 1
            names = re.findall(r"(\w+)\s*\(", lines[k])
            start, name = i, names[0] if names else lines[k]
        elif line == "}" and start is not None:
            yield i - start + 2, f"{path.name}:{name}"
            start = None


def test_no_function_over_60_lines():
    found = list(python_functions(ROOT / "generator" / "implgen"))
    for path in sorted((ROOT / "runtime_c").glob("*.[ch]")):
        found += c_functions(path)
    assert len(found) > 500  # the walk found the functions
    long = sorted((n, where) for n, where in found if n > MAX_LINES)
    assert not long, f"functions over {MAX_LINES} lines: {long}"


# the C test drivers that are not named cases (tests/c/ctest.h), and why
NOT_NAMED_CASES = {
    "embree_check.c": "a driver of several modes with its own command line, timed by bench/embree.py",
    "tracer_offsets.c": "a measurement with arguments (hits per shape, seed) whose rows tests/test_tracer_c.py judges",
}


def test_no_function_over_60_lines_in_the_c_test_cases():
    """The C test drivers written as named cases keep the rule too: a case is a small function."""
    cdir = ROOT / "tests" / "c"
    paths = [p for p in sorted(cdir.glob("*.[ch]")) if p.name not in NOT_NAMED_CASES]
    found = [f for path in paths for f in c_functions(path)]
    assert set(NOT_NAMED_CASES) <= {p.name for p in cdir.glob("*.c")}
    assert len(found) > 100  # the walk found the functions
    long = sorted((n, where) for n, where in found if n > MAX_LINES)
    assert not long, f"functions over {MAX_LINES} lines: {long}"


def test_the_c_walk_measures_a_known_function(tmp_path):
    src = tmp_path / "f.c"
    src.write_text(
        "static int f(int a,\n                 int b)\n{\n    return a + b;\n}\n\nstruct s {\n    int x;\n};\n"
    )
    assert list(c_functions(src)) == [(4, "f.c:f")]


def test_the_readme_is_a_front_door():
    lines = (ROOT / "README.md").read_text("utf-8").splitlines()
    assert len(lines) <= 200, f"README.md has {len(lines)} lines"
