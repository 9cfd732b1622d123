"""The GLSL backend without a browser: what `implgen --lang glsl` writes, what reaches the file's comments, the
names GLSL refuses, and the constants of the affine code (each float with a bound that encloses the exact
rational)."""

from __future__ import annotations

import re
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import SHAPES_DIR
from implgen.codegen import escape, glsl
from implgen.codegen.command import main as generate_command
from implgen.codegen.emit import generate
from implgen.errors import UserError
from implgen.spec.entry import load_spec, parse_spec


def test_lang_glsl_writes_the_shader_alone(tmp_path):
    assert generate_command([str(SHAPES_DIR / "torus_y.yaml"), "--lang", "glsl", "-o", str(tmp_path), "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["torus_y.glsl"]
    text = (tmp_path / "torus_y.glsl").read_text()
    spec = load_spec(SHAPES_DIR / "torus_y.yaml")
    assert f"//   f(x, y, z) = {spec.equation}\n" in text
    assert "//   params: uniform float torus_y_params[2], in this order: a (default 1.0), b (default 0.25)" in text
    assert not re.search(r"^\s*#version", text, re.M)
    for fn in ("float torus_y_value(vec3 p)", "vec3 torus_y_gradient(vec3 p)", "vec3 torus_y_normal(vec3 p)",
               "bool torus_y_bounds(out vec3 lo, out vec3 hi)", "vec3 torus_y_raa(vec3 x, vec3 y, vec3 z)",
               "int torus_y_hit(vec3 o, vec3 d, float tmin, float tmax, out float t, out vec3 n)"):  # fmt: skip
        assert fn in text


def test_lang_all_includes_glsl(tmp_path):
    generate_command([str(SHAPES_DIR / "sphere.yaml"), "-o", str(tmp_path), "-q"])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["sphere.c", "sphere.glsl", "sphere.h", "sphere.py"]


def test_the_shader_is_not_expanded():
    """The affine code follows f's own tree: the torus's (x^2 + y^2 + z^2)^2 is one square of one sum."""
    text = generate(load_spec(SHAPES_DIR / "torus_z.yaml"), ("glsl",))["torus_z.glsl"]
    body = text[text.index("vec3 torus_z_raa") : text.index("int torus_z_hit")]
    assert body.count("ig_raa_sqr(x)") == 1 and body.count("ig_raa_sqr(") <= 8 and "ig_raa_mul(x, x)" not in body


@settings(max_examples=300, deadline=None)
@given(st.text())
def test_glsl_comment_keeps_to_a_small_alphabet(text):
    out = escape.glsl_comment(text)
    assert re.fullmatch(r"[A-Za-z0-9 _.,:;+\-*/^()=]*", out)


def test_hostile_file_name_stays_a_comment(tmp_path):
    name = 'h"x\\y??\n z.yaml'
    path = tmp_path / name
    path.write_text("name: hostile\nequation: x^2 + y^2 + z^2 - a^2\nparams: {a: 1}\ndescription: '*/ \\\\'\n")
    text = generate(load_spec(path), ("glsl",))["hostile.glsl"]
    comments = "".join(line for line in text.splitlines() if line.lstrip().startswith("//"))
    assert name not in text and "\\" not in text and '"' not in text and "?" not in comments
    assert "U+0022" in text.splitlines()[0]


@pytest.mark.parametrize("name", ["gl_ball", "webgl_x", "my__shape"])
def test_names_glsl_reserves_are_refused_for_glsl_only(tmp_path, capsys, name):
    spec = parse_spec({"name": name, "equation": "x^2 + y^2 + z^2 - 1"}, "<t>")
    assert set(generate(spec, ("c",))) == {f"{name}.h", f"{name}.c"}
    with pytest.raises(UserError, match="reserved there"):
        generate(spec, ("glsl",))
    path = tmp_path / "s.yaml"
    path.write_text(f"name: {name}\nequation: x^2 + y^2 + z^2 - 1\n")
    from implgen.cli import main

    assert main([str(path), "--lang", "glsl", "-o", str(tmp_path / "out")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


RATIONALS = [
    Fraction(1, 3),
    Fraction(9, 80),
    Fraction(1, 10),
    Fraction(16777217),
    Fraction(2) ** 200,
    -(Fraction(3) ** 150),
    Fraction(1, 10**60),
    Fraction(-7, 2**140),
    Fraction(123456789, 1000),
]


@pytest.mark.parametrize("q", RATIONALS, ids=str)
def test_affine_constants_enclose_the_rational(q):
    """Each constant is a product of factors within float range; each factor is printed as a float literal that
    reads back as exactly that float32, with a bound (also a float32) on its distance from the exact factor."""
    factors = glsl._factors(q)
    assert np.prod(factors, dtype=object) == q
    for f in factors:
        code = glsl._AffineCode({}).constant(f)
        c_text, e_text = re.fullmatch(r"ig_raa_const\(([^,]+), ([^)]+)\)", code).groups()
        c, e = float(c_text), float(e_text)
        assert float(np.float32(c)) == c and float(np.float32(e)) == e  # both are float32 values, printed exactly
        assert abs(f - Fraction(c)) <= Fraction(e)
        assert e == 0 or e >= 2.0**-126  # no subnormal a GPU could flush to zero
        assert Fraction(e) <= abs(f) * Fraction(1, 2**23) or abs(f) < Fraction(2) ** -126


@settings(max_examples=200, deadline=None)
@given(st.fractions(min_value=-(10**30), max_value=10**30))
def test_any_rational_constant_is_enclosed(q):
    for f in glsl._factors(q):
        c = glsl._f32(f) if abs(f) >= Fraction(2) ** -126 else 0.0
        assert abs(f - Fraction(c)) <= Fraction(glsl._f32_up(abs(f - Fraction(c))))


def test_plain_float_code_has_only_float_literals():
    """GLSL has no implicit int to float: every number in the float code carries a point or an exponent."""
    spec = parse_spec({"name": "ints", "equation": "3*x^5 - 2*y + 16777217*z - 7/2", "params": {}}, "<t>")
    text = generate(spec, ("glsl",))["ints.glsl"]
    value = text[text.index("float ints_value") : text.index("// grad")]
    numbers = re.findall(r"(?<![\w.[])\d[\w.+-]*", value.split("{", 1)[1])  # not the p[i] indices
    assert numbers and all(("." in n or "e" in n) for n in numbers), numbers


def test_every_runtime_file_is_in_the_program_order():
    from implgen.resources import GLSL_RUNTIME_SOURCES, runtime_glsl_dir

    on_disk = sorted(p.name for p in runtime_glsl_dir().glob("*.glsl"))
    assert sorted(GLSL_RUNTIME_SOURCES) == on_disk and len(set(GLSL_RUNTIME_SOURCES)) == len(on_disk)
