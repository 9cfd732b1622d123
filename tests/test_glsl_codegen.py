"""The GLSL backend without a browser: what `implgen --lang glsl` writes, what reaches the file's comments, the
names GLSL reserves (spelled another way, one-to-one), and the constants of the affine code (each float with a
bound that encloses the exact rational)."""

from __future__ import annotations

import re
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import SHAPES_DIR
from implgen.codegen import escape
from implgen.codegen.backends.glsl import printer as glsl
from implgen.codegen.command import main as generate_command
from implgen.codegen.emit import generate
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


# A name as names.py takes it: these are the ones GLSL would not take as they are.
GLSL_AWKWARD = ["gl_ball", "GL_ball", "webgl_x", "my__shape", "ball_", "a___b_"]
IDENTIFIER = st.from_regex(r"[A-Za-z][A-Za-z0-9_]{0,63}", fullmatch=True)
RESERVED = re.compile(r"__|^gl_|^webgl_|^_webgl_")


def _unspelled(text: str) -> str:
    """glsl.py's spelling undone, independently: each _u read back as _."""
    assert re.fullmatch(r"[A-Za-z0-9]*(_u[A-Za-z0-9]*)*", text), text
    return "_".join(part[1:] if i else part for i, part in enumerate(text.split("_")))


@settings(max_examples=500, deadline=None)
@given(IDENTIFIER)
def test_a_name_makes_identifiers_glsl_takes_one_to_one(name):
    """glsl_name: the name itself when GLSL takes <name>_hit, else ig_shape_ and the name read back from it;
    param_local: k_<name>, else k0_ ... _u read back likewise, and never a shape's own identifier."""
    prefix, local = glsl.glsl_name(name), glsl.param_local(name)
    for ident in [local] + [f"{prefix}_{s}" for s in glsl.SUFFIXES]:
        assert not RESERVED.search(ident) and re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", ident), ident
    if RESERVED.search(f"{name}_hit") or name.lower().startswith(("gl_", "webgl_")):
        assert prefix.startswith("ig_shape_") and _unspelled(prefix[len("ig_shape_") :]) == name
    else:
        assert prefix == name
    if local.startswith("k0_"):
        assert local.endswith("_u") and _unspelled(local[3:-2]) == name
    else:
        assert local == f"k_{name}" and "__" not in name
    assert local.rsplit("_", 1)[1] not in glsl.SUFFIXES  # no <any prefix>_<suffix>: a local hides none


@pytest.mark.parametrize("name", GLSL_AWKWARD)
def test_names_glsl_reserves_are_spelled_for_glsl(name):
    """Each generated identifier is one GLSL takes: none holds __ or starts gl_ or webgl_; the C is unchanged."""
    spec = parse_spec(
        {
            "name": name,
            "equation": "x^2 + y^2 + z^2 - a__b*params + value_",
            "params": {"a__b": 1, "params": 1, "value_": 0},
        },
        "<t>",
    )
    assert set(generate(spec, ("c",))) == {f"{name}.h", f"{name}.c"}
    text = generate(spec, ("glsl",))[f"{name}.glsl"]
    code = "\n".join(line.split("//")[0] for line in text.splitlines())
    idents = set(re.findall(r"\b[A-Za-z_][A-Za-z0-9_]*", code))
    assert not [i for i in idents if RESERVED.search(i)]
    prefix = glsl.glsl_name(name)
    assert prefix != name and f"int {prefix}_hit(vec3 o" in text and f"uniform float {prefix}_params[3];" in text
    assert f"its GLSL identifiers start {prefix}" in text


def test_a_param_never_hides_the_shape_s_own_identifiers():
    """Shape `k`, param `params`: the local k_params would hide the uniform k_params in GLSL."""
    spec = parse_spec({"name": "k", "equation": "x^2 + y^2 + z^2 - params*b", "params": {"params": 1, "b": 1}}, "<t>")
    text = generate(spec, ("glsl",))["k.glsl"]
    declared = re.findall(r"^\s+float (\w+) = k_params\[(\d)\];", text, re.M)
    assert declared and {d for d, _ in declared} == {"k0_params_u", "k_b"}


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
