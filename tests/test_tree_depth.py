"""Every equation the parser accepts derives, or is refused by the documented depth limit in one line.

SymPy's diff, cse and printers walk an expression recursively, several Python frames a level. An equation nested
55 levels (`x^2 + z^2 + b + a*(b + a*( ... y ...))`, 110 levels of SymPy tree) was within the parenthesis and
param-degree limits, and `implgen SPEC`, `share` and `mesh` ended in a traceback of 2,387 lines from `sympy.diff`
(a long-lived process with SymPy's cache warm got through). The parser now refuses a tree deeper than
grammar.MAX_TREE_DEPTH; these tests run the deepest accepted equations in fresh processes, where SymPy's cache
is cold, through every path that derives, and a tree one level deeper is refused in one line.
"""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pytest
import sympy
from hypothesis import given
from hypothesis import strategies as st

from conftest import fuzz_settings
from fuzz_strategies import expressions
from implgen import cachedir
from implgen.codegen.derive import derive
from implgen.errors import UserError
from implgen.spec import grammar
from implgen.spec.entry import load_spec
from implgen.spec.grammar import MAX_TREE_DEPTH, ParseError, expression_depth, parse_expression
from implgen.spec.parse import VARIABLES, param_symbol
from implgen_proc import assert_one_line, implgen

PARAMS = "params: {a: 0.5, b: -0.1}\n"
NAMES = {"a": param_symbol("a"), "b": param_symbol("b")}


def nested(levels: int, inner: str = "y", factors: str = "a") -> str:
    """`b + a*(b + a*( ... inner ...))`: a sum and a product each level, 2 * levels deep (+ inner's depth); the
    product's factor cycles through `factors`."""
    text = inner
    for i in range(levels):
        text = f"b + {factors[i % len(factors)]}*({text})"
    return text


HALF = MAX_TREE_DEPTH // 2

# The deepest accepted equations, each exactly MAX_TREE_DEPTH deep: the issue's form; the same on the right of
# `=` (f = lhs - rhs negates it); a Horner form in x and a; squares of nested sums (powers in the tree).
DEEPEST = {
    "issue-form": "x^2 + z^2 + " + nested(HALF),
    "right-side": "x^2 + z^2 - 1 = " + nested(HALF),
    "horner-x": "z^2 - 1 + " + nested(HALF, "y", "xaa"),
    "squares": "x^2 + z^2 - 1 + " + nested(HALF - 3, f"({nested(1, f'({nested(1)})^2')})^2"),
}


def write_spec(folder: Path, name: str, equation: str) -> Path:
    path = folder / f"{name}.yaml"
    path.write_text(f"name: deep\nequation: {equation}\n{PARAMS}")
    return path


@pytest.mark.parametrize("form", sorted(DEEPEST))
def test_the_deepest_accepted_equations_are_at_the_limit(tmp_path, form):
    spec = load_spec(write_spec(tmp_path, form, DEEPEST[form]))
    assert expression_depth(spec.f) == MAX_TREE_DEPTH


@pytest.mark.parametrize("form", sorted(DEEPEST))
def test_the_deepest_accepted_equations_generate_share_and_mesh_in_a_fresh_process(tmp_path, form):
    """Each command in a process of its own (SymPy's cache cold), with the default recursion limit. The build
    cache's entry for this spec is removed first, so `mesh` derives it too instead of reading generated C."""
    path = write_spec(tmp_path, form, DEEPEST[form])
    shutil.rmtree(cachedir.cache_dir("gen") / load_spec(path).spec_key, ignore_errors=True)
    runs = {
        "generate": implgen(path, "--lang", "all", "-o", tmp_path / "gen", "-q"),
        "share": implgen("share", path, "-o", tmp_path / "page.html"),
        "mesh": implgen("mesh", path, "--clip", "box:1", "--cells", "8", "-o", tmp_path / "m.stl"),
    }
    for what, ran in runs.items():
        assert ran.code == 0 and "Traceback" not in ran.err, (what, ran.err[-2000:])
    assert {p.suffix for p in (tmp_path / "gen").iterdir()} == {".c", ".h", ".py", ".glsl"}
    assert (tmp_path / "page.html").stat().st_size > 0 and (tmp_path / "m.stl").stat().st_size > 84


def test_one_level_deeper_is_refused_in_one_line_by_every_command(tmp_path):
    equation = "x^2 + z^2 + " + nested(HALF, "y^2")  # one level over
    path = write_spec(tmp_path, "over", equation)
    fragment = f"equation: sums, products and powers nested {MAX_TREE_DEPTH + 1} levels deep"
    for args in ([path, "--lang", "all", "-o", tmp_path / "gen"], ["share", path, "-o", tmp_path / "p.html"]):
        assert_one_line(implgen(*args), str(path), fragment, f"(at most {MAX_TREE_DEPTH})")
    mesh = ["mesh", path, "--clip", "box:1", "--cells", "8", "-o", tmp_path / "m.stl"]
    assert_one_line(implgen(*mesh), str(path), fragment)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["over.yaml"]  # nothing written


def test_the_issues_equation_is_refused_in_one_line(tmp_path):
    path = write_spec(tmp_path, "issue", "x^2 + z^2 + " + nested(55))
    assert_one_line(implgen(path, "-o", tmp_path / "out"), str(path), "nested 110 levels deep")


def test_a_side_within_the_limit_whose_difference_is_not_is_refused(tmp_path):
    """f = lhs - rhs: -(a*(...)) stays a product, but -(...)^2 is (-1)*(...)^2, a level deeper than the right side."""
    rhs = f"b + ({nested(HALF - 1)})^2"
    assert expression_depth(parse_expression(rhs, VARIABLES, NAMES, 24).expr) == MAX_TREE_DEPTH
    with pytest.raises(UserError, match=rf"s\.yaml: equation: .* nested {MAX_TREE_DEPTH + 1} levels deep"):
        load_spec(write_spec(tmp_path, "s", f"x^2 + z^2 = {rhs}"))


def test_the_viewer_answers_beside_the_equation_and_draws_the_deepest(tmp_path):
    """The page got "internal error: RecursionError" (and the terminal 2,400 lines): now the parser's line, beside
    the equation; the deepest accepted equation is built (derived in the viewer's build thread) and drawn."""
    from starlette.testclient import TestClient

    from implgen.view.command import document_factory
    from implgen.view.server import create_app
    from test_view_api import picture, render_msg, reply

    params = {"a": 0.5, "b": -0.1}
    with TestClient(create_app(document_factory(None), threads=1)) as client, client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + z^2 + " + nested(55), "params": params}))
        err = reply(ws)
        assert err["type"] == "error" and err["field"] == "equation", err
        said = "equation: sums, products and powers nested 110 levels deep inside one another"
        assert err["message"] == f"{said} (at most {MAX_TREE_DEPTH})"
        ws.send_text(json.dumps({"type": "shape", "equation": DEEPEST["issue-form"], "params": params}))
        shape = reply(ws)
        assert shape["type"] == "shape" and shape["degree"] == 2, shape
        ws.send_text(render_msg({**hello, "values": shape["values"]}, seq=4, refine=False, w=64, h=48))
        assert len(picture(ws)) > 0


# ------------------------------------------------------------------------------ the depth itself


def recursive_depth(e: sympy.Basic) -> int:
    return 1 + max(map(recursive_depth, e.args)) if e.args else 0


@fuzz_settings(200)
@given(expressions(["x", "y", "z", "a", "b"], max_leaves=20))
def test_the_depth_is_the_trees_depth(text):
    try:
        parsed = parse_expression(text, VARIABLES, NAMES, 24)
    except ParseError:
        return
    assert expression_depth(parsed.expr) == recursive_depth(parsed.expr)


def test_the_depth_counts_levels_as_sympy_holds_them():
    x, y = VARIABLES["x"], VARIABLES["y"]
    assert [expression_depth(e) for e in (sympy.Integer(3), x, x + y, 2 * x + y, x - y**2, (x + 1) ** 2 * y)] == [
        0,
        0,
        1,
        2,
        3,
        3,
    ]


def test_the_depth_of_a_shared_subtree_is_walked_once_whatever_the_depth():
    """A tree far past the recursion limit, each level holding the level below twice: walked without recursion,
    and each shared node once (2^3000 paths, 3000 nodes)."""
    x = VARIABLES["x"]
    e = x
    for i in range(3000):
        e = sympy.Add(e, sympy.Mul(e, sympy.Symbol(f"s{i}"), evaluate=False), evaluate=False)
    assert expression_depth(e) == 6000


@fuzz_settings(20)
@given(st.integers(1, HALF))
def test_depth_limit_is_exact_on_the_nested_form(levels):
    parsed = parse_expression(nested(levels), VARIABLES, NAMES, 24)
    assert expression_depth(parsed.expr) == 2 * levels


# ------------------------------------------------------------------------------ the backstop in derive


def test_a_recursion_error_in_derive_is_one_line_naming_the_file(tmp_path):
    """Should the stack run out in derive anyway (here: a caller that left it little room), the spec is refused
    in one line naming its file, not with a RecursionError."""
    spec = load_spec(write_spec(tmp_path, "deep", DEEPEST["issue-form"]))
    sympy.core.cache.clear_cache()
    frame, used = sys._getframe(), 0
    while frame is not None:
        frame, used = frame.f_back, used + 1
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(used + 120)
    try:
        with pytest.raises(UserError) as caught:
            derive(spec)
    finally:
        sys.setrecursionlimit(limit)
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'deep.yaml'}: equation: too deeply nested to derive")
    assert "\n" not in message and str(grammar.MAX_TREE_DEPTH) in message
