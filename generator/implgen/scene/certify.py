"""The certify pass's result (docs/certify.md): per pixel, whether the first hit of its primary rays is certified
(0 miss, 1 hit) or why not (2 and up), the object each code is about, and the report `implgen render --report`
writes. The codes and their names come from the C runtime (runtime_c/certify.h, rt_certify_reason)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

CERTIFIED = (0, 1)  # certified miss, certified hit


@dataclass
class Certificate:
    """A render's certify map: codes (uint8, the image's rows and columns), the object of each (int32, -1: none),
    the names of the codes and of the scene's objects, and the pass's wall time."""

    codes: np.ndarray
    objects: np.ndarray
    reasons: dict[int, str]
    object_names: list[str]
    seconds: float = 0.0

    def not_certified(self) -> int:
        """Pixels not certified."""
        return int(np.count_nonzero(self.codes > 1))

    def report(self) -> dict:
        """Counts per reason and per object, and the codes' names, as JSON-ready data."""
        counts = np.bincount(self.codes.ravel(), minlength=len(self.reasons))
        per_object: dict[str, dict[str, int]] = {}
        for k, name in enumerate(self.object_names):
            mine = self.codes[self.objects == k]
            got = np.bincount(mine, minlength=len(self.reasons))
            per_object[name] = {self.reasons[c]: int(n) for c, n in enumerate(got) if n}
        return {
            "width": int(self.codes.shape[1]),
            "height": int(self.codes.shape[0]),
            "pixels": int(self.codes.size),
            "certified": int(self.codes.size - self.not_certified()),
            "not_certified": self.not_certified(),
            "counts": {self.reasons[c]: int(n) for c, n in enumerate(counts)},
            "per_object": per_object,
            "reasons": {str(c): name for c, name in self.reasons.items()},
            "seconds": round(self.seconds, 6),
        }


def reason_names(lib) -> dict[int, str]:
    """The codes of the map and their names, as the C runtime lists them."""
    out: dict[int, str] = {}
    code = 0
    while (name := lib.rt_certify_reason(code)) is not None:
        out[code] = name.decode()
        code += 1
    return out


def object_names(scene) -> list[str]:
    """A name for each top-level object: its place in the scene and its shape."""
    names = []
    for i, node in enumerate(scene.objects):
        what = node.spec.name if hasattr(node, "spec") else f"csg {node.op}"
        names.append(f"{i}:{what}")
    return names
