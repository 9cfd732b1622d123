"""The camera's primary rays as runtime_c/tracer_render.c builds them (one sample at a pixel's centre), in the
same double operations: the basis w = eye - look_at, u = up x w, v = w x u, each made unit by dividing by its
length, and the half-height tan(vfov / 2). For Python that needs the tracer's own rays: the POV-Ray comparison's
exact judge (bench/povray_compare.py), the GLSL checks' ray sets (implgen.measure.glslcheck) and the viewer's pick
(view/pick.py).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from implgen.scene.model import Camera


def camera_rays(cam: Camera, width: int, height: int, x: ArrayLike, y: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """(eye, directions) of the rays through the image points (x, y) of a width x height picture: (0, 0) is its
    top left corner and pixel (i, j)'s centre is (i + 0.5, j + 0.5). x and y broadcast; the directions have
    their shape and a last axis of 3, not unit length (the tracer's are not either)."""
    eye = np.asarray(cam.position, dtype=float)
    w = eye - np.asarray(cam.look_at, dtype=float)
    w /= np.sqrt(w @ w)
    u = np.cross(np.asarray(cam.up, dtype=float), w)
    u /= np.sqrt(u @ u)
    v = np.cross(w, u)
    tan_half = np.tan(0.5 * cam.fov * np.pi / 180.0)
    px = (2.0 * np.asarray(x, dtype=float) / width - 1.0) * tan_half * (width / height)
    py = (1.0 - 2.0 * np.asarray(y, dtype=float) / height) * tan_half
    return eye, px[..., None] * u + py[..., None] * v - w
