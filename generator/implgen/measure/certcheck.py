"""The certify pass (docs/certify.md) against the exact judge, ray by ray: tests/test_certify.py's and
bench/certify.py's measurement.

A sample of a scene's pixels: each pixel's centre ray (implgen.scene.camera, the tracer's own rays) is certified
by the C runtime (rt_certify_ray), and every certified answer is judged exactly (implgen.roots.exactray): a
certified miss must meet no object; a certified hit on object k at the tracer's t must meet k within a relative
1e-8 of t and meet no object (k included) before that. A CSG object is judged by its leaves: "met" when any leaf
is, which can only make the judge stricter about a certified answer.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from fractions import Fraction

import numpy as np

from implgen.roots.exactray import Placed
from implgen.scene.camera import camera_rays
from implgen.scene.model import Leaf

NEAR = 1e-8  # a certified hit is judged within this relative distance of the tracer's t


def placed_objects(scene) -> list[list[Placed]]:
    """Per top-level object, its leaves placed exactly (one for a leaf, every leaf of a CSG tree)."""
    out = []
    for node in scene.objects:
        leaves: list[Leaf] = []
        stack = [node]
        while stack:
            n = stack.pop()
            if isinstance(n, Leaf):
                leaves.append(n)
            else:
                stack += [n.left, n.right]
        out.append([Placed.of(lf.spec, lf.params, lf.matrix) for lf in leaves])
    return out


def _meets(obj: list[Placed], o, d, t0, t1) -> bool:
    return any(p.meets(o, d, t0, t1) for p in obj)


def judged_right(objects: list[list[Placed]], code: int, obj: int, t: float, o, d) -> bool:
    """Is a certified answer (code 0: miss; 1: a hit on object obj at the tracer's t) exactly true?"""
    if code == 0:
        return not any(_meets(x, o, d, 0, None) for x in objects)
    near = Fraction(t) * Fraction(1 - NEAR)
    if not _meets(objects[obj], o, d, near, Fraction(t) * Fraction(1 + NEAR)):
        return False
    return not any(_meets(x, o, d, 0, near) for x in objects)


@dataclass
class SceneCheck:
    """What a sample of pixels gave: the codes' counts, the pixels judged and those judged wrong, and per degree
    (of the object the tracer shows) the object pixels and those not certified."""

    counts: dict[int, int] = field(default_factory=dict)
    judged: int = 0
    wrong: list[tuple[int, int]] = field(default_factory=list)
    per_degree: dict[int, list[int]] = field(default_factory=dict)  # degree -> [object pixels, not certified]


def _degree(node) -> int:
    if isinstance(node, Leaf):
        return node.spec.degree
    return max(_degree(node.left), _degree(node.right))


def sample_pixels(width: int, height: int, n: int, seed: int) -> np.ndarray:
    """n distinct pixels (x, y) of the image, drawn without replacement."""
    rng = np.random.default_rng(seed)
    flat = rng.choice(width * height, size=min(n, width * height), replace=False)
    return np.stack([flat % width, flat // width], axis=1)


def check_pixels(scene, cs, width: int, height: int, pixels) -> SceneCheck:
    """Certify the centre ray of each pixel (x, y) with the C scene cs, and judge the certified ones exactly."""
    objects = placed_objects(scene)
    degrees = [_degree(n) for n in scene.objects]
    out = SceneCheck()
    for x, y in pixels:
        eye, d = camera_rays(scene.camera, width, height, x + 0.5, y + 0.5)
        o, d = [float(v) for v in eye], [float(v) for v in d]
        code, obj = cs.certify(o, d)
        out.counts[code] = out.counts.get(code, 0) + 1
        hit = cs.intersect(o, d)
        if hit is not None:
            row = out.per_degree.setdefault(degrees[hit.object], [0, 0])
            row[0] += 1
            row[1] += code > 1
        if code > 1:
            continue
        out.judged += 1
        if not judged_right(objects, code, obj, hit.t if hit is not None else 0.0, o, d):
            out.wrong.append((int(x), int(y)))
    return out
