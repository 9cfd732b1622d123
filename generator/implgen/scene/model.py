"""A scene as the renderer sees it: validated values, shapes resolved to specs, CSG as a binary tree.

Built by scene/load.py from a scene file; read by scene/build.py (which shapes to compile) and
scene/tracer.py (what to hand to the C tracer).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from implgen import abi
from implgen.scene.keys import Animation
from implgen.spec.model import Spec


@dataclass
class Material:
    color: tuple[float, float, float] = (0.8, 0.8, 0.8)
    color2: tuple[float, float, float] = (0.2, 0.2, 0.2)
    checker_scale: float = 0.0
    ambient: float = 0.1
    diffuse: float = 0.8
    specular: float = 0.3
    shininess: float = 50.0
    reflectivity: float = 0.0
    transparency: float = 0.0
    ior: float = 1.5
    absorption: tuple[float, float, float] = (0.0, 0.0, 0.0)
    inside: tuple[float, float, float] | None = None  # colour of a surface's back (f < 0) side; None: color

    @property
    def two_sided(self) -> float:
        """rt_material.two_sided: 1 when the back of the surface has its own colour."""
        return 0.0 if self.inside is None else 1.0

    def packed(self) -> list[float]:
        """RT_MATERIAL_DOUBLES values in the order of rt_material's fields (read from tracer.h)."""
        values: list[float] = []
        for name, count in abi.material_fields():
            v = getattr(self, name)
            if name == "inside" and v is None:
                v = (0.0, 0.0, 0.0)  # unused: two_sided is 0
            values += [float(x) for x in v] if count > 1 else [float(v)]
        return values + [0.0] * (abi.value("RT_MATERIAL_DOUBLES") - len(values))


CLIP_KINDS = ("sphere", "box")


@dataclass(frozen=True)
class Clip:
    """A top-level surface shown only inside a ball (`sphere`, radius `size`) or a cube (`box`, half-edge `size`)
    about `center`, in the leaf's object space; cut open, no cap (rt_scene_set_clip)."""

    kind: str
    size: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)


@dataclass
class Leaf:
    spec: Spec  # its symbolic part deferred when the spec's content was parsed before (spec/cache.py)
    params: dict[str, float]  # every param of the spec, in its declared order
    matrix: np.ndarray  # 3x4 object -> world
    material: Material | None
    where: str  # key path in the scene, for messages
    clip: Clip | None = None  # a top-level leaf only


@dataclass
class Csg:
    op: str
    left: Node
    right: Node
    material: Material | None
    where: str
    depth: int = field(init=False)  # of this binary node: 1 + the deeper child's

    def __post_init__(self) -> None:
        self.depth = 1 + max(depth(self.left), depth(self.right))


Node = Leaf | Csg


def depth(node: Node) -> int:
    """Depth of the binary CSG tree below a node (0 for a leaf)."""
    return node.depth if isinstance(node, Csg) else 0


@dataclass
class Light:
    position: tuple[float, float, float]
    color: tuple[float, float, float]  # colour x intensity


@dataclass
class Camera:
    position: tuple[float, float, float] = (0.0, 1.0, 6.0)
    look_at: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fov: float = 40.0


@dataclass
class Scene:
    source: str
    width: int = 640
    height: int = 480
    spp: int = 1
    max_depth: int = 8
    camera: Camera = field(default_factory=Camera)
    background: tuple[float, float, float] = (0.0, 0.0, 0.0)
    lights: list[Light] = field(default_factory=list)
    objects: list[Node] = field(default_factory=list)
    animation: Animation = field(default_factory=Animation)  # frames and fps; one frame for a still
    keyed: tuple[str, ...] = ()  # key paths of the values that change from frame to frame

    def leaves(self) -> list[Leaf]:
        out: list[Leaf] = []

        def walk(n: Node) -> None:
            if isinstance(n, Leaf):
                out.append(n)
            else:
                walk(n.left)
                walk(n.right)

        for o in self.objects:
            walk(o)
        return out

    def specs(self) -> list[Spec]:
        """The distinct shapes the scene uses (what gets generated and compiled, nothing else)."""
        seen: dict[int, Spec] = {}
        for leaf in self.leaves():
            seen.setdefault(id(leaf.spec), leaf.spec)
        return list(seen.values())
