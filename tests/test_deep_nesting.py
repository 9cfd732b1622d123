"""Raw YAML nested hundreds of levels deep: refused in one line before any walk over it recurses too far.

A scene's raw values are walked before the reader checks them (is a value keyed anywhere inside an object?
a transform with its keyed values resolved), so each walk is bounded on its own (scene/keys.py MAX_NESTING)
instead of leaning on a depth check that comes later. The files are written in flow style, the way a
generated or hostile file would nest deepest within the file size limit.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from implgen import parse_scene
from implgen.errors import UserError
from implgen.scene import keys
from implgen_proc import assert_one_line, implgen

SPHERE = str(Path(__file__).resolve().parent.parent / "examples" / "shapes" / "sphere.yaml")
LEAF = f"{{shape: {SPHERE}}}"


def nested_csg(levels: int) -> str:
    node = LEAF
    for _ in range(levels):
        node = f"{{union: [{node}, {LEAF}]}}"
    return node


def nested_list(levels: int) -> str:
    return "[" * levels + "1" + "]" * levels


ANIMATION = "animation: {frames: 2}\n"
LIGHTS = "lights: [{position: [1, 2, 3]}]\n"


@pytest.mark.parametrize(
    "name, text, fragment",
    [
        ("csg-animated", ANIMATION + LIGHTS + f"objects: [{nested_csg(200)}]\n", "objects[0]: nested more than"),
        ("csg-still", LIGHTS + f"objects: [{nested_csg(200)}]\n", "objects[0]: nested more than"),
        (
            "transform-still",
            LIGHTS + f"objects: [{{shape: {SPHERE}, transform: {{scale: {nested_list(400)}}}}}]\n",
            "objects[0]: nested more than",
        ),
        # a keyed param first: the object is known to be keyed at once, and its transform is resolved
        # (keys.resolve); through a file the YAML reader's own limit (~500 levels) comes first
        (
            "transform-keyed",
            ANIMATION
            + LIGHTS
            + f"objects: [{{shape: {SPHERE}, params: {{r: {{keys: {{0: 1, 1: 2}}}}}}, "
            + f"transform: {{scale: {nested_list(400)}}}}}]\n",
            "objects[0].transform",
        ),
    ],
)
def test_deep_nesting_is_one_line(tmp_path, name, text, fragment):
    scene = tmp_path / f"{name}.yaml"
    scene.write_text(text)
    ran = implgen("render", scene, "-o", tmp_path / "out.png", "-q", "--width", "4", "--height", "3")
    assert_one_line(ran, str(scene), fragment)
    assert not (tmp_path / "out.png").exists()


@pytest.mark.parametrize("where", ["transform", "csg"])
def test_deep_mappings_given_to_parse_scene(where):
    """The public API takes a mapping built in Python, past any YAML reader's limit: each walk stops at its bound."""
    obj: dict = {"shape": SPHERE, "params": {"r": {"keys": {0: 1, 1: 2}}}}
    if where == "transform":
        deep: object = 1
        for _ in range(2000):
            deep = [deep]
        obj["transform"] = {"scale": deep}
    else:
        for _ in range(1000):
            obj = {"union": [obj, {"shape": SPHERE}]}
    data = {"animation": {"frames": 2}, "lights": [{"position": [1, 2, 3]}], "objects": [obj]}
    with pytest.raises(UserError, match=r"^deep\.yaml: objects\[0\].*: nested more than 100 levels deep"):
        parse_scene(data, "deep.yaml")


def test_csg_nesting_under_the_walk_bound_still_gets_the_readers_message(tmp_path):
    """40 CSG levels are 80 containers: within the walks' bound, so the reader's own CSG limit speaks."""
    scene = tmp_path / "csg40.yaml"
    scene.write_text(ANIMATION + LIGHTS + f"objects: [{nested_csg(40)}]\n")
    ran = implgen("render", scene, "-o", tmp_path / "out.png", "-q")
    assert_one_line(ran, str(scene), "CSG operations nested more than 32 deep")


def test_the_walks_stop_at_their_bound_whatever_the_recursion_limit():
    deep: object = 1
    for _ in range(keys.MAX_NESTING + 1):
        deep = [deep]
    with pytest.raises(UserError, match=r"s\.yaml: objects\[0\]: nested more than"):
        keys.contains_keyed(deep, "s.yaml", "objects[0]")
    ctx = keys.FrameKeys(source="s.yaml")
    with pytest.raises(UserError, match=r"s\.yaml: objects\[0\]\.transform.*: nested more than"):
        keys.resolve(ctx, "objects[0].transform", {"scale": deep})
    shallow = deep[0]  # exactly MAX_NESTING containers: walked
    assert keys.contains_keyed(shallow, "s.yaml", "x") is False
    assert keys.resolve(ctx, "t", shallow) == shallow
