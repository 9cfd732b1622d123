"""The generated GLSL on desktop OpenGL 4.5 through EGL (implgen.measure.glslegl: moderngl; Mesa's llvmpipe
here, a CPU's vector units running the shader in float32), checked ray by ray against the exact judge.

The browser's tests (test_glsl_browser.py) run the same programs in GLSL ES 3.00 on SwiftShader; these run them
as GLSL 4.50 on another float32 implementation, and are quicker, so the targeted ray sets live here.
"""

from __future__ import annotations

import os

import numpy as np
import pytest

from implgen.measure import glslcheck
from implgen.spec.entry import parse_spec


@pytest.fixture(scope="module")
def gl():
    from implgen.measure.glslegl import Egl

    try:
        context = Egl()
    except RuntimeError as exc:
        if os.environ.get("IMPLGEN_REQUIRE_ALL"):
            raise
        pytest.skip(str(exc))
    with context:
        yield context


def _capped_sphere_rays(deltas, angles, back: float = 10.0):
    """Rays that meet the unit sphere first at a point q with x = 0.5 + delta, just past the box's face
    x = 0.5, travelling on through the cap x > 0.5 (outside the box) and out: inside the box they meet nothing,
    so the exact answer is a miss. Each starts `back` units before q."""
    o = np.zeros((len(deltas), len(angles), 3))
    d = np.zeros_like(o)
    for i, delta in enumerate(deltas):
        x = 0.5 + delta
        r = np.sqrt(1.0 - x * x)
        q = np.stack([np.full(len(angles), x), r * np.cos(angles), r * np.sin(angles)], -1)
        u = np.array([1.0, 0.0, 0.0]) - 1.5 * q  # +x, and into the sphere at q
        u /= np.linalg.norm(u, axis=-1, keepdims=True)
        o[i], d[i] = q - back * u, u
    return o, d


def test_a_root_just_outside_the_box_is_not_a_certified_hit(gl):
    """The clip is rounded outward (clip.glsl), so the search reaches a few units of t past the box's face; a
    root found there, outside the box, is flagged, never a certified hit (the gallery's dingdong, endrass,
    kummer, monkey saddle and Togliatti each had one such pixel at 640 x 480)."""
    box = {"x": [-1.5, 0.5], "y": [-1.5, 1.5], "z": [-1.5, 1.5]}
    spec = parse_spec({"name": "capped", "equation": "x^2 + y^2 + z^2 - 1", "bounds": box}, "<test>")
    o, d = _capped_sphere_rays(np.geomspace(2e-7, 8e-6, 16), np.linspace(0.2, 1.3, 32))
    case = glslcheck.make_case("capped", spec, o, d)
    out = glslcheck.run_glsl(gl, case)
    r = glslcheck.compare(case, out, glslcheck.run_c(case), max_judged=len(d.reshape(-1, 3)))
    assert r.glsl_hits > 100  # the margin is reached: these rays test something
    assert r.object_pixels == 0  # the exact answer: every ray misses
    assert r.glsl_wrong_unflagged == 0, r.examples


def test_roots_inside_the_box_stay_certified(gl):
    """The same rays moved to the other side of the face (delta < 0): the root is inside the box, and the
    check of the margin leaves those hits certified."""
    box = {"x": [-1.5, 0.5], "y": [-1.5, 1.5], "z": [-1.5, 1.5]}
    spec = parse_spec({"name": "capped", "equation": "x^2 + y^2 + z^2 - 1", "bounds": box}, "<test>")
    o, d = _capped_sphere_rays(-np.geomspace(1e-3, 1e-1, 8), np.linspace(0.2, 1.3, 32))
    case = glslcheck.make_case("capped", spec, o, d)
    out = glslcheck.run_glsl(gl, case)
    r = glslcheck.compare(case, out, glslcheck.run_c(case))
    assert r.object_pixels == r.pixels and r.glsl_hits == r.pixels
    assert r.flagged == 0
