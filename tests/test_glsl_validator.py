"""Every generated shader compiles as GLSL ES 3.00 (WebGL2) and as GLSL 4.50: Khronos' reference compiler,
glslangValidator (Debian's glslang-tools), on each checked-in generated/*.glsl and on fresh high-degree and
hostile shapes, each with the whole runtime and a main that calls every function the shape and the runtime
offer."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from conftest import GENERATED, SHAPE_NAMES
from implgen.bench.glslcases import chmutov
from implgen.codegen.emit import generate
from implgen.codegen.glslprogram import program
from implgen.spec.entry import parse_spec

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
    int status = NAME_hit(cam.eye, d, t0, t1, t, n);
    vec3 lo, hi;
    bool bounded = NAME_bounds(lo, hi);
    vec3 p = cam.eye + t * d;
    vec3 f = NAME_raa(vec3(p.x, 0.1, 1e-6), vec3(p.y, 0.0, 0.0), vec3(p.z, -0.1, 0.0));
    vec3 rgb = ig_shade(ig_material_default(), NAME_normal(p), d, vec3(1.0, 2.0, 1.0));
    if ((status & IG_UNSURE) != 0) {
        rgb = ig_mark_unsure(rgb, pixel);
    }
    float v = NAME_value(p) + NAME_gradient(p).x + f.x + float(ig_ray_steps);
    colour = vec4(rgb, (in_sphere && in_box && bounded) ? v + lo.x + hi.y : 0.0);
}
"""


def _validate(tmp_path: Path, name: str, shape: str) -> None:
    for target in ("es", "450"):
        source = tmp_path / f"{name}_{target}.frag"
        source.write_text(program([shape], MAIN.replace("NAME", name), target))
        proc = subprocess.run(["glslangValidator", str(source)], capture_output=True, text=True)
        assert proc.returncode == 0, f"{name} as {target}:\n{proc.stdout}{proc.stderr}"


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
