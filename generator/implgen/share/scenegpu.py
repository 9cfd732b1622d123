"""A scene's GLSL program (implgen.codegen.backends.glsl.scene) from the scene model the C build uses.

The shapes are the C build's (implgen.scene.build.plan_shapes with folding: one per distinct spec and param
values, the values folded in as constants, names made unique), each generated for GLSL; the leaves, CSG nodes,
materials and lights are read from the same `Scene` the C tracer is filled from (scene/tracer.py: a leaf's
material is its own or the nearest CSG node's above it; the world boxes as runtime_c/tracer_scene.c builds
them, a leaf's from its spec's box cut by its clip). No second scene reader: a scene file is read by
implgen.scene.load, and this module only lays out what it gives.
"""

from __future__ import annotations

import numpy as np

from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.scene import (
    CLIP_KINDS,
    OPS,
    SceneLeaf,
    SceneMaterial,
    SceneObject,
    SceneTables,
    scene_program,
)
from implgen.codegen.emit import generate
from implgen.scene.build import plan_shapes
from implgen.scene.model import Leaf, Material, Node, Scene

BOX_PAD = 1e-6  # of a world box's size, and absolutely: float's clip of it must not cut the object


def leaf_object_box(leaf: Leaf) -> tuple[np.ndarray, np.ndarray]:
    """The object-space box of what the leaf shows (tracer_scene.c leaf_box): its spec's box, cut by its clip's
    cube; +-inf where neither bounds it."""
    lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
    box = leaf.spec.box(leaf.params)
    if box is not None:
        lo, hi = np.array(box[:3], float), np.array(box[3:], float)
    if leaf.clip is not None:
        c, r = np.array(leaf.clip.center, float), float(leaf.clip.size)
        lo, hi = np.maximum(lo, c - r), np.minimum(hi, c + r)
    return lo, hi


def world_box(matrix: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The world box of an object-space box under a 3x4 map, by interval arithmetic (an infinite side stays
    infinite where the map uses that axis), padded by BOX_PAD."""
    wlo, whi = matrix[:, 3].astype(float).copy(), matrix[:, 3].astype(float).copy()
    for i in range(3):
        for j in range(3):
            m = float(matrix[i, j])
            if m == 0.0:
                continue
            a, b = m * lo[j], m * hi[j]
            wlo[i] += min(a, b)
            whi[i] += max(a, b)
    pad = BOX_PAD * (np.where(np.isfinite(wlo), np.abs(wlo), 0) + np.where(np.isfinite(whi), np.abs(whi), 0) + 1)
    return wlo - pad, whi + pad


def _node_box(node: Node) -> tuple[np.ndarray, np.ndarray]:
    """tracer_scene.c node_box: a union's boxes joined, an intersection's met, a difference its left's."""
    if isinstance(node, Leaf):
        return world_box(np.asarray(node.matrix, float), *leaf_object_box(node))
    (llo, lhi), (rlo, rhi) = _node_box(node.left), _node_box(node.right)
    if node.op == "union":
        return np.minimum(llo, rlo), np.maximum(lhi, rhi)
    if node.op == "intersection":
        return np.maximum(llo, rlo), np.minimum(lhi, rhi)
    return llo, lhi


def material_row(m: Material) -> SceneMaterial:
    inside = m.inside if m.inside is not None else (0.0, 0.0, 0.0)
    return SceneMaterial(
        color=tuple(m.color),
        color2=tuple(m.color2),
        inside=tuple(inside),
        two_sided=m.two_sided,
        absorption=tuple(m.absorption),
        surface=(m.ambient, m.diffuse, m.specular, m.shininess),
        optics=(m.reflectivity, m.transparency, m.ior, m.checker_scale),
    )


class _Layout:
    """The tables filled one object at a time, in the order the C tracer is filled (scene/tracer.py)."""

    def __init__(self, leaf_shape: dict[int, int]) -> None:
        self.leaf_shape = leaf_shape
        self.leaves: list[SceneLeaf] = []
        self.nodes: list[tuple[int, int]] = []
        self.materials: list[SceneMaterial] = []
        self.material_index: dict[int, int] = {}

    def material(self, m: Material) -> int:
        if id(m) not in self.material_index:
            self.material_index[id(m)] = len(self.materials)
            self.materials.append(material_row(m))
        return self.material_index[id(m)]

    def leaf(self, leaf: Leaf, material: Material, above: tuple[np.ndarray, np.ndarray] | None) -> int:
        m = np.asarray(leaf.matrix, float).reshape(3, 4)
        inv = np.linalg.inv(m[:, :3])
        inverse = np.concatenate([inv, (-inv @ m[:, 3])[:, None]], 1)
        clip_kind, clip = 0, (0.0, 0.0, 0.0, 0.0)
        if leaf.clip is not None:
            clip_kind, clip = CLIP_KINDS[leaf.clip.kind], (*map(float, leaf.clip.center), float(leaf.clip.size))
        lo, hi = above if above is not None else (np.full(3, -np.inf), np.full(3, np.inf))
        self.leaves.append(
            SceneLeaf(
                shape=self.leaf_shape[id(leaf)],
                inverse=tuple(float(v) for v in inverse.reshape(-1)),
                material=self.material(leaf.material or material),
                above_lo=tuple(map(float, lo)),
                above_hi=tuple(map(float, hi)),
                clip_kind=clip_kind,
                clip=clip,
            )
        )
        return len(self.leaves) - 1

    def post_order(self, node: Node, material: Material, above) -> int:
        """The node's subtree into the node table, children first; returns the span lists it holds at once."""
        if isinstance(node, Leaf):
            self.nodes.append((0, self.leaf(node, material, above)))
            return 1
        mat = node.material or material
        lo, hi = _node_box(node)
        box = (lo, hi) if above is None else (np.maximum(above[0], lo), np.minimum(above[1], hi))
        left = self.post_order(node.left, mat, box)
        right = self.post_order(node.right, mat, box)
        self.nodes.append((OPS[node.op], -1))
        return max(left, 1 + right)

    def object(self, node: Node, default: Material) -> tuple[SceneObject, int]:
        first = len(self.nodes)
        surface = isinstance(node, Leaf)
        stack = self.post_order(node, default, None)
        lo, hi = _node_box(node)
        flat = surface and node.spec.degree == 1
        obj = SceneObject(first, len(self.nodes) - first, surface, flat, tuple(map(float, lo)), tuple(map(float, hi)))
        return obj, stack


def scene_tables(scene: Scene) -> SceneTables:
    """The scene laid out for the GLSL scene tracer."""
    entries, leaf_index = plan_shapes(scene, fold=True)
    shapes = []
    for entry in entries:
        spec = entry.spec
        shapes.append((glsl_name(spec.name), generate(spec, ("glsl",))[f"{spec.name}.glsl"]))
    layout = _Layout(leaf_index)
    default = Material()
    objects, stack = [], 1
    for node in scene.objects:
        obj, depth = layout.object(node, default)
        objects.append(obj)
        stack = max(stack, depth)
    return SceneTables(
        shapes=shapes,
        leaves=layout.leaves,
        nodes=layout.nodes,
        objects=objects,
        materials=layout.materials,
        lights=[(tuple(map(float, li.position)), tuple(map(float, li.color))) for li in scene.lights],
        background=tuple(map(float, scene.background)),
        max_depth=scene.max_depth,
        csg_stack=stack,
    )


def scene_fragment(scene: Scene, target: str = "es") -> str:
    """The scene's whole fragment shader (uniforms: ig_scene_size, _eye, _look, _up, _fov, _mark, _output)."""
    return scene_program(scene_tables(scene), target)


def camera_uniforms(scene: Scene, size: tuple[int, int], output: int = 0, mark: bool = True) -> dict[str, list]:
    """The scene's camera and the picture's size as the program's uniforms, the camera's basis worked out in
    double as runtime_c/tracer_render.c (and implgen.scene.camera) does; output 1: each pixel's colour
    unclamped and, in alpha, 2 (object + 1) + its flag (`decode`)."""
    cam = scene.camera
    eye = np.asarray(cam.position, float)
    w = eye - np.asarray(cam.look_at, float)
    w /= np.sqrt(w @ w)
    u = np.cross(np.asarray(cam.up, float), w)
    if not u @ u > 0.0:  # up along the view: any perpendicular, as the tracer takes
        u = np.cross([0.0, 1.0, 0.0] if abs(w[0]) > 0.9 else [1.0, 0.0, 0.0], w)
    u /= np.sqrt(u @ u)
    v = np.cross(w, u)
    tan_half = np.tan(0.5 * cam.fov * np.pi / 180.0)
    return {
        "ig_scene_size": [float(size[0]), float(size[1])],
        "ig_scene_eye": [float(x) for x in eye],
        "ig_scene_right": [float(x) for x in u * tan_half * (size[0] / size[1])],
        "ig_scene_upv": [float(x) for x in v * tan_half],
        "ig_scene_back": [float(x) for x in w],
        "ig_scene_mark": [float(mark)],
        "ig_scene_output": [float(output)],
    }


def decode(pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Output 1's float pixels (h, w, 4) as drawn (row 0 at the bottom) -> (colour (h, w, 3), object of the camera
    ray's hit (-1: background), flag), row 0 at the top."""
    p = pixels[::-1]
    code = np.rint(p[..., 3]).astype(int)
    return p[..., :3], code // 2 - 1, (code & 1) != 0
