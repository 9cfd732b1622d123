"""A whole scene as one GLSL program: the scene's shapes, its tables (leaves, CSG nodes in post-order, objects,
materials, lights) and the scene tracer written once (templates/glsl/scene.glsl.j2, scene_trace.glsl.j2).

This module takes plain data (`SceneTables`), as program.py takes plain strings: the scene model is read by
implgen.share.scenegpu, above this floor, which fills the tables from the model the C build uses
(implgen.scene.build.plan_shapes: one shape per distinct spec and param values, the values folded in). Every
number is printed as a GLSL float literal (repr of a finite float; an infinite bound as +-1e30, the runtime's
open side); no text from a scene file reaches the program but the shapes' own generated GLSL.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.templating import environment

OPEN = 1.0e30  # clip.glsl IG_OPEN: a bound at or beyond it is an open side
OPS = {"union": 1, "intersection": 2, "difference": 3}  # scene_trace.glsl.j2 IG_SCENE_UNION, ...
CLIP_KINDS = {"sphere": 1, "box": 2}

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class SceneLeaf:
    shape: int  # index into SceneTables.shapes
    inverse: tuple[float, ...]  # the world -> object map, 3x4 by rows
    material: int
    above_lo: Vec3 = (-OPEN,) * 3  # a CSG leaf: the world boxes of the nodes above it, intersected
    above_hi: Vec3 = (OPEN,) * 3
    clip_kind: int = 0  # a surface: 0 none, 1 sphere, 2 box (CLIP_KINDS), in object space
    clip: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)  # its centre and size


@dataclass(frozen=True)
class SceneObject:
    first: int  # its nodes in SceneTables.nodes, in post-order
    count: int
    surface: bool  # a top-level leaf: a surface, its first root is the hit (else a CSG solid's spans)
    flat: bool  # a plane (degree 1): a ray leaving it need not test it again
    lo: Vec3
    hi: Vec3


@dataclass(frozen=True)
class SceneMaterial:
    color: Vec3
    color2: Vec3
    inside: Vec3
    two_sided: float
    absorption: Vec3
    surface: tuple[float, float, float, float]  # ambient, diffuse, specular, shininess
    optics: tuple[float, float, float, float]  # reflectivity, transparency, ior, checker scale


@dataclass(frozen=True)
class SceneTables:
    shapes: Sequence[tuple[str, str]]  # (prefix of its GLSL identifiers, its generated GLSL)
    leaves: Sequence[SceneLeaf]
    nodes: Sequence[tuple[int, int]]  # (op: 0 a leaf, else OPS's, leaf index or -1), each object's in post-order
    objects: Sequence[SceneObject]
    materials: Sequence[SceneMaterial]
    lights: Sequence[tuple[Vec3, Vec3]]  # (position, colour x intensity)
    background: Vec3
    max_depth: int
    csg_stack: int  # span lists a post-order evaluation holds at once: the deepest CSG tree + 1


def number(v: float) -> str:
    """A GLSL float literal: repr of the float (round-trip), an infinity as +-OPEN."""
    v = float(v)
    if math.isnan(v):
        raise ValueError("NaN in a scene table")
    if not math.isfinite(v) or abs(v) >= OPEN:
        return "1.0e30" if v > 0 else "-1.0e30"
    text = repr(v)
    return text if any(c in text for c in ".e") else text + ".0"


def _vec(values: Sequence[float]) -> str:
    return f"vec{len(values)}({', '.join(number(v) for v in values)})"


def _array(kind: str, items: Sequence[str], filler: str) -> str:
    """A const array's initialiser; GLSL has no empty arrays, so an empty table holds one unused `filler`."""
    items = list(items) or [filler]
    return f"{kind}[{len(items)}]({', '.join(items)})"


def _tables(t: SceneTables) -> dict[str, str]:
    leaves, objects, mats = t.leaves, t.objects, t.materials
    rows = [[_vec(leaf.inverse[4 * r : 4 * r + 4]) for leaf in leaves] for r in range(3)]
    zero3, zero4 = "vec3(0.0)", "vec4(0.0)"
    return {
        "shape_of_leaf": _array("int", [str(leaf.shape) for leaf in leaves], "0"),
        "leaf_minv0": _array("vec4", rows[0], zero4),
        "leaf_minv1": _array("vec4", rows[1], zero4),
        "leaf_minv2": _array("vec4", rows[2], zero4),
        "leaf_material": _array("int", [str(leaf.material) for leaf in leaves], "0"),
        "leaf_wlo": _array("vec3", [_vec(leaf.above_lo) for leaf in leaves], zero3),
        "leaf_whi": _array("vec3", [_vec(leaf.above_hi) for leaf in leaves], zero3),
        "leaf_clip_kind": _array("int", [str(leaf.clip_kind) for leaf in leaves], "0"),
        "leaf_clip": _array("vec4", [_vec(leaf.clip) for leaf in leaves], zero4),
        "node_op": _array("int", [str(op) for op, _ in t.nodes], "0"),
        "node_leaf": _array("int", [str(leaf) for _, leaf in t.nodes], "0"),
        "object_first": _array("int", [str(o.first) for o in objects], "0"),
        "object_count": _array("int", [str(o.count) for o in objects], "0"),
        "object_surface": _array("int", [str(int(o.surface)) for o in objects], "0"),
        "object_flat": _array("int", [str(int(o.flat)) for o in objects], "0"),
        "object_lo": _array("vec3", [_vec(o.lo) for o in objects], zero3),
        "object_hi": _array("vec3", [_vec(o.hi) for o in objects], zero3),
        "mat_color": _array("vec3", [_vec(m.color) for m in mats], zero3),
        "mat_color2": _array("vec3", [_vec(m.color2) for m in mats], zero3),
        "mat_inside": _array("vec3", [_vec(m.inside) for m in mats], zero3),
        "mat_two_sided": _array("float", [number(m.two_sided) for m in mats], "0.0"),
        "mat_absorption": _array("vec3", [_vec(m.absorption) for m in mats], zero3),
        "mat_surface": _array("vec4", [_vec(m.surface) for m in mats], zero4),
        "mat_optics": _array("vec4", [_vec(m.optics) for m in mats], zero4),
        "light_pos": _array("vec3", [_vec(p) for p, _ in t.lights], zero3),
        "light_color": _array("vec3", [_vec(c) for _, c in t.lights], zero3),
    }


def scene_text(t: SceneTables, live_lights: int = 0) -> str:
    """The scene's part of the program: its tables, the shapes' dispatch, then the scene tracer. `live_lights` > 0:
    the viewer's program, whose lights (up to that many; the tables' are not used) and background are uniforms
    the page sets (ig_light_pos, ig_light_color, ig_scene_nlights, ig_scene_background)."""
    if live_lights < 0:
        raise ValueError("live_lights must be >= 0")
    counts = {
        "leaves": len(t.leaves),
        "nodes": len(t.nodes),
        "objects": len(t.objects),
        "lights": int(live_lights) if live_lights else len(t.lights),
        "max_depth": int(t.max_depth),
        "csg_stack": max(1, int(t.csg_stack)),
    }
    return (
        environment()
        .get_template("glsl/scene.glsl.j2")
        .render(
            tables=_tables(t),
            counts=counts,
            background=_vec(t.background),
            prefixes=[prefix for prefix, _ in t.shapes],
            live_lights=int(live_lights),
        )
    )


def scene_program(t: SceneTables, target: str = "es", live_lights: int = 0) -> str:
    """A whole fragment shader: header, the runtime, the scene's shapes, its tables and the scene tracer
    (`live_lights`: scene_text's)."""
    if target not in HEADERS:
        raise ValueError(f"target must be one of {sorted(HEADERS)}, not {target!r}")
    shapes = "".join(text + "\n" for _, text in t.shapes)
    return HEADERS[target] + runtime_text() + shapes + scene_text(t, live_lights)
