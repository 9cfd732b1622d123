"""The GLSL scene tracer's picture against the C tracer's, pixel by pixel: the checks of
tests/test_glsl_scene_browser.py and bench/glsl_scene.py.

The reference is `implgen render` at one sample (a ray through each pixel's centre, as the GLSL casts it) and,
per pixel, the object the C tracer's camera ray meets first (rt_scene_intersect on the camera's rays,
implgen.scene.camera). The GLSL side gives its colour (unclamped), the object of its camera ray's hit and the
pixel's flag (any ray of its tree not sure). Compared: the object (or background) at every unflagged pixel
that is not on a silhouette -- a pixel next to one whose object differs, in either picture, where float and
double may see the edge a pixel apart -- and there the colour within a tolerance, except on the C picture's
own edges (a pixel next to one whose colour differs by more than EDGE: a checker's seam, a shadow's or a
reflected silhouette's edge, which float may also place a pixel apart).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from implgen.measure.glslcheck import silhouette
from implgen.scene.build import build_scene
from implgen.scene.camera import camera_rays
from implgen.scene.model import Scene
from implgen.scene.render import render
from implgen.scene.tracer import CScene

EDGE = 0.1  # a colour step between neighbours this large is an edge in the picture


def c_reference(scene: Scene, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """(colour (h, w, 3), object index of the camera ray's hit (h, w), -1 for the background), row 0 on top."""
    w, h = size
    built = build_scene(scene)
    rgb = render(scene, width=w, height=h, spp=1, threads=1, built=built)
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    eye, dirs = camera_rays(scene.camera, w, h, xs, ys)
    objects = np.full((h, w), -1, int)
    cs = CScene(scene, built)
    try:
        for r in range(h):
            for c in range(w):
                hit = cs.intersect(eye, dirs[r, c])
                objects[r, c] = -1 if hit is None else hit.object
    finally:
        cs.close()
    return rgb, objects


@dataclass
class SceneComparison:
    pixels: int
    flagged: int
    silhouette: int
    compared: int  # unflagged pixels off the silhouettes
    object_wrong: int  # of those, another object (or background) than C's
    colour_compared: int  # of those with the right object, off the picture's edges
    colour_wrong: int  # of those, a channel off by more than the tolerance
    colour_max: float  # the largest channel difference there (colours clamped to [0, 1] as the PNG is)
    colour_median: float
    examples: list = field(default_factory=list)


def colour_edges(rgb: np.ndarray) -> np.ndarray:
    """Pixels next to a neighbour (4-connected) whose colour differs by more than EDGE in some channel."""
    c = np.clip(rgb, 0.0, 1.0)
    edge = np.zeros(c.shape[:2], bool)
    for axis in (0, 1):
        step = np.abs(np.diff(c, axis=axis)).max(-1) > EDGE
        lo = [slice(None)] * 2
        hi = [slice(None)] * 2
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        edge[tuple(lo)] |= step
        edge[tuple(hi)] |= step
    return edge


def compare(
    c_rgb: np.ndarray, c_obj: np.ndarray, g_rgb: np.ndarray, g_obj: np.ndarray, g_flag: np.ndarray, tol: float
) -> SceneComparison:
    edge = silhouette(c_obj).astype(bool) | silhouette(g_obj).astype(bool)  # object ids: a change is an edge
    take = ~g_flag & ~edge
    wrong_obj = take & (c_obj != g_obj)
    same = take & (c_obj == g_obj) & ~colour_edges(c_rgb)
    diff = np.abs(np.clip(c_rgb, 0, 1) - np.clip(g_rgb, 0, 1)).max(-1)
    bad = same & ~(diff <= tol)  # NaN counts as wrong
    examples = [
        {"row": int(r), "col": int(c), "c": int(c_obj[r, c]), "glsl": int(g_obj[r, c]), "diff": float(diff[r, c])}
        for r, c in np.argwhere(wrong_obj | bad)[:5]
    ]
    return SceneComparison(
        pixels=int(c_obj.size),
        flagged=int(g_flag.sum()),
        silhouette=int(edge.sum()),
        compared=int(take.sum()),
        object_wrong=int(wrong_obj.sum()),
        colour_compared=int(same.sum()),
        colour_wrong=int(bad.sum()),
        colour_max=float(diff[same].max()) if same.any() else 0.0,
        colour_median=float(np.median(diff[same])) if same.any() else 0.0,
        examples=examples,
    )
