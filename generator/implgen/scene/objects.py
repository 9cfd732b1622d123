"""Objects in a scene file: shapes (a spec file or an inline equation, with params, a transform and a
material) and CSG operations over them, as the binary tree the tracer takes."""

from __future__ import annotations

import heapq
import os
from pathlib import Path
from typing import Any

import numpy as np

from implgen import validate
from implgen.errors import UserError
from implgen.scene import keys
from implgen.scene import transform as tf
from implgen.scene.materials import material_ref
from implgen.scene.model import CLIP_KINDS, Clip, Csg, Leaf, Material, Node
from implgen.scene.model import depth as node_depth
from implgen.scene.reader import Reader, given
from implgen.spec.entry import load_spec, parse_spec

MAX_CSG_NESTING = 32  # CSG operations nested inside each other, as written in the scene
MAX_CSG_CHILDREN = 1024  # objects in one CSG list (a list becomes a balanced binary tree)
MAX_OBJECTS = 10_000  # shapes placed in one scene, CSG operands included (each is one BVH leaf)
CSG_OPS = ("union", "intersection", "difference")
LEAF_KEYS = ("shape", "equation", "name", "params", "bounds", "ranges", "transform", "material", "clip")
CLIP_KEYS = (*CLIP_KINDS, "center")


def _resolve_shape_path(ctx: Reader, key: str, value: Any) -> Path:
    if not isinstance(value, str) or not value.strip() or "\0" in value:
        raise ctx.fail(key, "expected the path of a spec file")
    if value not in ctx.resolved:
        ctx.resolved[value] = _find_spec_file(ctx, key, Path(value))
    return ctx.resolved[value]


def _find_spec_file(ctx: Reader, key: str, p: Path) -> Path:
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


def _leaf(ctx: Reader, key: str, raw: dict, named: dict[str, Material]) -> Leaf:
    ctx.mapping(key, raw, LEAF_KEYS)
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
        for k in ("name", "bounds", "ranges"):
            if k in raw:
                raise ctx.fail(f"{key}.{k}", "only for an inline 'equation' (a spec file has its own)")
        path = _resolve_shape_path(ctx, f"{key}.shape", raw["shape"])
        if path not in ctx.spec_cache:
            ctx.count_shape(f"{key}.shape")
            try:
                ctx.spec_cache[path] = load_spec(path, cache=True)
            except UserError as err:  # the spec file's own message, after the scene's key that names it
                raise ctx.fail(f"{key}.shape", str(err)) from None
        spec = ctx.spec_cache[path]
        overrides = given(raw, "params", {})
    else:
        ctx.count_shape(f"{key}.equation")
        ctx.inline_count += 1
        mapping = {"name": raw.get("name", f"inline{ctx.inline_count}"), "equation": raw["equation"]}
        for k in ("bounds", "ranges"):  # ranges: a slider's span per param (the viewer's saved view keeps them)
            if k in raw:
                mapping[k] = raw[k]
        overrides: Any = {}
        if "params" in raw:
            mapping["params"], overrides = keys.inline_params(ctx, f"{key}.params", raw["params"])
        memo_key = f"{ctx.inline_count}:{mapping!r}"  # the same inline shape on every frame
        if memo_key not in ctx.inline_specs:
            ctx.inline_specs[memo_key] = parse_spec(mapping, f"{ctx.source}: {key}", cache=True)
        spec = ctx.inline_specs[memo_key]
    if not isinstance(overrides, dict):
        raise ctx.fail(f"{key}.params", "expected a mapping name -> number")
    params = dict(spec.params)
    for name, v in overrides.items():
        if name not in spec.params:
            known = ", ".join(spec.params) or "none"
            where = f"{key}.params.{name}" if isinstance(name, str) and name.isidentifier() else f"{key}.params"
            raise ctx.fail(where, f"shape {spec.name!r} has no param {validate.describe(name)} (params: {known})")
        params[name] = ctx.num(f"{key}.params.{name}", v)
    if overrides:
        spec.check_values(params, ctx.source, f"{key}.params")
    m = tf.parse_transform(ctx.source, f"{key}.transform", ctx.resolve(f"{key}.transform", raw.get("transform")))
    mat = material_ref(ctx, f"{key}.material", raw["material"], named) if "material" in raw else None
    clip = _clip(ctx, f"{key}.clip", raw["clip"]) if "clip" in raw else None
    return Leaf(spec=spec, params=params, matrix=m, material=mat, where=key, clip=clip)


def _clip(ctx: Reader, key: str, raw: Any) -> Clip:
    """`clip: {sphere: R}` or `{box: H}`, optional `center: [x, y, z]` (object space; default the origin)."""
    raw = ctx.mapping(key, raw, CLIP_KEYS)
    kinds = [k for k in CLIP_KINDS if k in raw]
    if len(kinds) != 1:
        raise ctx.fail(key, f"give exactly one of {', '.join(CLIP_KINDS)} (its radius or half-edge)")
    size = ctx.num(f"{key}.{kinds[0]}", raw[kinds[0]], 1e-9, 1e9)
    center = ctx.vec(f"{key}.center", raw["center"], -1e9, 1e9) if "center" in raw else (0.0, 0.0, 0.0)
    return Clip(kind=kinds[0], size=size, center=center)


def _node(ctx: Reader, key: str, raw: Any, named: dict[str, Material], depth: int) -> Node:
    if not isinstance(raw, dict):
        raise ctx.fail(key, "expected a mapping (a shape, an inline equation or a CSG operation)")
    ops = [op for op in CSG_OPS if op in raw]
    if not ops:
        leaf = _leaf(ctx, key, raw, named)
        if depth > 0 and leaf.clip is not None:
            raise ctx.fail(f"{key}.clip", "only for a top-level shape (a CSG intersection cuts a solid)")
        return leaf
    if len(ops) > 1:
        raise ctx.fail(key, f"one CSG operation per node (found {', '.join(ops)})")
    op = ops[0]
    ctx.mapping(key, raw, (op, "material", "transform"))
    if depth >= MAX_CSG_NESTING:
        raise ctx.fail(key, f"CSG operations nested more than {MAX_CSG_NESTING} deep as written")
    kids = raw[op]
    if not isinstance(kids, list) or not 2 <= len(kids) <= MAX_CSG_CHILDREN:
        raise ctx.fail(f"{key}.{op}", f"expected a list of 2 to {MAX_CSG_CHILDREN} objects")
    children = [_node(ctx, f"{key}.{op}[{i}]", k, named, depth + 1) for i, k in enumerate(kids)]
    mat = material_ref(ctx, f"{key}.material", raw["material"], named) if "material" in raw else None
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


def parse_object(ctx: Reader, i: int, raw: Any, named: dict[str, Material], fixed: dict | None) -> Node:
    """objects[i]; one with no keyed value is parsed on the first frame only and shared by later frames."""
    if fixed is not None and i not in fixed and not keys.contains_keyed(raw, ctx.source, f"objects[{i}]"):
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
    heap = [(node_depth(n), i, n) for i, n in enumerate(nodes)]
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
