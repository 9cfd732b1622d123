"""Scene files: YAML -> the validated scene model (scene/model.py). The format is documented in
docs/formats.md.

Every error is a UserError naming the scene file and the key at fault (`objects[2].transform.rotate`), so
the CLI prints one line and exits with status 2 before anything is compiled or written.
"""

from __future__ import annotations

import heapq
import os
from pathlib import Path
from typing import Any

import numpy as np

from implgen import abi, validate
from implgen.codegen.speccache import load_spec, parse_spec  # codegen.spec's, cached by content
from implgen.codegen.specmodel import Spec
from implgen.errors import UserError
from implgen.scene import keys
from implgen.scene import transform as tf
from implgen.scene.model import Camera, Csg, Leaf, Light, Material, Node, Scene, depth
from implgen.yamlfile import read_yaml

MAX_CSG_DEPTH = abi.value("RT_MAX_CSG_DEPTH")  # depth of the binary tree the tracer takes
MAX_CSG_NESTING = 32  # CSG operations nested inside each other, as written in the scene
MAX_CSG_CHILDREN = 1024  # objects in one CSG list (a list becomes a balanced binary tree)
MAX_SHAPES = 256  # distinct shapes (spec files and inline equations) in one scene
MAX_OBJECTS = 10_000  # shapes placed in one scene, CSG operands included (each is one BVH leaf)
MAX_DEPTH = abi.value("RT_MAX_DEPTH")
MAX_SPP = abi.value("RT_MAX_SPP")
MAX_SIZE = 16384  # image width and height
CSG_OPS = ("union", "intersection", "difference")

# Documented ranges of colours and material terms ([lo, hi]; lengths and positions use
# validate.MAX_COORDINATE). Light colour x intensity stays below 100 x 1e4.
COLOR_MAX = 100.0
INTENSITY_MAX = 1e4
MATERIAL_RANGES = {
    "ambient": (0.0, 100.0),
    "diffuse": (0.0, 100.0),
    "specular": (0.0, 100.0),
    "shininess": (0.0, 1e4),
    "reflectivity": (0.0, 1.0),
    "transparency": (0.0, 1.0),
}
IOR_MAX = 10.0
ABSORPTION_MAX = 1e6


# ----------------------------------------------------------------------------------------------- helpers

TOP_KEYS = ("image", "camera", "background", "lights", "materials", "objects", "animation")
IMAGE_KEYS = ("width", "height", "spp", "max_depth")
CAMERA_KEYS = ("position", "look_at", "up", "fov", "orbit")
LIGHT_KEYS = ("position", "color", "intensity")
MATERIAL_KEYS = (
    "color",
    "checker",
    "ambient",
    "diffuse",
    "specular",
    "shininess",
    "reflectivity",
    "transparency",
    "ior",
    "absorption",
    "inside",
)
LEAF_KEYS = ("shape", "equation", "name", "params", "bounds", "transform", "material")


class _Ctx:
    def __init__(self, path: Path, frame: int, memo: dict | None):
        self.path = path
        self.source = str(path)
        memo = {} if memo is None else memo  # shared by the frames of one animation: specs are read once
        self.spec_cache: dict[Path, Spec] = memo.setdefault("specs", {})
        self.resolved: dict[str, Path] = memo.setdefault("paths", {})  # `shape:` text -> spec file
        self.inline_specs: dict[str, Spec] = memo.setdefault("inline", {})
        self.inline_count = 0
        self.leaves = 0
        self.frame = frame
        self.frames: int | None = None  # the animation's frame count; None without an `animation` block
        self.keyed: list[str] = []  # key paths of the values that change with the frame
        self.keyed_cache: dict = memo.setdefault("keyed", {})  # keyed mappings parsed and checked once
        self.static: dict[int, tuple] = memo.setdefault("static", {})  # objects the same on every frame
        self.reused: set[int] = set()  # objects[i] taken from `static` on this frame

    def resolve(self, key: str, raw: Any) -> Any:
        """A part of the scene made only of numbers (a transform), with keyed values at this frame."""
        return keys.resolve(self.source, key, raw, self.frame, self.frames, self.keyed, self.keyed_cache)

    def fail(self, key: str, msg: str) -> UserError:
        return UserError(self.source, f"{key}: {msg}")

    def count_shape(self, key: str) -> None:
        if self.inline_count + len(self.spec_cache) >= MAX_SHAPES:
            raise self.fail(key, f"more than {MAX_SHAPES} distinct shapes in one scene")


def _given(raw: dict, key: str, default: Any) -> Any:
    """raw[key], or `default` when the key is left out or empty (`lights:`); `0` or `[]` where a mapping
    belongs is an error the caller reports, not a default."""
    value = raw.get(key)
    return default if value is None else value


def _mapping(ctx: _Ctx, key: str, value: Any, allowed: tuple[str, ...]) -> dict:
    return validate.mapping(ctx.source, key, value, allowed)


def _num(
    ctx: _Ctx,
    key: str,
    value: Any,
    lo: float = -validate.MAX_COORDINATE,
    hi: float = validate.MAX_COORDINATE,
    lo_open: bool = False,
) -> float:
    def check(k: str, v: Any) -> float:
        return validate.number(ctx.source, k, v, lo, hi, lo_open=lo_open)

    return keys.number_at(ctx.source, key, value, ctx.frame, ctx.frames, check, ctx.keyed, ctx.keyed_cache)


def _int(ctx: _Ctx, key: str, value: Any, lo: int, hi: int) -> int:
    if keys.is_keyed(value):
        raise ctx.fail(key, "cannot be keyed (it is the same on every frame)")
    return validate.whole(ctx.source, key, value, lo, hi)


def _vec(
    ctx: _Ctx, key: str, value: Any, lo: float = -validate.MAX_COORDINATE, hi: float = validate.MAX_COORDINATE
) -> tuple[float, float, float]:
    if keys.is_keyed(value):
        raise ctx.fail(key, "key each of the three numbers on its own: [x, {keys: ...}, z]")
    if isinstance(value, (list, tuple)) and len(value) == 3:
        value = [_num(ctx, f"{key}[{i}]", v, lo, hi) for i, v in enumerate(value)]
    return validate.vector(ctx.source, key, value, lo, hi)


def _color(ctx: _Ctx, key: str, value: Any) -> tuple[float, float, float]:
    return _vec(ctx, key, value, 0.0, COLOR_MAX)


def _material(ctx: _Ctx, key: str, raw: Any) -> Material:
    raw = _mapping(ctx, key, raw, MATERIAL_KEYS)
    m = Material()
    if "color" in raw:
        m.color = _color(ctx, f"{key}.color", raw["color"])
    if "checker" in raw:
        ch = _mapping(ctx, f"{key}.checker", raw["checker"], ("colors", "scale"))
        cols = ch.get("colors")
        if not isinstance(cols, list) or len(cols) != 2:
            raise ctx.fail(f"{key}.checker.colors", "expected two colours")
        m.color = _color(ctx, f"{key}.checker.colors[0]", cols[0])
        m.color2 = _color(ctx, f"{key}.checker.colors[1]", cols[1])
        m.checker_scale = _num(ctx, f"{key}.checker.scale", ch.get("scale", 1.0), 0.0, lo_open=True)
    for k, (lo, hi) in MATERIAL_RANGES.items():
        if k in raw:
            setattr(m, k, _num(ctx, f"{key}.{k}", raw[k], lo, hi))
    if "ior" in raw:
        m.ior = _num(ctx, f"{key}.ior", raw["ior"], 0.0, IOR_MAX, lo_open=True)
    if "absorption" in raw:
        m.absorption = _vec(ctx, f"{key}.absorption", raw["absorption"], 0.0, ABSORPTION_MAX)
    if "inside" in raw:  # two-sided: the colour of the back (f < 0) side of a surface
        m.inside = _color(ctx, f"{key}.inside", raw["inside"])
    return m


def _material_ref(ctx: _Ctx, key: str, raw: Any, named: dict[str, Material]) -> Material:
    if isinstance(raw, str):
        if raw not in named:
            known = ", ".join(sorted(named)) or "none defined"
            raise ctx.fail(key, f"no material named {validate.describe(raw)} (materials: {known})")
        return named[raw]
    return _material(ctx, key, raw)


def _resolve_shape_path(ctx: _Ctx, key: str, value: Any) -> Path:
    if not isinstance(value, str) or not value.strip() or "\0" in value:
        raise ctx.fail(key, "expected the path of a spec file")
    if value not in ctx.resolved:
        ctx.resolved[value] = _find_spec_file(ctx, key, Path(value))
    return ctx.resolved[value]


def _find_spec_file(ctx: _Ctx, key: str, p: Path) -> Path:
    candidates = [p] if p.is_absolute() else [ctx.path.parent / p, Path.cwd() / p]
    try:
        for c in candidates:
            if c.exists():
                return c.resolve()  # whatever it is: read_yaml says what is wrong with it
            if os.path.lexists(c):
                raise ctx.fail(key, f"{c} is a link to nothing (a missing target or a loop of links)")
    except (OSError, RuntimeError) as err:  # a name too long, a loop of links
        raise ctx.fail(key, f"cannot use this path ({getattr(err, 'strerror', None) or err})") from None
    tried = " or ".join(str(c) for c in candidates)
    raise ctx.fail(key, f"spec file not found (tried {tried})")


def _leaf(ctx: _Ctx, key: str, raw: dict, named: dict[str, Material]) -> Leaf:
    _mapping(ctx, key, raw, LEAF_KEYS)
    ctx.leaves += 1
    if ctx.leaves > MAX_OBJECTS:
        raise ctx.fail(key, f"more than {MAX_OBJECTS} objects in one scene (CSG operands count)")
    if ("shape" in raw) == ("equation" in raw):
        raise ctx.fail(
            key,
            "give exactly one of 'shape' (a spec file) or 'equation' (an inline shape), "
            f"or a CSG operation ({', '.join(CSG_OPS)})",
        )
    if "shape" in raw:
        for k in ("name", "bounds"):
            if k in raw:
                raise ctx.fail(f"{key}.{k}", "only for an inline 'equation' (a spec file has its own)")
        path = _resolve_shape_path(ctx, f"{key}.shape", raw["shape"])
        if path not in ctx.spec_cache:
            ctx.count_shape(f"{key}.shape")
            try:
                ctx.spec_cache[path] = load_spec(path)
            except UserError as err:  # the spec file's own message, after the scene's key that names it
                raise ctx.fail(f"{key}.shape", str(err)) from None
        spec = ctx.spec_cache[path]
        overrides = _given(raw, "params", {})
    else:
        ctx.count_shape(f"{key}.equation")
        ctx.inline_count += 1
        mapping = {"name": raw.get("name", f"inline{ctx.inline_count}"), "equation": raw["equation"]}
        if "bounds" in raw:
            mapping["bounds"] = raw["bounds"]
        overrides: Any = {}
        if "params" in raw:
            mapping["params"], overrides = keys.inline_params(
                ctx.source, f"{key}.params", raw["params"], ctx.frames, ctx.keyed_cache
            )
        memo_key = f"{ctx.inline_count}:{mapping!r}"  # the same inline shape on every frame
        if memo_key not in ctx.inline_specs:
            ctx.inline_specs[memo_key] = parse_spec(mapping, f"{ctx.source}: {key}")
        spec = ctx.inline_specs[memo_key]
    if not isinstance(overrides, dict):
        raise ctx.fail(f"{key}.params", "expected a mapping name -> number")
    params = dict(spec.params)
    for name, v in overrides.items():
        if name not in spec.params:
            known = ", ".join(spec.params) or "none"
            where = f"{key}.params.{name}" if isinstance(name, str) and name.isidentifier() else f"{key}.params"
            raise ctx.fail(where, f"shape {spec.name!r} has no param {validate.describe(name)} (params: {known})")
        params[name] = _num(ctx, f"{key}.params.{name}", v)
    if overrides:
        spec.check_values(params, ctx.source, f"{key}.params")
    m = tf.parse_transform(ctx.source, f"{key}.transform", ctx.resolve(f"{key}.transform", raw.get("transform")))
    mat = _material_ref(ctx, f"{key}.material", raw["material"], named) if "material" in raw else None
    return Leaf(spec=spec, params=params, matrix=m, material=mat, where=key)


def _node(ctx: _Ctx, key: str, raw: Any, named: dict[str, Material], depth: int) -> Node:
    if not isinstance(raw, dict):
        raise ctx.fail(key, "expected a mapping (a shape, an inline equation or a CSG operation)")
    ops = [op for op in CSG_OPS if op in raw]
    if not ops:
        return _leaf(ctx, key, raw, named)
    if len(ops) > 1:
        raise ctx.fail(key, f"one CSG operation per node (found {', '.join(ops)})")
    op = ops[0]
    _mapping(ctx, key, raw, (op, "material", "transform"))
    if depth >= MAX_CSG_NESTING:
        raise ctx.fail(key, f"CSG operations nested more than {MAX_CSG_NESTING} deep as written")
    kids = raw[op]
    if not isinstance(kids, list) or not 2 <= len(kids) <= MAX_CSG_CHILDREN:
        raise ctx.fail(f"{key}.{op}", f"expected a list of 2 to {MAX_CSG_CHILDREN} objects")
    children = [_node(ctx, f"{key}.{op}[{i}]", k, named, depth + 1) for i, k in enumerate(kids)]
    mat = _material_ref(ctx, f"{key}.material", raw["material"], named) if "material" in raw else None
    # difference [A, B, C] = A - (B u C); union and intersection lists become the shallowest binary tree
    if op == "difference":
        rest = children[1] if len(children) == 2 else _balanced("union", children[1:], key)
        node = Csg(op=op, left=children[0], right=rest, material=None, where=key)
    else:
        node = _balanced(op, children, key)
    node.material = mat
    if "transform" in raw:
        m = tf.parse_transform(ctx.source, f"{key}.transform", ctx.resolve(f"{key}.transform", raw["transform"]))
        _apply_transform(node, m)
    return node


def _object(ctx: _Ctx, i: int, raw: Any, named: dict[str, Material], fixed: dict | None) -> Node:
    """objects[i]; one with no keyed value is parsed on the first frame only and shared by later frames."""
    if fixed is not None and i not in fixed and not keys.contains_keyed(raw):
        leaves, inline = ctx.leaves, ctx.inline_count
        node = _node(ctx, f"objects[{i}]", raw, named, 0)
        fixed[i] = (node, ctx.leaves - leaves, ctx.inline_count - inline)
        return node
    if fixed is None or i not in fixed:
        return _node(ctx, f"objects[{i}]", raw, named, 0)
    node, leaves, inline = fixed[i]  # the same counts as on the first frame, which passed the limits
    ctx.reused.add(i)
    ctx.leaves += leaves
    ctx.inline_count += inline
    return node


def _balanced(op: str, nodes: list[Node], where: str) -> Csg:
    """One associative operation over a list as the shallowest binary tree: always join the two shallowest
    subtrees (Huffman's merge on depth), ties in list order. A long flat list stays a few levels deep."""
    heap = [(depth(n), i, n) for i, n in enumerate(nodes)]
    heapq.heapify(heap)
    order = len(nodes)
    while len(heap) > 1:
        _, i, a = heapq.heappop(heap)
        _, j, b = heapq.heappop(heap)
        left, right = (a, b) if i < j else (b, a)
        joined = Csg(op=op, left=left, right=right, material=None, where=where)
        heapq.heappush(heap, (joined.depth, order, joined))
        order += 1
    node = heap[0][2]
    assert isinstance(node, Csg)
    return node


def _apply_transform(node: Node, m: np.ndarray) -> None:
    """A transform on a CSG node moves every leaf below it (applied after the leaves' own)."""
    if isinstance(node, Leaf):
        node.matrix = tf.compose(m, node.matrix)
    else:
        _apply_transform(node.left, m)
        _apply_transform(node.right, m)


def parse_scene(data: Any, source: str | Path = "<scene>", *, frame: int = 0, memo: dict | None = None) -> Scene:
    """The scene at `frame` (0 for a still). `memo` carries the specs read for one frame to the next."""
    path = Path(source)
    ctx = _Ctx(path, frame, memo)
    if not isinstance(data, dict):
        raise UserError(ctx.source, "a scene must be a mapping with at least 'objects'")
    _mapping(ctx, "", data, TOP_KEYS)
    sc = Scene(source=ctx.source)
    if "animation" in data:
        sc.animation = keys.parse_animation(ctx.source, data["animation"])
        ctx.frames = sc.animation.frames
    if not 0 <= frame < sc.animation.frames:
        raise UserError(ctx.source, f"frame {frame} is outside [0, {sc.animation.frames - 1}]")
    img = _mapping(ctx, "image", _given(data, "image", {}), IMAGE_KEYS)
    sc.width = _int(ctx, "image.width", img.get("width", sc.width), 1, MAX_SIZE)
    sc.height = _int(ctx, "image.height", img.get("height", sc.height), 1, MAX_SIZE)
    sc.spp = _int(ctx, "image.spp", img.get("spp", sc.spp), 1, MAX_SPP)
    sc.max_depth = _int(ctx, "image.max_depth", img.get("max_depth", sc.max_depth), 0, MAX_DEPTH)
    cam = _mapping(ctx, "camera", _given(data, "camera", {}), CAMERA_KEYS)
    c = Camera()
    if "orbit" in cam:
        c.position, c.look_at = keys.orbit_camera(ctx.source, cam, ctx.frame, ctx.frames, ctx.keyed, ctx.keyed_cache)
    if "position" in cam:
        c.position = _vec(ctx, "camera.position", cam["position"])
    if "look_at" in cam:
        c.look_at = _vec(ctx, "camera.look_at", cam["look_at"])
    if "up" in cam:
        c.up = _vec(ctx, "camera.up", cam["up"])
    if "fov" in cam:
        c.fov = _num(ctx, "camera.fov", cam["fov"], 0.0, 179.0, lo_open=True)
    view = np.subtract(c.look_at, c.position)
    if not np.linalg.norm(view) > 0:
        raise ctx.fail("camera.look_at", "must differ from camera.position")
    if not np.linalg.norm(np.cross(view, c.up)) > 1e-9 * np.linalg.norm(view) * np.linalg.norm(c.up):
        raise ctx.fail("camera.up", "must not be zero or parallel to the viewing direction")
    sc.camera = c
    if "background" in data:
        sc.background = _color(ctx, "background", data["background"])
    lights = _given(data, "lights", [])
    if not isinstance(lights, list):
        raise ctx.fail("lights", "expected a list")
    for i, raw in enumerate(lights):
        raw = _mapping(ctx, f"lights[{i}]", raw, LIGHT_KEYS)
        if "position" not in raw:
            raise ctx.fail(f"lights[{i}]", "missing key 'position'")
        col = _color(ctx, f"lights[{i}].color", raw.get("color", [1, 1, 1]))
        k = _num(ctx, f"lights[{i}].intensity", raw.get("intensity", 1.0), 0.0, INTENSITY_MAX)
        sc.lights.append(Light(_vec(ctx, f"lights[{i}].position", raw["position"]), tuple(k * x for x in col)))
    named: dict[str, Material] = {}
    mats = _given(data, "materials", {})
    if not isinstance(mats, dict):
        raise ctx.fail("materials", "expected a mapping name -> material")
    for name, raw in mats.items():
        if not isinstance(name, str) or not 0 < len(name) <= 64 or not name.isprintable():
            raise ctx.fail(
                "materials", f"{validate.describe(name)} is not a material name (text, 1 to 64 printable characters)"
            )
        named[name] = _material(ctx, f"materials.{name}", raw)
    objs = data.get("objects")
    if not isinstance(objs, list) or not objs:
        raise ctx.fail("objects", "expected a non-empty list")
    fixed = ctx.static if not keys.contains_keyed(mats) else None  # no object can change with the frame
    sc.objects = [_object(ctx, i, raw, named, fixed) for i, raw in enumerate(objs)]
    sc.keyed = tuple(ctx.keyed)
    for i, obj in enumerate(sc.objects):
        if i in ctx.reused:  # checked on the first frame
            continue
        if depth(obj) > MAX_CSG_DEPTH:  # cannot happen within the documented limits; the tracer's own
            raise ctx.fail(getattr(obj, "where", "objects"), f"CSG tree deeper than {MAX_CSG_DEPTH}")
        for leaf in Scene(source="", objects=[obj]).leaves():
            tf.check_matrix(ctx.source, f"{leaf.where}.transform", leaf.matrix)
    return sc


def load_scene(path: str | Path) -> Scene:
    path = Path(path)
    return parse_scene(read_yaml(path, what="scene"), path)
