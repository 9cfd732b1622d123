"""A top-level surface's `clip` (rt_scene_set_clip): the surface shown only inside a ball or a cube, cut open
with no cap, in the shape's object space; checked against the ray parameters worked out by hand, and the
scene file's refusals."""

from __future__ import annotations

import math

import pytest
import yaml

from implgen.errors import UserError
from implgen.scene import build
from implgen.scene.load import parse_scene
from implgen.scene.tracer import CScene

CONE = "x^2 + y^2 - z^2"  # unbounded: without a clip it runs to the scene's far distance


def scene(obj: dict) -> dict:
    return {
        "image": {"width": 8, "height": 8},
        "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "fov": 40},
        "lights": [{"position": [0, 5, 5], "color": [1, 1, 1]}],
        "objects": [obj],
    }


def first_hit(obj: dict, o, d):
    sc = parse_scene(yaml.safe_load(yaml.safe_dump(scene(obj))), "clip.yaml")
    return CScene(sc, build.build_scene(sc)).intersect(o, d)


@pytest.mark.parametrize(
    "clip, t",
    [
        # the ray x = 0.5, along -z from z = 10, meets the cone where z^2 = 0.25 + y^2 = 0.25 + 0.09 (y = 0.3)
        (None, 10 - math.sqrt(0.34)),
        ({"sphere": 2.0}, 10 - math.sqrt(0.34)),  # both cone points are inside the ball
        ({"sphere": 0.6}, None),  # |(0.5, 0.3, +-0.583)| = 0.825 > 0.6: no point of it inside
        ({"box": 0.55}, None),  # |z| = 0.583 > 0.55
        ({"box": 0.6}, 10 - math.sqrt(0.34)),
        ({"box": 0.6, "center": [0, 0, -0.1]}, 10 + math.sqrt(0.34)),  # z in [-0.7, 0.5]: the far point only
    ],
)
def test_clip_shows_the_surface_inside_the_region_only(clip, t) -> None:
    obj = {"equation": CONE, "name": "cone"} | ({"clip": clip} if clip else {})
    hit = first_hit(obj, [0.5, 0.3, 10], [0, 0, -1])
    if t is None:
        assert hit is None
    else:
        assert hit is not None and hit.t == pytest.approx(t, abs=1e-9)


def test_clip_is_in_object_space_and_moves_with_the_transform() -> None:
    """A unit sphere clipped to the ball of radius 0.5 about (0, 0, 1) is the cap z > 0.875 (a disc of radius
    sqrt(1 - 0.875^2) seen from above); moved by (3, 0, 0), the clip moves with it."""
    obj = {"equation": "x^2 + y^2 + z^2 - 1", "name": "s", "clip": {"sphere": 0.5, "center": [0, 0, 1]}}
    obj["transform"] = {"translate": [3, 0, 0]}
    assert first_hit(obj, [3.0, 0.0, 10], [0, 0, -1]).t == pytest.approx(9.0, abs=1e-9)
    edge = math.sqrt(1 - 0.875**2)
    assert first_hit(obj, [3.0 + edge * 0.99, 0.0, 10], [0, 0, -1]) is not None
    assert first_hit(obj, [3.0 + edge * 1.01, 0.0, 10], [0, 0, -1]) is None


@pytest.mark.parametrize(
    "obj, needle",
    [
        ({"equation": CONE, "clip": {"sphere": 1, "box": 1}}, "give exactly one of sphere, box"),
        ({"equation": CONE, "clip": {"ball": 1}}, "clip"),
        ({"equation": CONE, "clip": {"sphere": -1}}, "clip.sphere"),
        ({"intersection": [{"equation": CONE, "clip": {"sphere": 1}}, {"equation": "z"}]}, "only for a top-level"),
    ],
)
def test_bad_clips_are_one_line(obj, needle) -> None:
    with pytest.raises(UserError) as err:
        parse_scene(scene(obj), "clip.yaml")
    assert needle in str(err.value) and "\n" not in str(err.value)


def test_the_c_side_refuses_a_clip_it_cannot_honour() -> None:
    """rt_scene_set_clip: only a leaf, never a CSG operand (before or after), a finite positive size."""
    import numpy as np

    from implgen.compile import clib
    from implgen.scene.model import Material
    from implgen.scene.tracer import CLIPS, OPS, bind, darr

    sc = parse_scene(scene({"equation": CONE, "name": "cone"}), "clip.yaml")
    built = build.build_scene(sc)
    lib = bind(clib.load(built.library))
    s = lib.rt_scene_new()
    try:
        mat = lib.rt_scene_add_material(s, darr(Material().packed()))
        eye = darr(np.eye(3, 4).reshape(-1))
        shape = lib.rt_scene_shape(0)
        a, b = (lib.rt_scene_add_leaf(s, shape, darr([]), 0, eye, mat) for _ in range(2))
        origin = darr([0, 0, 0])
        sphere = CLIPS["sphere"]
        assert lib.rt_scene_set_clip(s, a, sphere, origin, 0.0) == -1  # not positive
        assert lib.rt_scene_set_clip(s, a, sphere, origin, float("inf")) == -1
        assert lib.rt_scene_set_clip(s, a, 7, origin, 1.0) == -1  # no such kind
        assert lib.rt_scene_set_clip(s, a, sphere, origin, 1.0) == 0
        assert lib.rt_scene_add_csg(s, OPS["union"], a, b, -1) == -1  # a clipped operand
        assert b"clipped leaf" in lib.rt_scene_error(s)
        u = lib.rt_scene_add_csg(s, OPS["union"], b, lib.rt_scene_add_leaf(s, shape, darr([]), 0, eye, mat), -1)
        assert u >= 0
        assert lib.rt_scene_set_clip(s, b, sphere, origin, 1.0) == -1  # already an operand
        assert lib.rt_scene_set_clip(s, u, sphere, origin, 1.0) == -1  # not a leaf
    finally:
        lib.rt_scene_free(s)


def _clipped_cone_hit(clips: list[tuple[str | None, float]]):
    """A cone leaf given the clips in turn (the last one holds), committed, hit by the ray x = 0.5, y = 0.3 along
    -z from z = 10: the cone's points there are z = +-sqrt(0.34) = +-0.583."""
    import ctypes

    import numpy as np

    from implgen.compile import clib
    from implgen.scene.model import Material
    from implgen.scene.tracer import CLIPS, RtHit, bind, darr

    sc = parse_scene(scene({"equation": CONE, "name": "cone"}), "clip.yaml")
    lib = bind(clib.load(build.build_scene(sc).library))
    s = lib.rt_scene_new()
    try:
        mat = lib.rt_scene_add_material(s, darr(Material().packed()))
        leaf = lib.rt_scene_add_leaf(s, lib.rt_scene_shape(0), darr([]), 0, darr(np.eye(3, 4).reshape(-1)), mat)
        for kind, size in clips:
            assert lib.rt_scene_set_clip(s, leaf, CLIPS[kind] if kind else 0, darr([0, 0, 0]), size) == 0
        assert lib.rt_scene_add_object(s, leaf) == 0 and lib.rt_scene_commit(s) == 0
        hit = RtHit()
        if lib.rt_scene_intersect(s, darr([0.5, 0.3, 10]), darr([0, 0, -1]), 0.0, math.inf, ctypes.byref(hit)):
            return hit.t
        return None
    finally:
        lib.rt_scene_free(s)


@pytest.mark.parametrize("kind", ["box", "sphere"])
def test_a_later_clip_replaces_an_earlier_one(kind) -> None:
    """A second rt_scene_set_clip replaces the first, larger or smaller: the object's box is the spec's box cut
    by the last clip, not by every clip ever given (the small clip alone hides both cone points)."""
    near = 10 - math.sqrt(0.34)
    assert _clipped_cone_hit([(kind, 0.2)]) is None
    assert _clipped_cone_hit([(kind, 0.2), (kind, 2.0)]) == pytest.approx(near, abs=1e-9)
    assert _clipped_cone_hit([(kind, 2.0), (kind, 0.2)]) is None
    assert _clipped_cone_hit([(kind, 0.2), (None, 1.0)]) == pytest.approx(near, abs=1e-9)  # no clip: all of it
