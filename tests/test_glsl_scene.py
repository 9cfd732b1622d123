"""The GLSL scene program (implgen.codegen.backends.glsl.scene, filled by implgen.share.scenegpu from the scene
model the C build uses): its tables against the scene, its structure (every shape's tree once), and
glslangValidator on every example scene's program as GLSL ES 3.00 and 4.50. The pictures are checked against
the C tracer in tests/test_glsl_scene_browser.py.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from implgen.codegen.backends.glsl.scene import number, scene_program
from implgen.measure.glslcalls import inlined_copies
from implgen.scene.load import load_scene
from implgen.share.scenegpu import camera_uniforms, scene_tables
from page_shader import glslang_problems

SCENES = Path(__file__).resolve().parent.parent / "examples" / "scenes"
EXAMPLES = sorted(SCENES.glob("*.yaml"))


def test_numbers_are_glsl_float_literals():
    assert number(1) == "1.0" and number(-0.25) == "-0.25" and number(1e-300) == "1e-300"
    assert number(float("inf")) == "1.0e30" and number(-float("inf")) == "-1.0e30"
    with pytest.raises(ValueError):
        number(float("nan"))


def test_the_tables_are_the_scene_s():
    """csg_trio: a floor plane (a surface) and three CSG objects of a sphere and a torus, in post-order, each
    leaf's world -> object map the inverse of its transform, its material its own."""
    scene = load_scene(SCENES / "csg_trio.yaml")
    t = scene_tables(scene)
    assert len(t.objects) == 4 and len(t.leaves) == 7
    floor = t.objects[0]
    assert floor.surface and floor.flat and floor.count == 1
    for obj, op in zip(t.objects[1:], (1, 2, 3)):  # union, intersection, difference
        assert not obj.surface and obj.count == 3
        assert [n[0] for n in t.nodes[obj.first : obj.first + 3]] == [0, 0, op]
    assert t.csg_stack == 2
    leaves = scene.leaves()
    for leaf, row in zip(leaves, t.leaves):
        m = np.vstack([np.asarray(leaf.matrix, float).reshape(3, 4), [0, 0, 0, 1]])
        inv = np.vstack([np.array(row.inverse).reshape(3, 4), [0, 0, 0, 1]])
        assert np.allclose(inv @ m, np.eye(4), atol=1e-12)
        assert t.materials[row.material].color == tuple(leaf.material.color)
    assert len(t.shapes) == 3  # the floor, the sphere r = 0.7, the torus a = 0.75, b = 0.25: values folded in
    assert [len(t.lights), t.max_depth, t.background] == [2, 4, (0.08, 0.08, 0.12)]


def test_every_shape_s_tree_is_in_the_program_once():
    """The glassware's twelve shapes: each one's affine form and normal once in the program, with every call
    inlined -- one root finder for every ray of the tree, every object and every CSG leaf."""
    t = scene_tables(load_scene(SCENES / "glassware.yaml"))
    text = scene_program(t)
    assert len(t.shapes) == 12
    for prefix, _ in t.shapes:
        assert inlined_copies(text, f"{prefix}_raa") == 1, prefix
        assert inlined_copies(text, f"{prefix}_normal") == 1, prefix
    assert inlined_copies(text, "ig_scene_root") == 1


def test_the_camera_is_the_tracer_s():
    """The uniforms' camera gives the directions implgen.scene.camera gives (the C tracer's)."""
    from implgen.scene.camera import camera_rays

    scene = load_scene(SCENES / "glassware.yaml")
    u = camera_uniforms(scene, (64, 48))
    x, y = np.array([0.5, 10.5, 63.5]), np.array([0.5, 20.5, 47.5])
    _, want = camera_rays(scene.camera, 64, 48, x, y)
    right, up, back = (np.array(u[k]) for k in ("ig_scene_right", "ig_scene_upv", "ig_scene_back"))
    got = (2 * x / 64 - 1)[:, None] * right + (1 - 2 * y / 48)[:, None] * up - back
    assert np.allclose(got, want, rtol=1e-14, atol=1e-14)


@pytest.mark.needs_program("glslangValidator")
@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_every_example_scene_s_program_compiles(path, tmp_path):
    t = scene_tables(load_scene(path))
    for target, suffix in (("es", "es.frag"), ("450", "450.frag")):
        assert glslang_problems(scene_program(t, target), tmp_path / f"{path.stem}.{suffix}") == "", target
    # the viewer's program: its lights and background uniforms (view/gpu.py)
    live = scene_program(t, "es", live_lights=3)
    assert "uniform vec3 ig_light_pos[IG_SCENE_LIGHTS];" in live
    assert glslang_problems(live, tmp_path / f"{path.stem}.live.es.frag") == ""


def test_a_scene_page_shows_its_file_name_as_text():
    """The scene's page (implgen share SCENE.yaml): its file's name is text on the page, never markup, and the
    program in its data is the scene's."""
    import json
    import re

    from implgen.codegen.backends.glsl.program import HEADERS
    from implgen.share.scenepage import render_scene_page

    scene = load_scene(SCENES / "torus_shadow.yaml")
    hostile = '<script>alert("x")</script>&.yaml'
    html = render_scene_page(scene, hostile)
    assert "<script>alert" not in html and "&lt;script&gt;alert" in html
    block = re.search(r'<script type="application/json" id="ig-data">(.*?)</script>', html, re.S).group(1)
    data = json.loads(block)
    assert data["header"] + data["program"] == scene_program(scene_tables(scene), "es")
    assert data["header"] == HEADERS["es"]
