"""Singular points of f = 0 (f = 0 and grad f = 0: nodes, cusps) in a box, by subdivision and Newton.

Subdivision: a cell is kept while each of f, f_x, f_y, f_z may vanish in it -- the range of its values at the
eight corners, widened on both sides by that range's own width (a crude Lipschitz bound: it keeps a cusp's
component that touches zero without changing sign), holds 0 -- and split in eight, level after level. Near an
isolated singular point each component of the gradient is close to linear, and a plane through a point inside
a cube leaves corners on both sides, so its cell is kept. This is a search, not a proof: a cell dropped is one
where the samples rule out a zero, not one where interval arithmetic does.

Newton: Gauss-Newton on the four equations (f / size, f_x, f_y, f_z) in three unknowns, from the centre of each
kept cell, the Hessian by central differences of the generated gradient (the residual is exact, so the limit is
the true point; the step is only slower). A limit is a singular point when f and grad f vanish there to within
a tiny fraction of their sizes over the box; limits closer than 1e-7 of the box are one point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.shapelib import ShapeLib

START = 16  # cells along the longest side at the first level
LEVELS = 5  # halvings after it: cells of 1/512 of the box at the end
MAX_CELLS = 400_000  # more candidates than this: the singular set is not a set of points (a curve)


@dataclass
class Singular:
    points: np.ndarray  # (k, 3)
    complete: bool  # False when the search stopped at MAX_CELLS (a singular curve, say)


def _keep(vals: np.ndarray) -> np.ndarray:
    """vals (cells, 8, 4): whether every one of the 4 functions may vanish in the cell."""
    lo, hi = vals.min(axis=1), vals.max(axis=1)
    w = hi - lo
    return ((lo - w <= 0) & (hi + w >= 0)).all(axis=1)


def _corners(lib: ShapeLib, lo: np.ndarray, h: float) -> np.ndarray:
    offs = np.array([[c & 1, c >> 1 & 1, c >> 2 & 1] for c in range(8)], dtype=np.float64) * h
    p = lo[:, None, :] + offs[None, :, :]
    f, g = lib.value_gradient(p)
    return np.concatenate([f[..., None], g], axis=-1)


def _newton(lib: ShapeLib, p: np.ndarray, size: float, steps: int = 60) -> np.ndarray:
    eps = 1e-6 * size
    for _ in range(steps):
        f, g = lib.value_gradient(p)
        hess = np.empty((len(p), 3, 3))
        for k in range(3):
            dp = np.zeros(3)
            dp[k] = eps
            _, gp = lib.value_gradient(p + dp)
            _, gm = lib.value_gradient(p - dp)
            hess[:, :, k] = (gp - gm) / (2 * eps)
        jac = np.concatenate([g[:, None, :] / size, hess], axis=1)  # (n, 4, 3)
        res = np.concatenate([f[:, None] / size, g], axis=1)
        jtj = np.einsum("nki,nkj->nij", jac, jac) + 1e-300 * np.eye(3)
        jtr = np.einsum("nki,nk->ni", jac, res)
        with np.errstate(all="ignore"):
            step = np.linalg.solve(jtj, jtr[..., None])[..., 0]
        step = np.where(np.isfinite(step), step, 0.0)
        step = np.clip(step, -0.1 * size, 0.1 * size)
        p = p - step
        if np.abs(step).max(initial=0.0) <= 1e-15 * size:
            break
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
        vals = _corners(lib, cells, h)
        if level == 0:
            scale_f = float(np.abs(vals[..., 0]).max())
            scale_g = float(np.linalg.norm(vals[..., 1:], axis=-1).max())
        cells = cells[_keep(vals)]
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
    p = _newton(lib, cells + 0.5 * h, size)
    f, g = lib.value_gradient(p)
    ok = np.isfinite(p).all(axis=1) & (p >= lo - 1e-9 * size).all(axis=1) & (p <= hi + 1e-9 * size).all(axis=1)
    ok &= np.abs(f) <= 1e-12 * max(scale_f, 1e-300)
    ok &= np.linalg.norm(g, axis=1) <= 1e-9 * max(scale_g, 1e-300)
    p = p[ok]
    out: list[np.ndarray] = []
    for q in p[np.lexsort(p.T[::-1])]:
        if not any(np.abs(q - r).max() <= 1e-7 * size for r in out):
            out.append(q)
    pts = np.array(out).reshape(-1, 3)
    return Singular(points=pts, complete=complete)
