"""The kernel's pictures for `implgen.show`, rendered in double by the C tracer: a surface seen from the widget's
orbit (the fallback without WebGL2, and `_repr_png_`), and a scene's frames.

A surface is lit and coloured as on the shared page and in the viewer (gold outside, blue inside, share/page.py's
MATERIAL, two lights that turn with the camera), inside the same clip sphere the page draws it in, so the
fallback shows what WebGL2 would have.
"""

from __future__ import annotations

import math

import numpy as np

from implgen.imagefile import encode_png, to_uint8
from implgen.scene.model import Camera, Clip, Leaf, Light, Material, Scene
from implgen.scene.preview import BACKGROUND, INSIDE, OUTSIDE
from implgen.scene.render import render
from implgen.share.page import MATERIAL
from implgen.spec.model import Spec


def basis(orbit: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(right, up, back) of the orbit camera, as share/static/orbit.js computes them."""
    y, p = math.radians(orbit["yaw"]), math.radians(orbit["pitch"])
    back = np.array([math.cos(p) * math.sin(y), math.sin(p), math.cos(p) * math.cos(y)])
    right = np.array([math.cos(y), 0.0, -math.sin(y)])
    return right, np.cross(back, right), back


def orbit_camera(orbit: dict) -> Camera:
    _, up, back = basis(orbit)
    target = np.array(orbit["target"], dtype=float)
    eye = target + float(orbit["distance"]) * back
    return Camera(position=tuple(map(float, eye)), look_at=tuple(map(float, target)), up=tuple(up), fov=orbit["fov"])


def orbit_of(camera: Camera) -> dict:
    """The orbit (yaw, pitch, distance, target, fov) that sees what `camera` sees, up to its roll."""
    offset = np.subtract(camera.position, camera.look_at)
    distance = float(np.linalg.norm(offset))
    back = offset / distance
    yaw = math.degrees(math.atan2(back[0], back[2]))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, back[1]))))
    return {"yaw": yaw, "pitch": pitch, "distance": distance, "target": list(camera.look_at), "fov": camera.fov}


def surface_scene(spec: Spec, values: dict[str, float], orbit: dict, clip_size: float, size: tuple[int, int]) -> Scene:
    """`spec` alone, with these param values, from `orbit`, inside the clip sphere of radius `clip_size`."""
    material = Material(color=OUTSIDE, inside=INSIDE, **MATERIAL)
    params = {**spec.params, **values}
    leaf = Leaf(spec, params, np.eye(3, 4), material, "shape", clip=Clip(kind="sphere", size=clip_size))
    sc = Scene(source=f"implgen.show {spec.name}", width=size[0], height=size[1], spp=1, max_depth=4)
    sc.camera = orbit_camera(orbit)
    right, up, back = basis(orbit)
    target, reach = np.array(orbit["target"], dtype=float), 2.0 * float(orbit["distance"])

    def light(r: float, u: float, b: float, power: float) -> Light:
        return Light(tuple(map(float, target + reach * (r * right + u * up + b * back))), (power, power, power))

    sc.lights = [light(-0.6, 0.8, 1.0, 0.8), light(0.9, 0.1, 0.5, 0.35)]
    sc.background = BACKGROUND
    sc.objects = [leaf]
    return sc


def png(scene: Scene, size: tuple[int, int] | None = None) -> bytes:
    """The scene rendered in double (at `size`, else its own) as PNG bytes."""
    width, height = size if size is not None else (scene.width, scene.height)
    return encode_png(to_uint8(render(scene, width=width, height=height)))
