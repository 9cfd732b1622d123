"""The package's shape, read from the source tree: every import between implgen's modules (at the top of a file
or inside a function) runs down the pipeline's floors or stays in its room, no modules import each other in a
circle, no module is over 400 lines, and the room-level graph is the one docs/layout.md draws."""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "generator" / "implgen"
MAX_LINES = 400

# Floors from the ground up; a module may import only from its own floor or below. The top-level modules not
# named here (errors, validate, yamlfile, outputs, abi, resources, cachedir, ...) are the ground floor.
FLOORS = {
    "ground": 0,
    "spec": 1,
    "codegen": 2,
    "compile": 3,
    "roots": 4,
    "raycast": 4,  # the path generated Python imports: an alias of roots.raycast
    "scene": 5,
    "animation": 6,
    "view": 7,
    "export": 7,
    "share": 7,
    "notebook": 7,
    "mesh": 7,
    "measure": 7,
    "demo": 7,
    "cli": 8,
}


def module_name(path: Path) -> str:
    rel = path.relative_to(PACKAGE.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def room(module: str) -> str:
    parts = module.split(".")
    if len(parts) == 1:
        return "package"
    name = parts[1]
    return name if name in FLOORS else "ground"


def imports(path: Path, known: set[str]) -> set[str]:
    """implgen modules that `path` imports anywhere in it (a `from implgen.x import y` names module x.y when
    y is a module, else x)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    package = module_name(path) if path.name == "__init__.py" else module_name(path).rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("implgen"))
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + [base]).strip(".")
            if not base.startswith("implgen"):
                continue
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                out.add(sub if sub in known else base)
    return {m for m in out if m in known and m != "implgen"}


@pytest.fixture(scope="module")
def graph() -> dict[str, set[str]]:
    mods = modules()
    return {m: imports(p, set(mods)) for m, p in mods.items()}


def test_no_import_runs_up_a_floor(graph: dict[str, set[str]]) -> None:
    up = [
        f"{a} ({room(a)}) imports {b} ({room(b)})"
        for a, deps in graph.items()
        for b in deps
        if room(a) != "package" and FLOORS[room(b)] > FLOORS[room(a)]
    ]
    assert not up, "\n".join(up)


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one node (Tarjan), iteratively."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    on_stack: set[str] = set()
    stack: list[str] = []
    found: list[list[str]] = []
    counter = 0
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = counter
        counter += 1
        stack.append(start)
        on_stack.add(start)
        while work:
            node, it = work[-1]
            nxt = next(it, None)
            if nxt is not None:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter
                    counter += 1
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph.get(nxt, ())))))
                elif nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == node:
                        break
                if len(comp) > 1:
                    found.append(sorted(comp))
    return found


def test_no_import_circle_between_modules(graph: dict[str, set[str]]) -> None:
    assert _cycles(graph) == []


def room_graph(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    rooms: dict[str, set[str]] = defaultdict(set)
    for a, deps in graph.items():
        if room(a) == "package":
            continue
        for b in deps:
            if room(b) != room(a):
                rooms[room(a)].add(room(b))
    return rooms


def test_no_circle_between_rooms(graph: dict[str, set[str]]) -> None:
    assert _cycles(dict(room_graph(graph))) == []


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_the_room_graph_is_the_one_docs_layout_draws(graph: dict[str, set[str]]) -> None:
    """docs/layout.md lists, in a fenced block after "Room imports", each room and the rooms it imports."""
    text = (ROOT / "docs" / "layout.md").read_text(encoding="utf-8")
    block = re.search(r"Room imports.*?```text\n(.*?)```", text, re.S)
    assert block, "docs/layout.md has no 'Room imports' block"
    documented = {}
    for line in block.group(1).splitlines():
        if "->" in line:
            a, _, rest = line.partition("->")
            documented[a.strip()] = {r.strip() for r in rest.split(",") if r.strip()}
    actual = {a: deps for a, deps in room_graph(graph).items() if deps}
    assert documented == actual


@pytest.mark.parametrize("module", sorted(modules()))
def test_no_module_is_over_400_lines(module: str) -> None:
    lines = modules()[module].read_text(encoding="utf-8").count("\n")
    assert lines <= MAX_LINES, f"{module}: {lines} lines"


def test_the_package_lives_in_a_folder_of_its_name() -> None:
    import implgen

    assert (PACKAGE / "__init__.py").is_file()
    installed = Path(implgen.__file__).resolve().parent
    assert installed.name == "implgen"
    # every subpackage in the tree, at any depth, is one the installed package has (pyproject lists them by hand)
    subpackages = {p.parent.relative_to(PACKAGE) for p in PACKAGE.rglob("__init__.py")}
    assert subpackages <= {p.parent.relative_to(installed) for p in installed.rglob("__init__.py")}


def test_one_folder_per_backend_and_one_template_folder_of_its_name() -> None:
    """codegen/backends/<lang>/ for each of LANGS, its Backend named so, its templates in templates/<lang>/; every
    template folder but the scene glue's belongs to a backend."""
    from implgen.codegen.backends import LANGS, backend

    folders = {p.parent.name for p in (PACKAGE / "codegen" / "backends").glob("*/backend.py")}
    assert folders == set(LANGS)
    for lang in LANGS:
        b = backend(lang)
        assert b.name == lang
        for template, _ in b.outputs():
            assert (ROOT / "templates" / template).is_file(), template
    assert {p.name for p in (ROOT / "templates").iterdir() if p.is_dir() and p.name != "__pycache__"} == {
        *LANGS,
        "scene",
    }
