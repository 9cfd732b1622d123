"""Which object of a scene the user clicked: the camera ray through a pixel, traced by the C tracer to its
first hit, and the leaf whose surface that is (a CSG object's hit names the leaf too).

The ray goes through the pixel's centre exactly as the tracer's one-sample ray does (scene/camera.py).
"""

from __future__ import annotations

from implgen.scene.build import BuildResult
from implgen.scene.camera import camera_rays
from implgen.scene.model import Scene
from implgen.scene.tracer import CScene


def pick_leaf(sc: Scene, lib: BuildResult, x: float, y: float) -> int | None:
    """The index (in sc.leaves() order) of the leaf the ray through pixel (x, y) of sc's picture meets first,
    or None where it meets nothing (on a pool thread)."""
    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        o, d = camera_rays(sc.camera, sc.width, sc.height, x + 0.5, y + 0.5)  # the pixel's centre
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
