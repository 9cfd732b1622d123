"""The GLSL's second tree for f (backends/glsl/chebform.py): the tensor Chebyshev form of f on its box is f exactly,
and it is chosen only where it lowers float's error bound (the expanded Chmutov surfaces), never for a tree
the user wrote well. The pixels it gives are checked in the browser (tests/test_glsl_browser.py)."""

from __future__ import annotations

import threading
import time
from fractions import Fraction

import pytest
import sympy

from conftest import SHAPES_DIR
from implgen.codegen.backends.glsl import chebform
from implgen.codegen.emit import generate
from implgen.measure.glslcases import chmutov
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


# ----------------------------------------------------- its time on a degree-24 product, and the GLSL budget

BOX = {a: [-1, 1] for a in "xyz"}
# six distinct linear factors to the 4th power: degree 24, 2906 monomials; SymPy's Poly of it took 37.7 s
SIX_FACTORS = (
    "(x + y + z - 0.1)^4 * (x - y + 0.2*z)^4 * (x + 0.3*y - z + 0.05)^4 * (0.5*x - y - z - 0.2)^4"
    " * (x - 0.4*y + 0.7*z + 0.15)^4 * (0.2*x + y - 0.6*z - 0.3)^4 - 1e-6"
)
# eight products of two linear factors to the 12th power: seconds of exact ring arithmetic
PRODUCTS = " + ".join(
    f"({i}*x - {9 - i}*y + {i % 4 + 1}*z - {i}/7)^12*({9 - i}*x + y - {i}*z + 2/7)^12" for i in range(1, 9)
)


def _t(n: int, u: Fraction) -> Fraction:
    a, b = Fraction(1), u
    for _ in range(n):
        a, b = b, 2 * u * b - a
    return a


def _form_at(form: chebform.ChebForm, point: tuple[Fraction, ...]) -> Fraction:
    """The Chebyshev form's value at a rational point, exactly (T_n by its three-term recurrence)."""
    u = [(p - c) / h for p, c, h in zip(point, form.centre, form.half, strict=True)]
    return sum(c * _t(i, u[0]) * _t(j, u[1]) * _t(k, u[2]) for (i, j, k), c in form.coeffs.items())


@pytest.mark.parametrize(
    "spec",
    [load_spec(p) for p in sorted(SHAPES_DIR.glob("*.yaml"))] + [chmutov(16, nested=False), chmutov(16, nested=True)],
    ids=lambda s: s.name,
)
def test_the_monomials_are_sympy_s_expansion_in_its_order(spec):
    """codegen/backends/glsl/chebform.py expands f by integer ring arithmetic on its tree, not by sympy.Poly: the same
    coefficients, exactly, in the same order (lex, highest first), so the Chebyshev form is unchanged."""
    if spec.f.free_symbols - {X, Y, Z}:
        pytest.skip("params: no Chebyshev form")
    poly = sympy.Poly(spec.f, X, Y, Z, domain=sympy.QQ)
    expected = [(m, Fraction(int(c.numerator), int(c.denominator))) for m, c in poly.terms()]
    assert list(chebform._monomials(spec.f).items()) == expected


def test_a_degree_24_product_gets_its_chebyshev_form_in_bounded_time():
    """Six linear factors each to the 4th power (degree 24): 37.7 s of SymPy for its Chebyshev form before (0.6 s
    now); a generous bound, and the form
    equals f exactly at rational points (f's tree evaluated in exact rationals)."""
    spec = parse_spec({"name": "six", "equation": SIX_FACTORS, "bounds": BOX}, "<test>")
    start = time.monotonic()
    form = chebform.chebyshev_form(spec.f, spec.bounds)
    assert time.monotonic() - start < 15.0
    assert form is not None and len(form.coeffs) == 2925 and spec.degree == 24
    for point in [(Fraction(1, 3), Fraction(-2, 7), Fraction(5, 11)), (Fraction(-1), Fraction(1), Fraction(0))]:
        exact = spec.f.subs(dict(zip((X, Y, Z), map(sympy.Rational, point), strict=True)))
        assert Fraction(int(exact.p), int(exact.q)) == _form_at(form, point)


def test_the_budget_cuts_the_chebyshev_step_and_the_shader_keeps_the_tree():
    """Under chebform.budget the Chebyshev step stops at its deadline or its stop (OverBudget, the budget marked
    cut) and the GLSL evaluates the tree as written, saying why; outside a budget nothing changes."""
    power = chmutov(16, nested=False)
    with chebform.budget(0.0) as held:
        with pytest.raises(chebform.OverBudget):
            chebform.better_form(power.f, power.bounds)
    assert held.cut
    stop = threading.Event()
    stop.set()
    with chebform.budget(None, stop) as held:
        shader = generate(power, ("glsl",))["chmutov16.glsl"]
    assert (
        held.cut and "Evaluated in the tree as written (not expanded): the Chebyshev basis of the box was not" in shader
    )
    with chebform.budget(60.0) as held:
        assert "Evaluated in the Chebyshev basis of the box" in generate(power, ("glsl",))["chmutov16.glsl"]
    assert not held.cut
    assert "Evaluated in the Chebyshev basis of the box" in generate(power, ("glsl",))["chmutov16.glsl"]


def test_a_chebyshev_step_past_its_budget_stops_soon_after():
    """The deadline is checked between small steps (a node of the tree, a coefficient, a term): a Chebyshev step
    of seconds of exact arithmetic stops within a generous second of a 0.1 s budget."""
    spec = parse_spec({"name": "products", "equation": PRODUCTS, "bounds": BOX}, "<test>")
    start = time.monotonic()
    with chebform.budget(0.1), pytest.raises(chebform.OverBudget):
        chebform.better_form(spec.f, spec.bounds)
    assert time.monotonic() - start < 1.1
