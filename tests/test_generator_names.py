"""Param names that collide with what the generated code uses itself still work (they are renamed
internally), and folding params into constants keeps the shape the same."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import sympy

from conftest import CShapes, load_python_shape
from implgen.codegen.emit import generate
from implgen.outputs import write_text_files
from implgen.spec.entry import parse_spec
from implgen.spec.parse import X, Y, Z, param_symbol

NASTY = [
    "c",
    "d",
    "o",
    "t",
    "g",
    "n",
    "p",
    "params",
    "roots",
    "box",
    "count",
    "all",
    "ox",
    "dx",
    "px",
    "w0",
    "q0",
    "k_c",
    "shape",
    "math",
    "np",
    "coeffs",
    "value",
    "NAME",
    "DEGREE",
    "PARAMS",
]


def _spec():
    equation = "x^2 + y^2 + z^2 - 1 + " + " + ".join(f"{n}*x*y/{i + 2}" for i, n in enumerate(NASTY))
    params = {n: 0.01 * (i + 1) for i, n in enumerate(NASTY)}
    return parse_spec(
        {"name": "nasty", "equation": equation, "params": params, "bounds": {"x": ["-2 - c", "2 + d"]}}, "<test>"
    )


def _exact_value(spec, point, params) -> float:
    q = lambda v: sympy.Rational(Fraction(float(v)))  # noqa: E731
    subs = {param_symbol(k): q(v) for k, v in params.items()}
    subs.update(dict(zip((X, Y, Z), map(q, point))))
    return float(spec.f.xreplace(subs))


def test_params_named_like_internal_identifiers(tmp_path, rng):
    spec = _spec()
    write_text_files(generate(spec), tmp_path)
    module = load_python_shape("nasty", tmp_path)
    assert list(module.PARAMS) == NASTY
    cshape = CShapes(["nasty"], folder=tmp_path)
    values = {n: float(v) for n, v in zip(NASTY, rng.uniform(-1, 1, len(NASTY)))}
    for point in rng.uniform(-1, 1, (10, 3)):
        want = _exact_value(spec, point, values)
        assert np.isclose(module.value(point, **values), want, rtol=1e-13, atol=1e-15)
        assert np.isclose(cshape.value("nasty", point, list(values.values())), want, rtol=1e-13, atol=1e-15)
    flag, box = cshape.bounds("nasty", list(values.values()))
    assert flag == 1 and box[0] == -2 - values["c"] and box[3] == 2 + values["d"] and np.isinf(box[1])


def test_specialise_folds_params_and_keeps_the_surface(tmp_path, rng):
    spec = parse_spec(
        {
            "name": "torus",
            "equation": "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
            "params": {"R": 1.0, "r": 0.25},
            "bounds": {"z": ["-r", "r"]},
        },
        "<test>",
    )
    folded = spec.specialise({"R": 1.5, "r": 0.5}, name="torus_fixed")
    assert folded.params == {} and folded.folded == {"R": 1.5, "r": 0.5} and folded.box()[2] == -0.5
    write_text_files(generate(spec) | generate(folded), tmp_path)
    general = load_python_shape("torus", tmp_path)
    fixed = load_python_shape("torus_fixed", tmp_path)
    o = rng.uniform(-2, 2, (100, 3))
    d = rng.normal(size=(100, 3))
    assert np.allclose(fixed.coeffs(o, d), general.coeffs(o, d, R=1.5, r=0.5), rtol=1e-14, atol=1e-14)
    assert "folded into constants: R = 1.5, r = 0.5" in (tmp_path / "torus_fixed.c").read_text()
