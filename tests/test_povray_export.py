"""The POV-Ray export expands f exactly: its terms evaluate to f (rational reference) at random points."""

from __future__ import annotations

from fractions import Fraction

import pytest
import sympy

from conftest import SHAPE_FILES, SHAPE_NAMES
from implgen.export.povray import polynomial_object, polynomial_terms
from implgen.spec.entry import load_spec
from implgen.spec.parse import X, Y, Z, param_symbol


@pytest.mark.parametrize("path", SHAPE_FILES, ids=SHAPE_NAMES)
def test_terms_reproduce_f(path, rng):
    spec = load_spec(path)
    terms = polynomial_terms(spec)
    assert max(sum(m) for m, _ in terms) == spec.degree
    q = lambda v: sympy.Rational(Fraction(float(v)))  # noqa: E731
    f = spec.f.xreplace({param_symbol(k): q(v) for k, v in spec.params.items()})
    for p in rng.uniform(-1.2, 1.2, (20, 3)):
        exact = f.xreplace(dict(zip((X, Y, Z), map(q, p))))
        mags = [abs(c) * abs(p[0]) ** m[0] * abs(p[1]) ** m[1] * abs(p[2]) ** m[2] for m, c in terms]
        got = sum(c * p[0] ** m[0] * p[1] ** m[1] * p[2] ** m[2] for m, c in terms)
        assert abs(got - float(exact)) <= 1e-13 * max(sum(mags), 1e-300)


def test_object_text_for_the_torus():
    spec = load_spec([p for p in SHAPE_FILES if p.stem == "torus_z"][0])
    text = polynomial_object(spec, {"R": 2.0, "r": 0.5})
    assert text.startswith("polynomial { 4,") and text.rstrip().endswith("}") and "sturm" in text
    assert "xyz(4,0,0):1," in text  # x^4
    assert "xyz(0,0,0):14.0625" in text  # (R^2 + r^2)^2 - 4 R^2 r^2 = (R^2 - r^2)^2 = 3.75^2
    assert "xyz(0,0,2):7.5," in text  # -2(R^2 + r^2) + 4 R^2 = 2 R^2 - 2 r^2


def test_torus_constant_and_z2_terms_match_hand_expansion():
    # (x^2+y^2+z^2 - R^2 - r^2)^2 - 4R^2(r^2 - z^2): z^2 coefficient -2(R^2 + r^2) + 4R^2 = 2R^2 - 2r^2.
    spec = load_spec([p for p in SHAPE_FILES if p.stem == "torus_z"][0])
    terms = dict(polynomial_terms(spec, {"R": 2.0, "r": 0.5}))
    assert terms[(0, 0, 2)] == 2 * 4.0 - 2 * 0.25
    assert terms[(2, 0, 0)] == -2 * (4.0 + 0.25)
    assert terms[(0, 0, 0)] == (4.0 + 0.25) ** 2 - 4 * 4.0 * 0.25
