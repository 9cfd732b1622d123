"""Grid lines → crossings: every line of the grid is a ray along an axis; the C runtime gives every root of f
along it at once (ShapeLib.roots, one C call per family of lines), the clips' crossings are closed forms.

A grid edge is active when the solid's inside flag differs at its two ends (f < 0 and every clip < 0, at the
vertex). Its crossing is a root on that edge where the solid's boundary truly is: a root of f where every clip
is <= 0, or a clip's crossing where f and the other clips are <= 0. An edge with several such points (three
sheets through one edge) takes the middle one; an edge whose ends differ but where no root was found (a
vertex within rounding of the surface) takes the end nearer the surface, and is counted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.region import Clip, Grid
from implgen.mesh.shapelib import ShapeLib


@dataclass
class Crossings:
    """Active edges along one axis: `edges` (flat index of the edge's lower vertex), their crossing points,
    unit normals (toward f > 0 of the piece that bounds the solid there; 0 where the gradient vanishes), and
    which piece: 0 for f, k >= 1 for clips[k - 1]."""

    edges: np.ndarray
    points: np.ndarray
    normals: np.ndarray
    piece: np.ndarray
    fallback: int
    hidden: int  # edges whose two ends agree but that hold boundary points (a sheet poking through, a tangency)
    inner_edge: np.ndarray | None = None  # per interval between two boundary points on one edge: the edge
    inner_ends: np.ndarray | None = None  # (k, 2, 3): the interval's two boundary points


def clip_values(clips: list[Clip], p: np.ndarray) -> np.ndarray:
    """(len(clips), ...) values of every clip at p."""
    return np.stack([c.value(p) for c in clips]) if clips else np.zeros((0,) + p.shape[:-1])


def inside_flags(lib: ShapeLib, clips: list[Clip], p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(inside, g) at points p: g = max(f, clips), inside = g < 0."""
    g = lib.value(p)
    cv = clip_values(clips, p)
    if len(cv):
        g = np.maximum(g, cv.max(axis=0))
    return g < 0, g


def grid_flags(lib: ShapeLib, clips: list[Clip], grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """inside_flags at every vertex of the grid, without an array of its points."""
    x, y, z = (grid.coords(a) for a in range(3))
    g = lib.values_grid(x, y, z)
    for c in clips:
        np.maximum(g, c.on_grid(x, y, z), out=g)
    return g < 0, g


def piece_value_gradient(lib: ShapeLib, clips: list[Clip], j: int, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(value, gradient) at points p of piece j: 0 for f, j >= 1 for clips[j - 1]."""
    if j == 0:
        return lib.value_gradient(p)
    return clips[j - 1].value(p), clips[j - 1].gradient(p)


def boundary_value_gradient(lib: ShapeLib, clips: list[Clip], p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """g = max(f, clips) at points p (n, 3), and the gradient of the piece that attains it."""
    f, g = lib.value_gradient(p)
    if clips:
        cv = clip_values(clips, p)
        top = cv.argmax(axis=0)
        use = cv.max(axis=0) > f
        f = np.where(use, cv.max(axis=0), f)
        for k, c in enumerate(clips):
            sel = use & (top == k)
            g[sel] = c.gradient(p[sel])
    return f, g


def unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = np.where((n > 0) & np.isfinite(n), v / n, 0.0)
    return u


def line_points(lib: ShapeLib, clips: list[Clip], length: float, axis: int, starts: np.ndarray):
    """Every boundary point of the solid on the lines along `axis` starting at `starts` (L, 3), up to `length`
    along them: (line, t, piece), t measured from the line's start, in order of line and, without clips, of t
    along it."""
    d = np.zeros(3)
    d[axis] = 1.0
    roots, counts = lib.roots(starts, d, 0.0, length)
    lines, cols = np.nonzero(np.arange(roots.shape[1])[None, :] < counts[:, None])
    if not clips:
        return lines, roots[lines, cols], np.zeros(lines.size, dtype=np.int32)
    ts = [roots[lines, cols]]
    ls = [lines]
    pieces = [np.zeros(lines.size, dtype=np.int32)]
    for k, c in enumerate(clips):
        x = c.crossings(axis, starts)
        li, ci = np.nonzero(np.isfinite(x))
        t = x[li, ci] - starts[li, axis]
        ok = (t >= 0) & (t <= length)
        ts.append(t[ok])
        ls.append(li[ok])
        pieces.append(np.full(int(ok.sum()), k + 1, dtype=np.int32))
    line = np.concatenate(ls)
    t = np.concatenate(ts)
    piece = np.concatenate(pieces)
    # the piece bounds the solid there only where every other piece is <= 0
    others = np.full(len(t), -np.inf)
    on_clip = np.flatnonzero(piece != 0)
    p = starts[line[on_clip]]
    p[:, axis] += t[on_clip]
    others[on_clip] = lib.value(p)
    for k, c in enumerate(clips):
        others = np.maximum(others, np.where(piece == k + 1, -np.inf, c.along(axis, starts, line, t)))
    keep = others <= 0
    if not keep[lines.size :].any():  # no clip bounds the solid on these lines: f's roots, already in order
        return lines[keep[: lines.size]], t[: lines.size][keep[: lines.size]], piece[: lines.size][keep[: lines.size]]
    order = np.lexsort((t[keep], line[keep]))
    return line[keep][order], t[keep][order], piece[keep][order]


def axis_crossings(
    lib: ShapeLib, clips: list[Clip], grid: Grid, axis: int, inside: np.ndarray, g: np.ndarray
) -> Crossings:
    """The active edges along `axis` and their crossings. inside, g: per vertex (n0+1, n1+1, n2+1)."""
    shape = inside.shape
    strides = np.array([shape[1] * shape[2], shape[2], 1])
    lo_sl = tuple(slice(0, -1) if a == axis else slice(None) for a in range(3))
    hi_sl = tuple(slice(1, None) if a == axis else slice(None) for a in range(3))
    idx = np.nonzero(inside[lo_sl] != inside[hi_sl])  # views: no copy of the flags
    active = np.ravel_multi_index(idx, shape)  # ascending
    # the lines: vertices with index 0 along the axis, in flat vertex numbering
    base_idx = np.indices(tuple(1 if a == axis else s for a, s in enumerate(shape))).reshape(3, -1)
    base = np.ravel_multi_index(tuple(base_idx), shape)
    starts = grid.point(base)
    line, t, piece = line_points(lib, clips, grid.n[axis] * grid.h, axis, starts)
    step = np.clip(np.floor(t / grid.h).astype(np.int64), 0, shape[axis] - 2)
    key = base[line] + step * strides[axis]
    at = np.minimum(np.searchsorted(active, key), max(active.size - 1, 0))
    on = (active[at] == key) if active.size else np.zeros(key.size, dtype=bool)
    # in order of line and t, one edge's points are consecutive: runs of one key
    run = np.flatnonzero(np.concatenate([[True], key[1:] != key[:-1]])) if key.size else np.zeros(0, dtype=np.int64)
    count = np.diff(np.append(run, key.size))
    hidden = int((~on[run]).sum())  # edges whose ends agree but that hold points
    pair = np.flatnonzero(key[1:] == key[:-1]) if key.size else np.zeros(0, dtype=np.int64)
    ends = np.repeat(starts[line[pair]][:, None, :], 2, axis=1)  # consecutive points of one edge: an interval
    ends[:, 0, axis] += t[pair]
    ends[:, 1, axis] += t[pair + 1]
    run, count = run[on[run]], count[on[run]]
    pick = run + count // 2  # an edge with several points: the middle one
    slot = at[run]
    found = np.zeros(active.size, dtype=bool)
    found[slot] = True
    points = np.empty((active.size, 3))
    pieces = np.zeros(active.size, dtype=np.int32)
    points[slot] = starts[line[pick]]
    points[slot, axis] += t[pick]
    pieces[slot] = piece[pick]
    miss = np.nonzero(~found)[0]
    if miss.size:  # an end within rounding of the surface: the end nearer it
        lo_v = active[miss]
        hi_v = lo_v + strides[axis]
        gf = g.reshape(-1)
        end = np.where(np.abs(gf[lo_v]) <= np.abs(gf[hi_v]), lo_v, hi_v)
        points[miss] = grid.point(end)
    _, grad = lib.value_gradient(points)  # then the clips' own where they bound the solid
    for j in np.unique(pieces[pieces != 0]):
        sel = np.flatnonzero(pieces == j)
        grad[sel] = piece_value_gradient(lib, clips, int(j), points[sel])[1]
    return Crossings(
        edges=active, points=points, normals=unit(grad), piece=pieces, fallback=int(miss.size), hidden=hidden,
        inner_edge=key[pair], inner_ends=ends,
    )  # fmt: skip
