"""Every generated shader compiles as GLSL ES 3.00 (WebGL2) and as GLSL 4.50: Khronos' reference compiler,
glslangValidator (Debian's glslang-tools), on each checked-in generated/*.glsl and on fresh high-degree and
hostile shapes, each with the whole runtime and a main that calls every function the shape and the runtime
offer."""

from __future__ import annotations

from pathlib import Path

import pytest

from conftest import GENERATED, SHAPE_NAMES
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import program, shape_defines
from implgen.codegen.emit import generate
from implgen.measure.glslcases import chmutov
from implgen.spec.entry import parse_spec
from page_shader import glslang_problems

pytestmark = pytest.mark.needs_program("glslangValidator")

MAIN = """
uniform vec2 size;
out vec4 colour;

void main()
{
    vec2 pixel = vec2(gl_FragCoord.x, size.y - gl_FragCoord.y);
    IgCamera cam = ig_camera(vec3(3.0, 2.0, 4.0), vec3(0.0), vec3(0.0, 1.0, 0.0), 40.0, size);
    vec3 d = ig_camera_dir(cam, pixel, size);
    float t0 = 0.0;
    float t1 = 1.0e4;
    bool in_sphere = ig_clip_sphere(cam.eye, d, vec3(0.0), 2.0, t0, t1);
    bool in_box = ig_clip_box(cam.eye, d, vec3(-2.0), vec3(2.0), t0, t1);
    float t;
    vec3 n;
    int status = IG_SHAPE_HIT(cam.eye, d, t0, t1, t, n);
    vec3 lo, hi;
    bool bounded = IG_SHAPE_BOUNDS(lo, hi);
    vec3 p = cam.eye + t * d;
    vec3 f = IG_SHAPE_RAA(vec3(p.x, 0.1, 1e-6), vec3(p.y, 0.0, 0.0), vec3(p.z, -0.1, 0.0));
    vec3 rgb = ig_shade(ig_material_default(), IG_SHAPE_NORMAL(p), d, vec3(1.0, 2.0, 1.0));
    if ((status & IG_UNSURE) != 0) {
        rgb = ig_mark_unsure(rgb, pixel);
    }
    float v = IG_SHAPE_VALUE(p) + IG_SHAPE_GRADIENT(p).x + f.x + float(ig_ray_steps);
    colour = vec4(rgb, (in_sphere && in_box && bounded) ? v + lo.x + hi.y : 0.0);
}
"""


def _validate(tmp_path: Path, name: str, shape: str) -> None:
    """Errors and warnings alike fail (glslangValidator only warns about identifiers that hold __)."""
    for target in ("es", "450"):
        text = program([shape], MAIN, target, shape_defines(glsl_name(name)))
        problems = glslang_problems(text, tmp_path / f"{name}_{target}.frag")
        assert not problems, f"{name} as {target}:\n{problems}"


@pytest.mark.parametrize("name", SHAPE_NAMES)
def test_generated_shader_compiles_as_es300_and_450(tmp_path, name):
    _validate(tmp_path, name, (GENERATED / f"{name}.glsl").read_text())


@pytest.mark.parametrize("n, nested", [(24, True), (24, False), (16, False)])
def test_high_degree_shaders_compile(tmp_path, n, nested):
    spec = chmutov(n, nested)
    _validate(tmp_path, spec.name, generate(spec, ("glsl",))[f"{spec.name}.glsl"])


def test_awkward_constants_and_params_compile(tmp_path):
    """Constants beyond float range (products of in-range factors), below it, not representable; many params."""
    spec = parse_spec(
        {
            "name": "awkward",
            "equation": "2^200*x^2 + y^2/3 + z^2/10^60 - a*b + 1/7*c^3 - 16777217",
            "params": {"a": 1.0, "b": 2.5, "c": -3.0},
            "bounds": {"x": ["-a", "a"], "z": [-1, "b"]},
        },
        "<test>",
    )
    _validate(tmp_path, "awkward", generate(spec, ("glsl",))["awkward.glsl"])


@pytest.mark.parametrize("name", ["ball_", "a__b", "gl_ball", "webgl_ball", "k", "MAX_LIGHTS"])
def test_names_glsl_reserves_or_that_hide_the_shape_s_compile(tmp_path, name):
    """Names whose identifiers GLSL reserves (spelled another way: backends/glsl/printer.py glsl_name, param_local), and
    params whose locals would hide the shape's own identifiers (shape k: k_params, k_value), all in use."""
    params = {"params": 1.0, "value": 0.5, "a__b": 2.0, "c_": 0.25, "gl_x": 1.0, "x_hit": 0.0}
    spec = parse_spec(
        {
            "name": name,
            "equation": "x^2 + y^2 + z^2 - params*value + a__b*c_ - gl_x + x_hit*z",
            "params": params,
            "bounds": {"x": ["-params - a__b", "value + c_"], "z": ["-gl_x - x_hit", 2]},
        },
        "<test>",
    )
    _validate(tmp_path, name, generate(spec, ("glsl",))[f"{name}.glsl"])
