"""A picture of one shape spec on its own, framed: the gallery's contact sheet (bench/surfaces.py) and its tests.

The camera looks at the spec's box from above and to the side, far enough for the box's bounding sphere to fill
the view; two lights move with it. The outside (f > 0) is gold, the inside blue, as in the viewer. The spec
needs a whole, finite box: an open one is framed first (implgen.spec.gallery's Entry.load_framed gives one).
"""

from __future__ import annotations

import math

import numpy as np

from implgen.scene.model import Camera, Leaf, Light, Material, Scene
from implgen.spec.model import Spec

OUTSIDE = (0.95, 0.75, 0.3)
INSIDE = (0.35, 0.55, 0.95)
BACKGROUND = (0.12, 0.12, 0.14)
YAW, PITCH, FOV = 30.0, 25.0, 40.0  # degrees


def frame(spec: Spec, values: dict[str, float] | None = None) -> tuple[np.ndarray, float]:
    """(centre, radius) of the sphere the picture shows: the box's bounding sphere. A ValueError for a spec
    without a whole box: there is nothing to frame."""
    box = spec.box(values)
    if box is None or not all(math.isfinite(v) for v in box):
        raise ValueError(f"{spec.name} has no whole box to frame: frame it first (gallery Entry.load_framed)")
    lo, hi = np.array(box[:3]), np.array(box[3:])
    return 0.5 * (lo + hi), 0.5 * float(np.linalg.norm(hi - lo))


def preview_scene(spec: Spec, width: int, height: int, spp: int = 1, values: dict[str, float] | None = None) -> Scene:
    """The scene of `spec` alone (param `values` over its defaults), framed by frame()."""
    params = {**spec.params, **(values or {})}
    centre, radius = frame(spec, params)
    material = Material(color=OUTSIDE, inside=INSIDE, ambient=0.12, diffuse=0.75, specular=0.45, shininess=40.0)
    node = Leaf(spec=spec, params=params, matrix=np.eye(3, 4), material=material, where="shape")
    y, p = math.radians(YAW), math.radians(PITCH)
    back = np.array([math.cos(p) * math.sin(y), math.sin(p), math.cos(p) * math.cos(y)])
    distance = radius / math.sin(math.radians(FOV / 2)) * 1.05
    position = centre + distance * back
    right = np.array([math.cos(y), 0.0, -math.sin(y)])
    up = np.cross(back, right)

    def light(r: float, u: float, b: float, power: float) -> Light:
        return Light(tuple(centre + 2 * distance * (r * right + u * up + b * back)), (power, power, power))

    sc = Scene(source=f"preview of {spec.name}", width=width, height=height, spp=spp, max_depth=4)
    sc.camera = Camera(position=tuple(position), look_at=tuple(centre), up=tuple(up), fov=FOV)
    sc.lights = [light(-0.6, 0.8, 1.0, 0.8), light(0.9, 0.1, 0.5, 0.35)]
    sc.background = BACKGROUND
    sc.objects = [node]
    return sc
