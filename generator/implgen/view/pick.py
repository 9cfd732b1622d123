"""Which object of a scene the user clicked: the camera ray through a pixel, traced by the C tracer to its
first hit, and the leaf whose surface that is (a CSG object's hit names the leaf too).

The ray goes through the pixel's centre exactly as the tracer's one-sample ray does (tracer_render.c: the
camera basis w = eye - look_at, u = up x w, v = w x u, and the half-height tan(vfov / 2)).
"""

from __future__ import annotations

import math

import numpy as np

from implgen.scene.build import BuildResult
from implgen.scene.model import Camera, Scene
from implgen.scene.tracer import CScene


def pixel_ray(cam: Camera, width: int, height: int, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    """(origin, direction) of the ray through pixel (x, y) of a width x height picture, (0, 0) its top left."""
    w = np.subtract(cam.position, cam.look_at, dtype=float)
    w /= np.linalg.norm(w)
    u = np.cross(cam.up, w)
    u /= np.linalg.norm(u)
    v = np.cross(w, u)
    half = math.tan(math.radians(cam.fov) / 2)
    px = (2.0 * (x + 0.5) / width - 1.0) * half * width / height
    py = (1.0 - 2.0 * (y + 0.5) / height) * half
    return np.asarray(cam.position, float), px * u + py * v - w


def pick_leaf(sc: Scene, lib: BuildResult, x: float, y: float) -> int | None:
    """The index (in sc.leaves() order) of the leaf the ray through pixel (x, y) of sc's picture meets first,
    or None where it meets nothing (on a pool thread)."""
    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        o, d = pixel_ray(sc.camera, sc.width, sc.height, x, y)
        hit = cs.intersect(o, d)
        if hit is None:
            return None
        leaf = cs.leaf_nodes.get(hit.leaf)
    finally:
        cs.close()
    for i, candidate in enumerate(sc.leaves()):
        if candidate is leaf:
            return i
    return None
