"""What the viewer shows, as validated values: the shape, its param values, the orbit camera and the options;
and the scene model built from them for the tracer.

Everything here comes from a parsed message (view/protocol.py) or a parsed file: the equation is a `Spec` from
the spec parser, numbers went through implgen.validate. Nothing typed by a user is kept as text.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import PurePath

import numpy as np

from implgen.errors import UserError
from implgen.scene.model import Camera, Clip, Csg, Leaf, Light, Material, Node, Scene
from implgen.share.page import MATERIAL  # the shape's material, both sides: the shared page's too
from implgen.spec.entry import parse_spec
from implgen.spec.paramrange import param_ranges
from implgen.spec.parse import Spec

CLIPS = ("none", "sphere", "box")
LIGHTS = ("studio", "headlight", "top", "scene")
# The light presets, the one statement of them: the server's picture (Document.lights) and the page's GPU
# preview (view/static/gpu.js, sent in the hello message) place the same lights. A light is `camera`: at
# target + 2 d (r right + u up + b back), moving with the orbit camera, or `world`: at target + d (x, y, z),
# fixed in the world; d is the camera's distance to its target. (The headlight is the eye: camera 0, 0, 0.5.)
LIGHT_PRESETS: dict[str, list[dict]] = {
    "studio": [
        {"frame": "camera", "at": (-0.6, 0.8, 1.0), "colour": (0.8, 0.8, 0.8)},
        {"frame": "camera", "at": (0.9, 0.1, 0.5), "colour": (0.35, 0.35, 0.4)},
    ],
    "headlight": [{"frame": "camera", "at": (0.0, 0.0, 0.5), "colour": (1.0, 1.0, 1.0)}],
    "top": [{"frame": "world", "at": (0.0, 3.0, 0.3), "colour": (1.0, 1.0, 1.0)}],
}

# The starter shape: Suffern's torus about the y-axis.
STARTER = {
    "name": "torus",
    "equation": "(x^2 + y^2 + z^2)^2 - 2*(a^2 + b^2)*(x^2 + y^2 + z^2) + 4*a^2*y^2 + (a^2 - b^2)^2",
    "params": {"a": 1.0, "b": 0.35},
    "bounds": {"x": ["-a - b", "a + b"], "y": ["-b", "b"], "z": ["-a - b", "a + b"]},
}


def _clip_spec(kind: str) -> Spec:
    """The cut option's clip solid, its size `r` a run-time param: a ball of radius r, or the cube [-r, r]^3 (a
    ball that holds the cube, cut by its bounds box: inside CSG a leaf is its solid cut by its bounds)."""
    eq = "x^2 + y^2 + z^2 - r^2" if kind == "sphere" else "x^2 + y^2 + z^2 - 4*r^2"
    box = {a: ["-r", "r"] for a in "xyz"}
    return parse_spec({"name": f"clip_{kind}", "equation": eq, "params": {"r": 1.0}, "bounds": box}, "clip")


CLIP_SPECS = {kind: _clip_spec(kind) for kind in CLIPS[1:]}


@dataclass
class Orbit:
    """The camera turns about `target` at `distance`: yaw about +y, pitch above the x-z plane (degrees)."""

    yaw: float = 30.0
    pitch: float = 25.0
    distance: float = 6.0
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    fov: float = 40.0

    def basis(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(position, right, up) of the camera."""
        y, p = math.radians(self.yaw), math.radians(self.pitch)
        back = np.array([math.cos(p) * math.sin(y), math.sin(p), math.cos(p) * math.cos(y)])
        right = np.array([math.cos(y), 0.0, -math.sin(y)])
        up = np.cross(back, right)
        return np.add(self.target, self.distance * back), right, up

    def camera(self) -> Camera:
        pos, _, up = self.basis()
        return Camera(position=tuple(pos), look_at=tuple(self.target), up=tuple(up), fov=self.fov)

    @staticmethod
    def looking(cam: Camera) -> Orbit:
        """The orbit that reproduces a scene file's camera position and target (up becomes +y)."""
        v = np.subtract(cam.position, cam.look_at)
        dist = float(np.linalg.norm(v))
        pitch = math.degrees(math.asin(max(-1.0, min(1.0, v[1] / dist))))
        yaw = math.degrees(math.atan2(v[0], v[2]))
        return Orbit(yaw=yaw, pitch=max(-89.0, min(89.0, pitch)), distance=dist, target=cam.look_at, fov=cam.fov)


@dataclass
class Options:
    clip: str = "sphere"
    clip_size: float = 3.0
    cut: bool = False  # False: the surface inside the clip, cut open (as SURFER); True: the solid, its cut capped
    color: tuple[float, float, float] = (0.95, 0.75, 0.3)
    inside: tuple[float, float, float] = (0.35, 0.55, 0.95)
    lights: str = "studio"
    background: tuple[float, float, float] = (0.12, 0.12, 0.14)


@dataclass
class Document:
    """The viewer's state. `base` is the scene a SCENE.yaml gave (None for a spec: the shape alone);
    `leaf` is the leaf whose equation and params the page edits."""

    spec: Spec
    values: dict[str, float]
    orbit: Orbit = field(default_factory=Orbit)
    options: Options = field(default_factory=Options)
    base: Scene | None = None
    leaf: Leaf | None = None
    # a scene file's leaves edited so far, other than `leaf`: id(leaf) -> (its spec, its param values)
    edits: dict[int, tuple[Spec, dict[str, float]]] = field(default_factory=dict)
    # the slider ranges the page sent with a save or an export (the user's own spans): name -> (low, high)
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)
    frame: bool = True  # the page frames the clip at the start (not a saved view's camera, nor a scene's)
    # a scene file's top-level leaves whose clip the page set: id(leaf) -> the clip (None: no clip)
    clips: dict[int, Clip | None] = field(default_factory=dict)

    @staticmethod
    def for_spec(spec: Spec, fitted: float | None = None) -> Document:
        """A spec's document; `fitted`: the clip fitted to a shape without a box (view/fit.py), else its box's."""
        doc = Document(spec=spec, values=dict(spec.params))
        if fitted is not None:
            doc.options.clip_size = fitted
        box = spec.box()
        if box is not None and all(math.isfinite(v) for v in box):
            # a clip ball about the origin that holds the spec's box (its bounding sphere, and a margin)
            radius = 0.5 * math.dist(box[:3], box[3:])
            center = tuple(0.5 * (lo + hi) for lo, hi in zip(box[:3], box[3:]))
            doc.options.clip_size = max(1e-3, round(radius * 1.2 + math.dist(center, (0.0, 0.0, 0.0)), 3))
        # the camera frames the clip ball (the page frames it again for its picture's narrower direction)
        doc.orbit.distance = max(1e-3, doc.options.clip_size / math.sin(math.radians(doc.orbit.fov / 2)) * 1.1)
        return doc

    @staticmethod
    def for_scene(scene: Scene) -> Document:
        leaves = scene.leaves()
        leaf = leaves[0]
        doc = Document(spec=leaf.spec, values=dict(leaf.params), base=scene, leaf=leaf)
        doc.orbit = Orbit.looking(scene.camera)
        doc.options = Options(clip="none", lights="scene", background=scene.background)
        return doc

    @staticmethod
    def for_file(scene: Scene) -> Document:
        """A scene file's document: the page's own saved view (Save YAML of a shape) reopens as that page, a spec
        with its clip, colours, light preset and camera; any other scene is edited as a scene."""
        return saved_view(scene) or Document.for_scene(scene)

    def shape_state(self) -> dict:
        """The shape the page shows: its name, equation, params, their values and the degree."""
        spec = self.spec
        return {
            "name": spec.name,
            "equation": spec.as_written,  # the user's own tree printed back, not SymPy's order
            "params": spec.params,
            "values": self.values,
            "degree": spec.degree,
            "ranges": {k: list(r) for k, r in param_ranges(spec).items()},  # the sliders' spans (paramrange.py)
            "object_clip": self.object_clip(),
        }

    def scene_name(self) -> str:
        """What a scene file's saved files are called: its file's name without the folder and the suffix."""
        return PurePath(self.base.source).stem if self.base is not None else ""

    def state(self) -> dict:
        """What the page starts from: the shape, its values, the camera, the options (and a scene's objects)."""
        o, orbit = self.options, self.orbit
        return {
            **self.shape_state(),
            "mode": "spec" if self.base is None else "scene",
            "frame": self.base is None and self.frame,
            "scene_name": self.scene_name(),
            "objects": self.objects(),
            "object": self.object_index(),
            "orbit": {
                "yaw": orbit.yaw,
                "pitch": orbit.pitch,
                "distance": orbit.distance,
                "target": list(orbit.target),
                "fov": orbit.fov,
            },
            "options": {
                "clip": o.clip,
                "clip_size": o.clip_size,
                "cut": o.cut,
                "color": list(o.color),
                "inside": list(o.inside),
                "lights": o.lights,
                "background": list(o.background),
            },
        }

    def objects(self) -> list[dict]:
        """A scene file's leaves, as the page lists them to pick one: the shape's name and where it is."""
        if self.base is None:
            return []
        out = []
        for i, leaf in enumerate(self.base.leaves()):
            spec = self.spec if leaf is self.leaf else self.edits.get(id(leaf), (leaf.spec,))[0]
            out.append({"index": i, "name": spec.name, "where": leaf.where})
        return out

    def object_index(self) -> int | None:
        if self.base is None:
            return None
        return next(i for i, leaf in enumerate(self.base.leaves()) if leaf is self.leaf)

    def clippable(self) -> bool:
        """Whether the page may give the scene's picked leaf a clip: a top-level object (inside CSG the other parts
        bound it)."""
        return self.base is not None and any(obj is self.leaf for obj in self.base.objects)

    def leaf_clip(self) -> Clip | None:
        """The scene's picked leaf's clip, the page's if it set one."""
        if self.leaf is None:
            return None
        return self.clips[id(self.leaf)] if id(self.leaf) in self.clips else self.leaf.clip

    def set_clip(self, kind: str, size: float) -> None:
        """Give the scene's picked (top-level) leaf a clip of `kind` (none, sphere, box) about its clip's centre."""
        if not self.clippable():
            raise UserError("clip", "only a scene's top-level object takes a clip (in CSG the other parts bound it)")
        old = self.leaf_clip()
        clip = None if kind == "none" else Clip(kind=kind, size=size, center=old.center if old else (0.0, 0.0, 0.0))
        self.clips = {**self.clips, id(self.leaf): clip}  # a new dict: a trial document shares the old one

    def object_clip(self) -> dict | None:
        """A scene's picked object's clip as the page shows it, and whether it can take one; None for a shape."""
        if self.base is None:
            return None
        clip = self.leaf_clip()
        return {
            "clip": clip.kind if clip else "none",
            "size": clip.size if clip else self.options.clip_size,
            "clippable": self.clippable(),
        }

    def select(self, index: int) -> None:
        """Edit the scene file's leaf `index` (in leaves() order) from now on; the edits of the one edited so
        far are kept."""
        leaves = self.base.leaves() if self.base is not None else []
        if not 0 <= index < len(leaves):
            raise IndexError(index)
        self.edits = dict(self.edits)  # a copy: a trial document (dataclasses.replace) shares the dict
        self.edits[id(self.leaf)] = (self.spec, dict(self.values))
        self.leaf = leaves[index]
        self.spec, values = self.edits.pop(id(self.leaf), (self.leaf.spec, self.leaf.params))
        self.values = dict(values)

    def set_spec(self, spec: Spec) -> None:
        """A new shape: a param keeps its slider value while its name and default stay, else takes the default."""
        old = self.spec.params
        self.values = {k: self.values.get(k, v) if old.get(k) == v else v for k, v in spec.params.items()}
        self.spec = spec

    def lights(self) -> list[Light]:
        """Light presets move with the camera (the lit side stays in view while orbiting), except `top`."""
        preset = self.options.lights
        if preset == "scene" and self.base is not None:
            return list(self.base.lights)
        pos, right, up = self.orbit.basis()
        back = (pos - np.asarray(self.orbit.target)) / self.orbit.distance
        d = self.orbit.distance
        t = np.asarray(self.orbit.target)
        out = []
        for light in LIGHT_PRESETS.get(preset, LIGHT_PRESETS["studio"]):
            r, u, b = light["at"]
            where = (
                t + 2.0 * d * (r * right + u * up + b * back)
                if light["frame"] == "camera"
                else t + d * np.array(light["at"])
            )
            out.append(Light(tuple(float(v) for v in where), light["colour"]))
        return out

    def material(self) -> Material:
        o = self.options
        return Material(color=o.color, inside=o.inside, **MATERIAL)

    def _shape_node(self) -> Node:
        leaf = Leaf(spec=self.spec, params=dict(self.values), matrix=np.eye(3, 4), material=None, where="shape")
        if self.options.clip == "none":
            return leaf
        if not self.options.cut:  # the surface inside the ball or the cube, cut open: both sides show
            leaf.clip = Clip(kind=self.options.clip, size=self.options.clip_size)
            return leaf
        clip = Leaf(
            spec=CLIP_SPECS[self.options.clip],
            params={"r": self.options.clip_size},
            matrix=np.eye(3, 4),
            material=replace(self.material(), color=self.options.inside),  # cut faces show the inside colour
            where="clip",
        )
        return Csg(op="intersection", left=leaf, right=clip, material=None, where="shape")

    def scene(self, width: int = 640, height: int = 480, spp: int = 1) -> Scene:
        """The scene the tracer renders (a fresh model each time; the specs are shared)."""
        if self.base is None:
            sc = Scene(source="view", width=width, height=height, spp=spp, max_depth=4)
            node = self._shape_node()
            node.material = self.material()  # the shape's, or the clip's intersection's (its cut faces keep theirs)
            sc.objects = [node]
        else:
            sc = replace(self.base, width=width, height=height, spp=spp)
            edits = {**self.edits, id(self.leaf): (self.spec, self.values)}
            sc.objects = [_with_leaf(obj, edits, self.clips) for obj in self.base.objects]
        sc.camera = self.orbit.camera()
        sc.lights = self.lights()
        sc.background = self.options.background
        return sc


def _saved_shape(node: Node) -> tuple[Leaf, Material, str | None, float, bool] | None:
    """The shape of a view Save YAML wrote and its clip: (leaf, material, clip kind or None, size, cut), or None
    when the object is not one (a transform, a material of another kind, a clip off the origin)."""
    clip, size, cut = None, 3.0, False
    if isinstance(node, Csg):  # the cut solid: the shape intersected with the clip solid, its cut face inside
        right = node.right
        kind = next((k for k, c in CLIP_SPECS.items() if isinstance(right, Leaf) and right.spec.name == c.name), None)
        if node.op != "intersection" or not isinstance(node.left, Leaf) or kind is None:
            return None
        if right.spec.equation != CLIP_SPECS[kind].equation or set(right.params) != {"r"}:
            return None
        leaf, material, clip, size, cut = node.left, node.material, kind, float(right.params["r"]), True
        if leaf.material is not None or right.material != replace(material, color=material.inside):
            return None
    else:
        leaf, material = node, node.material
        if leaf.clip is not None:
            if any(leaf.clip.center):
                return None
            clip, size = leaf.clip.kind, leaf.clip.size
    if not isinstance(leaf, Leaf) or leaf.clip is not None and cut or not np.array_equal(leaf.matrix, np.eye(3, 4)):
        return None
    if (
        material is None
        or material.inside is None
        or material != Material(material.color, inside=material.inside, **MATERIAL)
    ):
        return None
    return leaf, material, clip, size, cut


def _close(a, b, scale: float) -> bool:
    return bool(np.allclose(np.asarray(a, float), np.asarray(b, float), rtol=0.0, atol=1e-9 * scale))


def saved_view(scene: Scene) -> Document | None:
    """The page a scene file was saved from (dump.yaml_text of a shape, not of a scene): one shape, untransformed,
    in the viewer's two-sided material, clipped about the origin or not at all, seen by an orbit camera under one of
    the light presets. None for any other scene."""
    if len(scene.objects) != 1 or scene.animation.frames > 1:
        return None
    found = _saved_shape(scene.objects[0])
    if found is None:
        return None
    leaf, material, clip, size, cut = found
    doc = Document(spec=leaf.spec, values=dict(leaf.params), orbit=Orbit.looking(scene.camera), frame=False)
    cam, scale = doc.orbit.camera(), max(1.0, doc.orbit.distance)
    if not (_close(cam.position, scene.camera.position, scale) and _close(cam.up, scene.camera.up, 1.0)):
        return None
    doc.options = Options(
        clip=clip or "none",
        clip_size=size,
        cut=cut,
        color=material.color,
        inside=material.inside,
        background=scene.background,
    )
    for preset in LIGHT_PRESETS:
        doc.options.lights = preset
        lights = doc.lights()
        if len(lights) == len(scene.lights) and all(
            _close(a.position, b.position, scale) and _close(a.color, b.color, 1.0)
            for a, b in zip(lights, scene.lights)
        ):
            return doc
    return None


def _with_leaf(
    node: Node, edits: dict[int, tuple[Spec, dict[str, float]]], clips: dict[int, Clip | None] | None = None
) -> Node:
    """A copy of the tree with each edited leaf given its spec and params, and its clip where the page set one."""
    if isinstance(node, Leaf):
        key = id(node)
        if key in edits:
            spec, values = edits[key]
            node = replace(node, spec=spec, params=dict(values))
        if clips and key in clips:
            node = replace(node, clip=clips[key])
        return node
    left = _with_leaf(node.left, edits, clips)
    right = _with_leaf(node.right, edits, clips)
    return Csg(op=node.op, left=left, right=right, material=node.material, where=node.where)
