"""The generated GLSL in a real browser: headless Chromium's WebGL2 (ANGLE on SwiftShader), pixels read back.

Each case is a grid of float32 rays (implgen.measure.glslcases: every example shape through a camera, Chmutov
surfaces of degree 12 to 24, a torus from 10^3 units, grazing rays). The GLSL's hit mask is compared with the C
solvers' (double) on the same rays, and every pixel where they disagree or the GLSL flagged IG_UNSURE is
decided by the exact judge (f(o + t d) over Q, Descartes). The reduced affine forms themselves are checked
against f evaluated exactly. Small images (96 x 72): SwiftShader is a CPU emulation. The measured table at
640 x 480 is bench/glsl_compare.py's (bench/results/glsl.md).
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from conftest import SHAPES_DIR
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import program, shape_defines
from implgen.measure import glslcases, glslcheck
from implgen.roots import exactray
from implgen.spec.entry import load_spec, parse_spec

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")
SIZE = (96, 72)


@pytest.fixture(scope="module")
def gl():
    from implgen.measure.webgl import WebGL

    with WebGL() as browser:
        version, renderer = browser.info()
        assert version.startswith("WebGL 2.0"), version
        yield browser


def _compare(gl, case: glslcheck.Case) -> glslcheck.Comparison:
    out = glslcheck.run_glsl(gl, case)
    return glslcheck.compare(case, out, glslcheck.run_c(case))


EXAMPLES = glslcases.example_cases(SHAPES_DIR, SIZE)
NESTED = glslcases.high_degree_cases(SIZE, (True,))


@pytest.mark.parametrize("case", EXAMPLES + NESTED, ids=[c.label for c in EXAMPLES + NESTED])
def test_hit_mask_matches_the_exact_answer(gl, case):
    """No pixel is wrong without its flag; at most 1 % of the object's pixels are flagged; the certified hits'
    t agree with C's within float resolution."""
    r = _compare(gl, case)
    assert r.object_pixels > 0.05 * r.pixels  # the shape is in the picture (the slim Zitrus covers 8 %)
    assert r.glsl_wrong_unflagged == 0, r.examples
    assert r.glsl_wrong <= 0.001 * r.object_pixels, r.examples
    assert r.flagged <= 0.01 * r.object_pixels
    assert r.t_rel_err_max < 2e-5


@pytest.mark.parametrize("n", [16, 24])
def test_power_form_is_drawn_from_its_chebyshev_form(gl, n):
    """The expanded Chebyshev polynomial cancels by ~(1 + sqrt 2)^n / 2 near |x| = 1; its box's Chebyshev form
    (codegen/backends/glsl/chebform.py) does not, and the surface is certified like the nested one."""
    case = glslcases.view_case(f"chmutov{n}", glslcases.chmutov(n, nested=False), SIZE)
    r = _compare(gl, case)
    assert r.object_pixels > 0.1 * r.pixels
    assert r.glsl_wrong == 0, r.examples
    assert r.flagged <= 0.01 * r.object_pixels


def test_power_form_without_a_box_is_flagged_not_guessed(gl):
    """With no box there is no Chebyshev form: float cannot certify the sign of f on the surface, and the
    runtime says so (docs/glsl.md); no answer is wrong without its flag."""
    power = glslcases.chmutov(16, nested=False)
    spec = parse_spec({"name": "chmutov16", "equation": power.equation}, "<test>")
    r = _compare(gl, glslcases.view_case("chmutov16 unbounded", spec, SIZE))
    assert r.glsl_wrong_unflagged == 0
    assert r.flagged > 0.2 * r.object_pixels  # about half, where |x|, |y| or |z| is near 1


def test_torus_from_a_thousand_units(gl):
    """From 10^3 units the coordinates carry about 1e-4 of rounding: the tube touches its box along its top
    and outer circles, and a root within that of a face cannot be placed inside or outside the box in float,
    so it is flagged (ray.glsl's margin check): about 4 % of the object's pixels, none wrong unflagged."""
    r = _compare(gl, glslcases.far_torus_case(SHAPES_DIR, SIZE))
    assert r.object_pixels > 0.1 * r.pixels
    assert r.glsl_wrong_unflagged == 0, r.examples
    assert r.flagged <= 0.06 * r.object_pixels


def test_grazing_rays(gl):
    """Rows z = r + k delta over the top of torus_z's tube: the touching row (k = 0, a double root) is flagged
    wherever it touches; the rows a thousandth above and below are certified and right."""
    case = glslcases.grazing_case(SHAPES_DIR, 64)
    out = glslcheck.run_glsl(gl, case)
    judge = glslcheck.Judge(case)
    status = out["status"]
    for k in range(status.shape[0]):
        for col in range(status.shape[1]):
            truth = judge(k, col)
            hit, unsure = bool(status[k, col] & 1), bool(status[k, col] & 2)
            if k == 3 and truth:  # touching: a tangent root
                assert unsure or hit
            elif k != 3:
                assert not unsure and hit == truth, (k, col, truth, status[k, col])


def test_affine_forms_enclose_f(gl, rng):
    """The shape's _raa over random segments of random sizes: at points of the segment (its ends included), f evaluated
    exactly (rationals) lies within the form's centre + slope * e +- radius; and a point (slope 0) too."""
    shapes = [load_spec(p) for p in sorted(SHAPES_DIR.glob("*.yaml"))]
    shapes += [glslcases.chmutov(24, True), glslcases.chmutov(16, False)]
    w, h = 16, 8
    main = """
uniform highp sampler2D ig_test_orig;
uniform highp sampler2D ig_test_dir;
out vec4 ig_test_out;
void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 m = texelFetch(ig_test_orig, px, 0);
    vec4 s = texelFetch(ig_test_dir, px, 0);
    ig_test_out = vec4(IG_SHAPE_RAA(vec3(m.x, s.x, 0.0), vec3(m.y, s.y, 0.0), vec3(m.z, s.z, 0.0)), 0.0);
}
"""
    for spec in shapes:
        box = spec.box()
        lo = np.array(box[:3]) if box is not None and all(np.isfinite(box)) else np.full(3, -1.5)
        hi = np.array(box[3:]) if box is not None and all(np.isfinite(box)) else np.full(3, 1.5)
        m = (lo + rng.random((h, w, 3)) * (hi - lo)).astype(np.float32)
        scale = 10.0 ** rng.uniform(-7, -0.5, (h, w, 1))
        slope = (rng.normal(size=(h, w, 3)) * scale).astype(np.float32)
        slope[: h // 2] = 0.0  # points: the radius is then rounding alone
        pad = np.zeros((h, w, 1), np.float32)
        params = {k: float(np.float32(v)) for k, v in spec.params.items()}
        prefix = glsl_name(spec.name)
        uniforms = {f"{prefix}_params": list(params.values())} if params else {}
        frag = program([glslcheck.glsl_text(spec)], main, defines=shape_defines(prefix))
        out, _ = gl.run(frag, (w, h), uniforms, np.concatenate([m, pad], -1), np.concatenate([slope, pad], -1))
        terms = exactray.exact_terms(spec, params)
        for r, c in np.ndindex(h, w):
            cf, lf, rf = (Fraction(float(v)) for v in out[r, c, :3])
            assert np.isfinite(out[r, c, :3]).all()
            for e in (Fraction(-1), Fraction(-1, 3), Fraction(0), Fraction(5, 7), Fraction(1)):
                p = [Fraction(float(m[r, c, k])) + Fraction(float(slope[r, c, k])) * e for k in range(3)]
                f = sum(coef * p[0] ** i * p[1] ** j * p[2] ** k for (i, j, k), coef in terms)
                assert abs(f - (cf + lf * e)) <= rf, (spec.name, r, c, float(e))


def test_runtime_camera_and_shading_match_the_c_tracer(gl, tmp_path):
    """A whole picture through the runtime's camera (ig_camera, ig_camera_dir) and shading: the hit mask agrees
    with the C tracer's coverage at the same camera except on silhouette pixels (the camera rays are rounded
    to float on the GPU), and hit pixels are lit."""
    from implgen.scene.render import render

    spec_path = SHAPES_DIR / "torus_z.yaml"
    eye, look, fov = (2.5, 1.8, 3.0), (0.0, 0.0, 0.0), 40.0
    main = """
uniform vec2 size;
out vec4 ig_test_out;
void main()
{
    vec2 pixel = vec2(gl_FragCoord.x, size.y - gl_FragCoord.y);
    IgCamera cam = ig_camera(vec3(2.5, 1.8, 3.0), vec3(0.0), vec3(0.0, 1.0, 0.0), 40.0, size);
    vec3 d = ig_camera_dir(cam, pixel, size);
    float t;
    vec3 n;
    int status = torus_z_hit(cam.eye, d, 0.0, ig_inf(), t, n);
    vec3 rgb = (status & IG_HIT) != 0 ? ig_shade(ig_material_default(), n, d, vec3(1.0, 2.0, 1.5)) : vec3(0.0);
    ig_test_out = vec4(rgb, float(status));
}
"""
    spec = load_spec(spec_path)
    frag = program([glslcheck.glsl_text(spec)], main)
    out, _ = gl.run(frag, SIZE, {"torus_z_params": [1.0, 0.25], "size": [float(SIZE[0]), float(SIZE[1])]})
    status = out[::-1, :, 3].astype(int)  # row 0 of the read-back is the bottom row
    glsl_hit = (status & 1) != 0
    scene = {
        "camera": {"position": list(eye), "look_at": list(look), "up": [0, 1, 0], "fov": fov},
        "background": [0, 0, 0],
        "lights": [],
        "objects": [
            {"shape": str(spec_path), "material": {"color": [1, 1, 1], "ambient": 1.0, "diffuse": 0.0, "specular": 0}}
        ],
    }
    c_hit = render(scene, width=SIZE[0], height=SIZE[1], spp=1, threads=1, max_depth=0)[..., 0] > 0.5
    differ = glsl_hit != c_hit
    assert c_hit.sum() > 0.1 * c_hit.size
    assert differ.sum() <= 0.005 * c_hit.sum()
    assert (differ & ~glslcheck.silhouette(c_hit)).sum() == 0
    lit = out[::-1, :, :3].sum(-1)
    assert (lit[glsl_hit] > 0.05).all() and (lit[~glsl_hit] == 0).all()
