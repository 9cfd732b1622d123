"""Singular points of f = 0 (f = 0 and grad f = 0: nodes, cusps) in a box, by subdivision and Newton.

Subdivision: a cell is kept while each of f, f_x, f_y, f_z may vanish in it, and split in eight, level after
level. A gradient component may vanish when the range of its values at the eight corners and the centre,
widened on both sides by twice that range's width (once on the last two levels, where the cells are small
enough for it to be nearly linear), holds 0: a crude Lipschitz bound, which also keeps a cusp's component that
touches zero without changing sign. f may vanish when it changes sign at the samples or one of them is within
2 |grad f| x the diagonal of 0 (a node where f keeps one sign at every corner, its other sign in a narrow cone,
is kept). Near an isolated singular point each component of the gradient is close to linear, and a plane
through a point inside a cube leaves corners on both sides, so its cell is kept. This is a search, not a
proof: a cell dropped is one where the samples rule out a zero, not one where interval arithmetic does.

Newton: Gauss-Newton on the four equations (f / size, f_x, f_y, f_z) in three unknowns, from the centre of each
kept cell, the Hessian by central differences of the generated gradient (the residual is exact, so the limit is
the true point; the step is only slower). A limit is a singular point when f and grad f vanish there to within
a tiny fraction of their sizes over the box; limits closer than 1e-7 of the box are one point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.cells import CORNER_OFFSETS
from implgen.mesh.shapelib import ShapeLib

START = 16  # cells along the longest side at the first level
LEVELS = 5  # halvings after it: cells of 1/512 of the box at the end
MAX_CELLS = 2_000_000  # more candidates than this: the singular set is not a set of points (a curve)
CHUNK = 100_000  # cells evaluated at once (8 corners x 4 values each)
MAX_REPORTED = 2000  # more distinct points than this: a singular curve, reported as incomplete


@dataclass
class Singular:
    points: np.ndarray  # (k, 3)
    complete: bool  # False when the search stopped at MAX_CELLS (a singular curve, say)


def _keep(vals: np.ndarray, widen: float, h: float) -> np.ndarray:
    """vals (9, cells, 4), sample first: whether f and its gradient may all vanish in the cell. A gradient
    component: its corner range, widened by `widen` times its width on each side, holds 0. f: it changes sign,
    or some sample is within 2 |grad f| x the cell's diagonal of zero (f's own slope bounds how far it moves)."""
    lo, hi = np.minimum.reduce(vals), np.maximum.reduce(vals)
    w = widen * (hi - lo)
    grad_ok = ((lo[:, 1:] - w[:, 1:] <= 0) & (hi[:, 1:] + w[:, 1:] >= 0)).all(axis=1)
    g2 = vals[..., 1] ** 2 + vals[..., 2] ** 2 + vals[..., 3] ** 2
    slope = np.sqrt(np.maximum.reduce(g2))
    f_ok = (lo[:, 0] <= 0) & (hi[:, 0] >= 0) | (np.minimum.reduce(np.abs(vals[..., 0])) <= 2 * slope * h * np.sqrt(3))
    return grad_ok & f_ok


def _corners(lib: ShapeLib, lo: np.ndarray, h: float) -> np.ndarray:
    """f and grad f at the 8 corners and the centre of each cell: (9, cells, 4). The centre catches a component
    that touches zero without changing sign midway between corners where it is equal (a cusp's)."""
    offs = np.concatenate([CORNER_OFFSETS, [[0.5, 0.5, 0.5]]])
    p = lo[None, :, :] + (offs * h)[:, None, :]  # (9, cells, 3): sample first
    f, g = lib.value_gradient(p)
    return np.concatenate([f[..., None], g], axis=-1)


def _newton(lib: ShapeLib, p: np.ndarray, size: float, steps: int = 60) -> np.ndarray:
    eps = 1e-6 * size
    p = p.copy()
    live = np.arange(len(p))
    for _ in range(steps):
        if live.size == 0:
            break
        q = p[live]
        f, g = lib.value_gradient(q)
        hess = lib.gradient_jacobian(q, eps)
        jac = np.concatenate([g[:, None, :] / size, hess], axis=1)  # (n, 4, 3)
        res = np.concatenate([f[:, None] / size, g], axis=1)
        jtj = np.einsum("nki,nkj->nij", jac, jac)
        jtj += (1e-14 * np.trace(jtj, axis1=1, axis2=2) + 1e-300)[:, None, None] * np.eye(3)
        jtr = np.einsum("nki,nk->ni", jac, res)
        with np.errstate(all="ignore"):
            step = np.linalg.solve(jtj, jtr[..., None])[..., 0]
        step = np.where(np.isfinite(step), step, 0.0)
        step = np.clip(step, -0.1 * size, 0.1 * size)
        p[live] = q - step
        live = live[np.abs(step).max(axis=1) > 1e-15 * size]
    return p


def find_singular(lib: ShapeLib, lo: np.ndarray, hi: np.ndarray) -> Singular:
    """The singular points of f = 0 in the box [lo, hi]."""
    size = float((hi - lo).max())
    h = size / START
    n = np.maximum(np.ceil((hi - lo) / h).astype(int), 1)
    idx = np.indices(tuple(n)).reshape(3, -1).T
    cells = lo + h * idx
    scale_f = scale_g = 0.0
    complete = True
    for level in range(LEVELS + 1):
        widen = 2.0 if level < LEVELS - 1 else 1.0
        kept = [np.zeros((0, 3))]
        for at in range(0, len(cells), CHUNK):
            vals = _corners(lib, cells[at : at + CHUNK], h)
            if level == 0:
                scale_f = max(scale_f, float(np.abs(vals[..., 0]).max()))  # the sizes f and grad f take
                scale_g = max(scale_g, float(np.linalg.norm(vals[..., 1:], axis=-1).max()))
            kept.append(cells[at : at + CHUNK][_keep(vals, widen, h)])
        cells = np.concatenate(kept)
        if level == LEVELS:
            break
        if len(cells) * 8 > MAX_CELLS:
            complete = False
            break
        h /= 2
        offs = np.array([[c & 1, c >> 1 & 1, c >> 2 & 1] for c in range(8)], dtype=np.float64) * h
        cells = (cells[:, None, :] + offs[None]).reshape(-1, 3)
    if len(cells) == 0:
        return Singular(points=np.zeros((0, 3)), complete=complete)
    p = _newton(lib, cells + 0.5 * h, size, steps=6)  # a few steps from every cell, then the distinct ones on
    p = p[np.isfinite(p).all(axis=1)]
    _, first = np.unique(np.round((p - lo) / (1e-5 * size)).astype(np.int64), axis=0, return_index=True)
    p = _newton(lib, p[np.sort(first)], size)
    f, g = lib.value_gradient(p)
    ok = np.isfinite(p).all(axis=1) & (p >= lo - 1e-9 * size).all(axis=1) & (p <= hi + 1e-9 * size).all(axis=1)
    ok &= np.abs(f) <= 1e-12 * max(scale_f, 1e-300)
    ok &= np.linalg.norm(g, axis=1) <= 1e-9 * max(scale_g, 1e-300)
    p = p[ok]
    if len(p) == 0:
        return Singular(points=np.zeros((0, 3)), complete=complete)
    # one point per cluster: snapped to 1e-7 of the box, then neighbours across a snapping line merged
    _, first = np.unique(np.round((p - lo) / (1e-7 * size)).astype(np.int64), axis=0, return_index=True)
    pts = p[np.sort(first)]
    if len(pts) <= MAX_REPORTED:
        keep: list[int] = []
        for i in range(len(pts)):
            if not keep or np.abs(pts[keep] - pts[i]).max(axis=1).min() > 1e-7 * size:
                keep.append(i)
        pts = pts[keep]
    pts = pts[np.lexsort(pts.T[::-1])]
    if len(pts) > MAX_REPORTED:  # not isolated points: a curve of them; a sample is reported
        complete = False
        pts = pts[:: -(-len(pts) // MAX_REPORTED)]
    return Singular(points=pts, complete=complete)
