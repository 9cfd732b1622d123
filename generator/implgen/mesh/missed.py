"""Detail the grid misses, told by the exact crossings: where the mesh's topology may not be the surface's.

A grid edge can hold several boundary points of the solid (every root on its line is known). Between two
consecutive ones lies an interval of one phase -- inside or outside the solid -- that neither end of the edge
shows: a sheet that pokes through the edge and back, or a thin piece of the solid (a neck) or of the outside (a
gap between two near-touching parts) that passes between grid vertices. The first is harmless: the phase there
is the one of grid vertices next to it, which the mesh already joins (a grid line grazing a torus holds two
crossings a few hundredths of a cell apart). The others change the topology: a neck joins two parts of the
solid that the grid keeps apart, a missed piece is lost.

So each such interval is tested against the 18 grid vertices of the four cells around its edge. Its middle is
joined by a straight segment to each of them of its phase, each segment solved exactly for the solid's boundary:
a segment without a boundary point joins the interval to that vertex. The grid's own joins among those vertices
are the mesh's: two vertices of one phase joined by a grid edge, or across a face whose corners alternate when
the face's centre has that phase (cells.py's rule). The interval is detail the grid misses when it reaches none
of those vertices, or vertices that the grid's joins keep apart; it is counted with where it is and how thin
(its length along the edge). Inside, a segment between two inside points has no boundary point when f has no
root on it (every clip is convex); outside, when f has none and is positive at both ends, or when one clip is
positive all along it (a half-space: at both ends; a ball: the segment misses it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.crossings import Crossings, inside_flags
from implgen.mesh.region import Clip, Grid, HalfSpace
from implgen.mesh.shapelib import ShapeLib

# offsets of the 18 corners of the four cells around an edge along axis a: (along a, along a + 1, along a + 2)
AROUND = np.array([(i, j, k) for i in (0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)], dtype=np.int64)
_AT = {tuple(o): n for n, o in enumerate(AROUND.tolist())}
# the grid edges among them (pairs of indices) and the unit squares (four indices, corners in turn)
EDGES = np.array(
    [(n, _AT[q]) for n, o in enumerate(AROUND.tolist()) for d in range(3)
     if (q := tuple(o[i] + (i == d) for i in range(3))) in _AT]
)  # fmt: skip


def _squares() -> np.ndarray:
    out = []
    for o in AROUND.tolist():
        for d, e in ((0, 1), (0, 2), (1, 2)):
            ring = [
                tuple(o[i] + (i == d and s) + (i == e and t) for i in range(3))
                for s, t in ((0, 0), (1, 0), (1, 1), (0, 1))
            ]
            if all(r in _AT for r in ring):
                out.append([_AT[r] for r in ring])
    return np.array(out)


SQUARES = _squares()


@dataclass
class Missed:
    """The intervals between boundary points on grid edges that no grid vertex of their phase reaches."""

    axis: np.ndarray  # (k,) the edge's axis
    edge: np.ndarray  # (k,) the edge's lower grid vertex (flat)
    middle: np.ndarray  # (k, 3)
    width: np.ndarray  # (k,) the interval's length along the edge

    @property
    def count(self) -> int:
        return len(self.width)


def _clip_outside(clip: Clip, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Whether the segment a-b lies outside the clip (its value > 0) all along."""
    if isinstance(clip, HalfSpace):
        return (clip.value(a) > 0) & (clip.value(b) > 0)
    c = np.asarray(clip.center)
    d = b - a
    t = np.clip(np.einsum("ij,ij->i", c - a, d) / np.maximum(np.einsum("ij,ij->i", d, d), 1e-300), 0.0, 1.0)
    return clip.value(a + t[:, None] * d) > 0


def _joined(lib: ShapeLib, clips: list[Clip], a: np.ndarray, b: np.ndarray, inside: np.ndarray) -> np.ndarray:
    """Whether each segment a-b (both ends of phase `inside`) stays in that phase (see the module's docstring)."""
    d = b - a
    length = np.linalg.norm(d, axis=1)
    _, counts = lib.roots(a, d / np.maximum(length, 1e-300)[:, None], 0.0, length)
    clear = counts == 0
    if inside.all():
        return clear
    out = ~inside & clear & (lib.value(a) > 0) & (lib.value(b) > 0)
    for c in clips:
        out |= ~inside & _clip_outside(c, a, b)
    return np.where(inside, clear, out)


def _grid_parts(lib: ShapeLib, clips: list[Clip], grid: Grid, flat: np.ndarray, same: np.ndarray, phase) -> np.ndarray:
    """(k, 18) labels: the parts that the grid's joins (edges, and faces by their centres) make of each interval's
    corners of its phase; -1 on corners of the other phase."""
    flags = np.where(same, phase[:, None], ~phase[:, None])  # each corner's own flag
    links = [np.broadcast_to(same[:, EDGES[:, 0]] & same[:, EDGES[:, 1]], (len(same), len(EDGES)))]
    pairs = [EDGES]
    q = flags[:, SQUARES]  # (k, squares, 4)
    amb = (q[..., 0] == q[..., 2]) & (q[..., 1] == q[..., 3]) & (q[..., 0] != q[..., 1])
    k, sq = np.nonzero(amb)
    centre_in = np.zeros(amb.shape, dtype=bool)
    if k.size:
        centre = grid.point(flat[k[:, None], SQUARES[sq]].reshape(-1)).reshape(-1, 4, 3).mean(axis=1)
        centre_in[k, sq] = inside_flags(lib, clips, centre)[0]
    for d in (0, 1):  # the diagonal through corners d and d + 2, joined when the centre has their phase
        pairs.append(SQUARES[:, [d, d + 2]])
        links.append(amb & (centre_in == phase[:, None]) & (q[..., d] == phase[:, None]))
    pairs_all, links_all = np.concatenate(pairs), np.concatenate(links, axis=1)
    label = np.where(same, np.arange(18)[None, :], 99)
    for _ in range(18):  # spread the least label along the joins until nothing changes
        low = np.minimum(label[:, pairs_all[:, 0]], label[:, pairs_all[:, 1]])
        new = label.copy()
        for j, (u, v) in enumerate(pairs_all.tolist()):
            on = links_all[:, j]
            new[on, u] = np.minimum(new[on, u], low[on, j])
            new[on, v] = np.minimum(new[on, v], low[on, j])
        if np.array_equal(new, label):
            break
        label = new
    return np.where(same, label, -1)


def _lone(lib: ShapeLib, clips: list[Clip], grid: Grid, inside: np.ndarray, c: Crossings, a: int) -> np.ndarray:
    """Which of the axis' intervals are detail the grid misses (see the module's docstring)."""
    shape = np.array(inside.shape)
    mid = c.inner_ends.mean(axis=1)
    phase, _ = inside_flags(lib, clips, mid)
    idx = np.stack(np.unravel_index(c.inner_edge, inside.shape), axis=1)
    corner = idx[:, None, :] + np.roll(AROUND, a, axis=1)[None, :, :]  # (k, 18, 3): (a, a+1, a+2) -> (x, y, z)
    real = ((corner >= 0) & (corner < shape)).all(axis=2)
    flat = np.ravel_multi_index(tuple(np.clip(corner, 0, shape - 1).transpose(2, 0, 1)), inside.shape)
    same = real & (inside.reshape(-1)[flat] == phase[:, None])
    parts = _grid_parts(lib, clips, grid, flat, same, phase)
    k, j = np.nonzero(same)
    reach = np.zeros(same.shape, dtype=bool)
    if k.size:
        reach[k, j] = _joined(lib, clips, mid[k], grid.point(flat[k, j]), phase[k])
    seen = np.where(reach, parts, 99)
    first = seen.min(axis=1)
    return (first == 99) | (np.where(reach, parts, first[:, None]) != first[:, None]).any(axis=1)


def missed_detail(lib: ShapeLib, clips: list[Clip], grid: Grid, inside: np.ndarray, cross: list[Crossings]) -> Missed:
    """The intervals on grid edges that are detail the grid misses (see the module's docstring)."""
    parts = []
    for a, c in enumerate(cross):
        if c.inner_edge is None or not len(c.inner_edge):
            continue
        lone = _lone(lib, clips, grid, inside, c, a)
        mid = c.inner_ends[lone].mean(axis=1)
        width = np.linalg.norm(c.inner_ends[lone, 1] - c.inner_ends[lone, 0], axis=1)
        parts.append((np.full(int(lone.sum()), a), c.inner_edge[lone], mid, width))
    if not parts:
        return Missed(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0))
    return Missed(*(np.concatenate([p[i] for p in parts]) for i in range(4)))
