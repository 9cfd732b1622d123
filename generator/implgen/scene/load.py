"""Scene files: YAML -> the validated scene model (scene/model.py). The format is documented in
docs/formats.md.

The top-level blocks are read here (image, camera, background, lights; materials in scene/materials.py,
objects and CSG in scene/objects.py), each number through the frame's reader (scene/reader.py). Every error is a
UserError naming the scene file and the key at fault (`objects[2].transform.rotate`), so the CLI prints one
line and exits with status 2 before anything is compiled or written.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from implgen import abi
from implgen.errors import UserError
from implgen.scene import keys
from implgen.scene import transform as tf
from implgen.scene.materials import parse_materials
from implgen.scene.model import Camera, Light, Node, Scene, depth
from implgen.scene.objects import parse_object
from implgen.scene.reader import Reader, given
from implgen.yamlfile import read_yaml

MAX_CSG_DEPTH = abi.value("RT_MAX_CSG_DEPTH")  # depth of the binary tree the tracer takes
MAX_DEPTH = abi.value("RT_MAX_DEPTH")
MAX_SPP = abi.value("RT_MAX_SPP")
MAX_SIZE = 16384  # image width and height
INTENSITY_MAX = 1e4  # light colour x intensity stays below 100 x 1e4

TOP_KEYS = ("image", "camera", "background", "lights", "materials", "objects", "animation")
IMAGE_KEYS = ("width", "height", "spp", "max_depth")
CAMERA_KEYS = ("position", "look_at", "up", "fov", "orbit")
LIGHT_KEYS = ("position", "color", "intensity")


def parse_scene(data: Any, source: str | Path = "<scene>", *, frame: int = 0, memo: dict | None = None) -> Scene:
    """The scene at `frame` (0 for a still). `memo` carries the specs read for one frame to the next."""
    ctx = Reader(Path(source), frame, memo)
    if not isinstance(data, dict):
        raise UserError(ctx.source, "a scene must be a mapping with at least 'objects'")
    ctx.mapping("", data, TOP_KEYS)
    sc = Scene(source=ctx.source)
    if "animation" in data:
        sc.animation = keys.parse_animation(ctx.source, data["animation"])
        ctx.frames = sc.animation.frames
    if not 0 <= frame < sc.animation.frames:
        raise UserError(ctx.source, f"frame {frame} is outside [0, {sc.animation.frames - 1}]")
    _image(ctx, ctx.mapping("image", given(data, "image", {}), IMAGE_KEYS), sc)
    sc.camera = _camera(ctx, ctx.mapping("camera", given(data, "camera", {}), CAMERA_KEYS))
    if "background" in data:
        sc.background = ctx.color("background", data["background"])
    sc.lights = _lights(ctx, given(data, "lights", []))
    mats = given(data, "materials", {})
    named = parse_materials(ctx, mats)
    objs = data.get("objects")
    if not isinstance(objs, list) or not objs:
        raise ctx.fail("objects", "expected a non-empty list")
    keyed_mats = keys.contains_keyed(mats, ctx.source, "materials")
    fixed = ctx.static if not keyed_mats else None  # no object can change with the frame
    sc.objects = [parse_object(ctx, i, raw, named, fixed) for i, raw in enumerate(objs)]
    sc.keyed = tuple(ctx.keyed)
    _check_objects(ctx, sc.objects)
    return sc


def _image(ctx: Reader, img: dict, sc: Scene) -> None:
    """`image`: size, samples and depth (never keyed: one library and one buffer serve every frame)."""
    sc.width = ctx.whole("image.width", img.get("width", sc.width), 1, MAX_SIZE)
    sc.height = ctx.whole("image.height", img.get("height", sc.height), 1, MAX_SIZE)
    sc.spp = ctx.whole("image.spp", img.get("spp", sc.spp), 1, MAX_SPP)
    sc.max_depth = ctx.whole("image.max_depth", img.get("max_depth", sc.max_depth), 0, MAX_DEPTH)


def _camera(ctx: Reader, cam: dict) -> Camera:
    """`camera`: where it is and looks (or its orbit), which way is up, the vertical field of view."""
    c = Camera()
    if "orbit" in cam:
        c.position, c.look_at = keys.orbit_camera(ctx, cam)
    if "position" in cam:
        c.position = ctx.vec("camera.position", cam["position"])
    if "look_at" in cam:
        c.look_at = ctx.vec("camera.look_at", cam["look_at"])
    if "up" in cam:
        c.up = ctx.vec("camera.up", cam["up"])
    if "fov" in cam:
        c.fov = ctx.num("camera.fov", cam["fov"], 0.0, 179.0, lo_open=True)
    view = np.subtract(c.look_at, c.position)
    if not np.linalg.norm(view) > 0:
        raise ctx.fail("camera.look_at", "must differ from camera.position")
    if not np.linalg.norm(np.cross(view, c.up)) > 1e-9 * np.linalg.norm(view) * np.linalg.norm(c.up):
        raise ctx.fail("camera.up", "must not be zero or parallel to the viewing direction")
    return c


def _lights(ctx: Reader, lights: Any) -> list[Light]:
    """`lights`: point lights, colour times intensity."""
    if not isinstance(lights, list):
        raise ctx.fail("lights", "expected a list")
    out = []
    for i, raw in enumerate(lights):
        raw = ctx.mapping(f"lights[{i}]", raw, LIGHT_KEYS)
        if "position" not in raw:
            raise ctx.fail(f"lights[{i}]", "missing key 'position'")
        col = ctx.color(f"lights[{i}].color", raw.get("color", [1, 1, 1]))
        k = ctx.num(f"lights[{i}].intensity", raw.get("intensity", 1.0), 0.0, INTENSITY_MAX)
        out.append(Light(ctx.vec(f"lights[{i}].position", raw["position"]), tuple(k * x for x in col)))
    return out


def _check_objects(ctx: Reader, objects: list[Node]) -> None:
    """What holds only for a whole object: the tracer's CSG depth, and each leaf's final matrix."""
    for i, obj in enumerate(objects):
        if i in ctx.reused:  # checked on the first frame
            continue
        if depth(obj) > MAX_CSG_DEPTH:  # cannot happen within the documented limits; the tracer's own
            raise ctx.fail(getattr(obj, "where", "objects"), f"CSG tree deeper than {MAX_CSG_DEPTH}")
        for leaf in Scene(source="", objects=[obj]).leaves():
            tf.check_matrix(ctx.source, f"{leaf.where}.transform", leaf.matrix)


def load_scene(path: str | Path) -> Scene:
    path = Path(path)
    return parse_scene(read_yaml(path, what="scene"), path)
