"""A clip fitted to where a new equation has real points: the ball that holds what rays find of the surface.

Rays from outside a probe ball of radius PROBE (the surface clipped to it, rt_scene_set_clip) are aimed at
points about the origin, some spread wide and some close in; the farthest hit from the origin, with a margin,
is the clip's radius. When hits come near the probe ball's own edge, the surface runs on beyond it (a cone,
Barth's sextic): there is nothing to fit, and the caller keeps its size. The rays are traced by the C tracer on
the shape's own library (a few hundred first hits: milliseconds).
"""

from __future__ import annotations

import math

import numpy as np

from implgen.scene.build import BuildResult
from implgen.scene.model import Clip, Leaf, Material, Scene
from implgen.scene.tracer import CScene
from implgen.spec.parse import Spec

PROBE = 10.0  # radius of the ball the probe looks in
RAYS = 384  # probe rays; half aimed near the origin, half spread over the ball
UNBOUNDED = 0.8  # a hit farther than this share of PROBE: the surface runs on (no fit)
MARGIN = 1.15  # the fitted radius over the farthest hit


def probe_scene(spec: Spec, values: dict[str, float]) -> Scene:
    """The shape alone, clipped to the probe ball (the same specs as the page's scene without a cut)."""
    leaf = Leaf(spec=spec, params=dict(values), matrix=np.eye(3, 4), material=Material(), where="fit")
    leaf.clip = Clip(kind="sphere", size=PROBE)
    return Scene(source="fit", width=8, height=8, spp=1, max_depth=1, objects=[leaf])


def _directions(n: int) -> np.ndarray:
    """n unit vectors spread evenly over the sphere (a Fibonacci lattice)."""
    i = np.arange(n) + 0.5
    z = 1.0 - 2.0 * i / n
    phi = math.pi * (3.0 - math.sqrt(5.0)) * i
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _nice(r: float) -> float:
    """r rounded up to two significant digits."""
    step = 10.0 ** (math.floor(math.log10(r)) - 1)
    return float(f"{math.ceil(r / step - 1e-9) * step:.2g}")


def fit_clip(sc: Scene, lib: BuildResult) -> float | None:
    """The radius of a clip ball holding the probe scene's surface, or None: no real point found, or the surface
    runs on beyond the probe ball (on a pool thread)."""
    return clip_for(reach(sc, lib))


def fitted(spec: Spec) -> float | None:
    """The clip fitted to a spec file's shape at its defaults, as to a new equation, or None (no box needed: it
    has one; or the probe found nothing to fit). Builds the shape's library (the build cache keeps it)."""
    from implgen.scene.build import build_scene

    box = spec.box()
    if box is not None and all(map(math.isfinite, box)):
        return None
    probe = probe_scene(spec, dict(spec.params))
    return fit_clip(probe, build_scene(probe))


def clip_for(far: float | None) -> float | None:
    """The fitted clip radius for a surface whose farthest point found is `far` (reach), or None."""
    return None if far is None or math.isinf(far) else _nice(far * MARGIN)


def reach(sc: Scene, lib: BuildResult) -> float | None:
    """How far from the origin the probe scene's surface reaches: its farthest hit, math.inf when it runs on
    beyond the probe ball, None when no ray meets it (on a pool thread)."""
    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        rng = np.random.default_rng(0)
        spread = np.where(np.arange(RAYS) % 2 == 0, PROBE / 4, PROBE / 200)
        targets = rng.normal(size=(RAYS, 3)) * spread[:, None]
        farthest, hits = 0.0, 0
        for u, target in zip(_directions(RAYS), targets):
            o = 3.0 * PROBE * u
            hit = cs.intersect(o, target - o)
            if hit is not None:
                hits += 1
                farthest = max(farthest, math.dist(hit.p, (0.0, 0.0, 0.0)))
    finally:
        cs.close()
    if hits == 0 or farthest <= 0.0:
        return None
    return math.inf if farthest > UNBOUNDED * PROBE else farthest
