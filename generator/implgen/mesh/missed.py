"""Detail the grid misses, told by the exact crossings: where the mesh's topology may not be the surface's.

A grid edge can hold several boundary points of the solid (every root on its line is known). Between two
consecutive ones lies an interval of one phase -- inside or outside the solid -- that neither end of the edge
shows: a sheet that pokes through the edge and back, or a thin piece of the solid (a neck) or of the outside (a
gap between two near-touching parts) that passes between grid vertices. The first is harmless: the phase there
is the one of grid vertices next to it, which the mesh already joins (a grid line grazing a torus holds two
crossings a few hundredths of a cell apart). The others change the topology: a neck joins two parts of the
solid that the grid keeps apart, a gap parts two that the grid joins, a missed piece is lost.

So each interval is tested within the block of the 18 grid vertices of the four cells around its edge, whose
parts (of one phase) are the mesh's: joined by a grid edge, or across a face whose corners alternate when the
face's centre has their phase (cells.py's rule).
  - Its middle is joined by a straight segment to each vertex of its phase, each segment solved exactly for the
    solid's boundary: a segment without a boundary point joins the interval to that vertex. An interval that
    reaches no vertex, or vertices of two parts, is missed (a piece, a neck).
  - When the edge's two ends agree, the grid joins them across the interval; if they fall apart once the joins
    that are not true are dropped -- the grid edges that hold crossings, the face diagonals whose segment is
    not clear --, the grid joins across a gap it misses.
A missed interval is counted with where it is and how wide (its length along the edge). Inside, a segment
between two inside points has no boundary point when f has no root on it (every clip is convex); outside, when f
has none and is positive at both ends, or when one clip is positive all along it (a half-space: at both ends; a
ball: the segment misses it). Next to a singular point (pipeline.py sets those aside) the detail is the node's
own: the mesh joins or parts its cones as the grid falls.
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

    def keep(self, sel: np.ndarray) -> Missed:
        return Missed(self.axis[sel], self.edge[sel], self.middle[sel], self.width[sel])

    def stats(self) -> dict:
        """The mesh's stats of them: how many, the widest, and where it is."""
        wide = int(np.argmax(self.width)) if self.count else -1
        return {
            "missed_detail_edges": self.count,
            "missed_widest": float(self.width[wide]) if self.count else None,  # along its edge
            "missed_at": [float(v) for v in self.middle[wide]] if self.count else None,
        }

    def away_from(self, points: np.ndarray, reach: float) -> Missed:
        """Those farther than `reach` (along some axis) from every point: detail next to a node is the node's
        own (the mesh joins or parts its cones as the grid falls), not detail a finer grid would resolve."""
        if not len(points) or not self.count:
            return self
        near = (np.abs(self.middle[:, None, :] - points[None, :, :]).max(axis=2) <= reach).any(axis=1)
        return self.keep(~near)


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


def _grid_parts(lib, clips, grid: Grid, flat: np.ndarray, same: np.ndarray, phase, cut=None) -> np.ndarray:
    """(k, 18) labels: the parts that the grid's joins (edges, and faces by their centres) make of each block's
    corners of the phase; -1 on corners of the other phase. With `cut` ((k, EDGES) flags of the grid edges that
    hold crossings), only the joins that are true: an edge without crossings, a diagonal whose segment is clear."""
    flags = np.where(same, phase[:, None], ~phase[:, None])  # each corner's own flag
    edge_on = same[:, EDGES[:, 0]] & same[:, EDGES[:, 1]]
    links = [edge_on if cut is None else edge_on & ~cut]
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
        on = amb & (centre_in == phase[:, None]) & (q[..., d] == phase[:, None])
        if cut is not None and on.any():
            k, sq = np.nonzero(on)
            ends = flat[k[:, None], SQUARES[sq][:, [d, d + 2]]]
            on[k, sq] = _joined(lib, clips, grid.point(ends[:, 0]), grid.point(ends[:, 1]), phase[k])
        links.append(on)
    return _spread(np.concatenate(pairs), np.concatenate(links, axis=1), same)


def _spread(pairs: np.ndarray, links: np.ndarray, same: np.ndarray) -> np.ndarray:
    """Each block's corners labelled by the least corner index of their part under the joins `links` (k, pairs)."""
    label = np.where(same, np.arange(same.shape[1])[None, :], 99)
    row, j = np.nonzero(links)
    u, v = pairs[j, 0], pairs[j, 1]
    for _ in range(same.shape[1]):  # spread the least label along the joins until nothing changes
        low = np.minimum(label[row, u], label[row, v])
        before = label.copy()
        np.minimum.at(label, (row, u), low)
        np.minimum.at(label, (row, v), low)
        if np.array_equal(before, label):
            break
    return np.where(same, label, -1)


@dataclass
class _Blocks:
    """The 18 corners of the four cells around each interval's edge."""

    flat: np.ndarray  # (k, 18) flat vertex index (clipped into the grid)
    real: np.ndarray  # (k, 18) inside the grid
    cut: np.ndarray  # (k, EDGES) the block's grid edges that hold crossings


def _blocks(inside: np.ndarray, edges: np.ndarray, a: int, held: np.ndarray) -> _Blocks:
    shape = np.array(inside.shape)
    idx = np.stack(np.unravel_index(edges, inside.shape), axis=1)
    corner = idx[:, None, :] + np.roll(AROUND, a, axis=1)[None, :, :]  # (k, 18, 3): (a, a+1, a+2) -> (x, y, z)
    real = ((corner >= 0) & (corner < shape)).all(axis=2)
    flat = np.ravel_multi_index(tuple(np.clip(corner, 0, shape - 1).transpose(2, 0, 1)), inside.shape)
    axis = (a + np.array([int(np.flatnonzero(AROUND[v] - AROUND[u])[0]) for u, v in EDGES.tolist()])) % 3
    key = axis[None, :] * inside.size + flat[:, EDGES[:, 0]]
    return _Blocks(flat=flat, real=real, cut=np.isin(key, held))


def _lone(lib, clips, grid: Grid, inside: np.ndarray, c: Crossings, a: int, held: np.ndarray) -> np.ndarray:
    """Which of the axis' intervals are detail the grid misses (see the module's docstring)."""
    mid = c.inner_ends.mean(axis=1)
    phase, _ = inside_flags(lib, clips, mid)
    b = _blocks(inside, c.inner_edge, a, held)
    flags = inside.reshape(-1)[b.flat]
    same = b.real & (flags == phase[:, None])
    parts = _grid_parts(lib, clips, grid, b.flat, same, phase)
    k, j = np.nonzero(same)
    reach = np.zeros(same.shape, dtype=bool)
    if k.size:
        reach[k, j] = _joined(lib, clips, mid[k], grid.point(b.flat[k, j]), phase[k])
    seen = np.where(reach, parts, 99)
    first = seen.min(axis=1)
    lone = (first == 99) | (np.where(reach, parts, first[:, None]) != first[:, None]).any(axis=1)
    ends = flags[:, _AT[(0, 0, 0)]]  # the edge's own ends: when they agree, the grid joins them across it
    agree = b.real[:, _AT[(1, 0, 0)]] & (flags[:, _AT[(1, 0, 0)]] == ends)
    if agree.any():  # joined by the grid; apart without the joins that cross the boundary: a gap missed
        sel = np.flatnonzero(agree)
        true = _grid_parts(lib, clips, grid, b.flat[sel], b.real[sel] & (flags[sel] == ends[sel, None]),
                           ends[sel], b.cut[sel])  # fmt: skip
        lone[sel] |= true[:, _AT[(0, 0, 0)]] != true[:, _AT[(1, 0, 0)]]
    return lone


def missed_detail(lib: ShapeLib, clips: list[Clip], grid: Grid, inside: np.ndarray, cross: list[Crossings]) -> Missed:
    """The intervals on grid edges that are detail the grid misses (see the module's docstring)."""
    held = np.unique(np.concatenate([a * inside.size + c.inner_edge for a, c in enumerate(cross)] + [[]]))
    parts = []
    for a, c in enumerate(cross):
        if c.inner_edge is None or not len(c.inner_edge):
            continue
        lone = _lone(lib, clips, grid, inside, c, a, held.astype(np.int64))
        mid = c.inner_ends[lone].mean(axis=1)
        width = np.linalg.norm(c.inner_ends[lone, 1] - c.inner_ends[lone, 0], axis=1)
        parts.append((np.full(int(lone.sum()), a), c.inner_edge[lone], mid, width))
    if not parts:
        return Missed(np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros((0, 3)), np.zeros(0))
    return Missed(*(np.concatenate([p[i] for p in parts]) for i in range(4)))
