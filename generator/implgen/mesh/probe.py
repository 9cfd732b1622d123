"""Where a grid sees nothing: lines across the region itself, finer than the grid, to tell "no real points" from
"a grid too coarse for the region" and to say how fine a grid would see the solid.

Three sets of lines, each solved exactly for the solid's boundary points (crossings.line_points): the grid's own
lines; PROBES x PROBES lines along each axis spread over the region's own extent across it (not the grid's: a
grid of cubic cells over a long thin box has cells far wider than the box); and, where either found points,
PROBES x PROBES lines along each axis over the box of those points, grown by a cell of the grid and a spacing of
the probes (a small solid that the first probes only graze). Along each axis, the solid's thickness is its
longest chord on those lines (an interval between two consecutive boundary points whose middle is inside); the
solid's thickness is the least of the three (a thin plate's across it, a thin tube's across the tube), and a
grid whose cells are at most half of it puts grid vertices in the solid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from implgen.mesh.crossings import inside_flags, line_points
from implgen.mesh.region import SHIFT, Clip, Grid
from implgen.mesh.shapelib import ShapeLib

PROBES = 64  # lines across the box probed along each of its two other axes


@dataclass
class Probe:
    lines: int  # lines solved (the grid's and the probes')
    points: int  # boundary points found on them
    thickness: float  # the solid's thickness: the least over the axes of the longest chord along each (0: none)


def _lattice(lo: np.ndarray, hi: np.ndarray, axis: int) -> np.ndarray:
    """PROBES^2 line starts along `axis` over [lo, hi] across it, shifted off its symmetry planes, a little
    before lo along it (a solid that meets the box is then closed on the lines)."""
    b, c = (axis + 1) % 3, (axis + 2) % 3
    starts = np.empty((PROBES * PROBES, 3))
    starts[:, axis] = lo[axis] - 0.01 * (hi[axis] - lo[axis])
    starts[:, b] = np.repeat(lo[b] + (np.arange(PROBES) + 0.5 + SHIFT) / PROBES * (hi[b] - lo[b]), PROBES)
    starts[:, c] = np.tile(lo[c] + (np.arange(PROBES) + 0.5 + 1.37 * SHIFT) / PROBES * (hi[c] - lo[c]), PROBES)
    return starts


def _chords(lib: ShapeLib, clips: list[Clip], starts: np.ndarray, length: float, axis: int):
    """The boundary points on the lines (k, 3) and the longest chord inside the solid along them (0: none)."""
    line, t, _ = line_points(lib, clips, length, axis, starts)
    order = np.lexsort((t, line))  # each line's points in order of t
    line, t = line[order], t[order]
    pts = starts[line].copy()
    pts[:, axis] += t
    same = np.flatnonzero(line[1:] == line[:-1])  # two consecutive points on one line: an interval
    if same.size == 0:
        return pts, 0.0
    inside, _ = inside_flags(lib, clips, 0.5 * (pts[same] + pts[same + 1]))
    return pts, float((t[same + 1] - t[same])[inside].max(initial=0.0))


def probe_region(lib: ShapeLib, clips: list[Clip], lo: np.ndarray, hi: np.ndarray, grid: Grid) -> Probe:
    """The region [lo, hi] and its grid probed (see the module's docstring)."""
    chord = np.zeros(3)
    found, lines = [np.zeros((0, 3))], 0
    for axis in range(3):  # the grid's own lines
        base = np.indices(tuple(1 if a == axis else s for a, s in enumerate(grid.shape))).reshape(3, -1).T
        starts = grid.origin + grid.h * base
        pts, chord[axis] = _chords(lib, clips, starts, grid.n[axis] * grid.h, axis)
        found.append(pts)
        lines += len(starts)
    boxes = [(lo, hi)]
    for stage in range(2):
        for a, b in boxes:
            for axis in range(3):
                pts, c = _chords(lib, clips, _lattice(a, b, axis), 1.02 * float(b[axis] - a[axis]), axis)
                found.append(pts)
                chord[axis] = max(chord[axis], c)
                lines += PROBES * PROBES
        every = np.concatenate(found)
        if stage or not len(every):
            break
        grow = grid.h + (hi - lo) / PROBES
        boxes = [(np.maximum(every.min(axis=0) - grow, lo), np.minimum(every.max(axis=0) + grow, hi))]
    seen = chord[chord > 0]
    return Probe(lines=lines, points=len(np.concatenate(found)), thickness=float(seen.min()) if seen.size else 0.0)


def cells_to_see(longest: float, thickness: float) -> int:
    """Cells along the region's longest side whose size is half the solid's thickness."""
    return math.ceil(longest / (0.5 * thickness))
