"""The GLSL's second tree for f (codegen/chebform.py): the tensor Chebyshev form of f on its box is f exactly,
and it is chosen only where it lowers float's error bound (the expanded Chmutov surfaces), never for a tree
the user wrote well. The pixels it gives are checked in the browser (tests/test_glsl_browser.py)."""

from __future__ import annotations

import pytest
import sympy

from conftest import SHAPES_DIR
from implgen.bench.glslcases import chmutov
from implgen.codegen import chebform
from implgen.codegen.emit import generate
from implgen.spec.entry import load_spec, parse_spec
from implgen.spec.parse import X, Y, Z


def _rebuilt(form: chebform.ChebForm) -> sympy.Expr:
    """sum c T_i(u) T_j(v) T_k(w) with u = (x - centre) / half, from SymPy's own Chebyshev polynomials."""
    u = [
        (s - sympy.Rational(c.numerator, c.denominator)) / sympy.Rational(h.numerator, h.denominator)
        for s, c, h in zip((X, Y, Z), form.centre, form.half, strict=True)
    ]
    return sum(
        sympy.Rational(c.numerator, c.denominator)
        * sympy.chebyshevt(i, u[0])
        * sympy.chebyshevt(j, u[1])
        * sympy.chebyshevt(k, u[2])
        for (i, j, k), c in form.coeffs.items()
    )


@pytest.mark.parametrize(
    "spec",
    [
        chmutov(12, nested=False),
        load_spec(SHAPES_DIR / "heart.yaml"),
        parse_spec(
            {
                "name": "lopsided",
                "equation": "x^3*y - 7/3*y^2*z^4 + z - 1/5",
                "bounds": {"x": [-1, 3], "y": [1 / 2, 5 / 4], "z": [-2, -1 / 8]},
            },
            "<test>",
        ),
    ],
    ids=["chmutov12 power form", "heart", "lopsided box"],
)
def test_the_chebyshev_form_is_f_exactly(spec):
    form = chebform.chebyshev_form(spec.f, spec.bounds)
    assert form is not None
    assert sympy.expand(_rebuilt(form) - spec.f) == 0


@pytest.mark.parametrize("n", [12, 16, 20, 24])
def test_the_expanded_chmutov_surfaces_get_the_chebyshev_form(n):
    assert chebform.better_form(chmutov(n, nested=False).f, chmutov(n, nested=False).bounds) is not None
    assert chebform.better_form(chmutov(n, nested=True).f, chmutov(n, nested=True).bounds) is None


@pytest.mark.parametrize("path", sorted(SHAPES_DIR.glob("*.yaml")), ids=lambda p: p.stem)
def test_the_example_shapes_keep_their_own_tree(path):
    spec = load_spec(path)
    assert chebform.better_form(spec.f, spec.bounds) is None


def test_params_or_an_open_box_keep_the_tree():
    power = chmutov(16, nested=False)
    open_box = parse_spec({"name": "c16", "equation": power.equation}, "<test>")
    assert chebform.chebyshev_form(open_box.f, open_box.bounds) is None
    one_axis = parse_spec({"name": "c16", "equation": power.equation, "bounds": {"x": [-1, 1]}}, "<test>")
    assert chebform.chebyshev_form(one_axis.f, one_axis.bounds) is None
    with_param = parse_spec(
        {
            "name": "c16",
            "equation": power.equation + " + a",
            "params": {"a": 0},
            "bounds": {"x": [-1, 1], "y": [-1, 1], "z": [-1, 1]},
        },
        "<test>",
    )
    assert chebform.chebyshev_form(with_param.f, with_param.bounds) is None


def test_the_shader_says_which_form_it_evaluates():
    assert "Evaluated in the Chebyshev basis of the box" in generate(chmutov(20, False), ("glsl",))["chmutov20.glsl"]
    assert "Evaluated in the tree as written" in generate(chmutov(20, True), ("glsl",))["chmutov20n.glsl"]
