"""Dual vertices: the point of each sheet of a cell, from the exact crossings on its edges.

First the QEF of dual contouring (Ju, Losasso, Schaefer and Warren 2002): the point nearest, in least squares,
to the tangent planes at the sheet's crossings (exact points, unit normals from the generated gradient), with
the small eigenvalues of the normal matrix dropped (a flat or curved piece keeps to the crossings' mass point
along it; a crease or a corner is located), clamped to the cell: one C loop over the cells
(ShapeLib.sheet_points). Then onto the surface itself: Newton steps of least norm on the pieces that bound the
sheet (f alone on a smooth sheet, in C too; f and a clip on a cap's rim, two clip planes on a box's edge), so
every vertex lies on the true boundary up to rounding. A projection that does not converge or strays beyond a
cell is reported, and contour.py puts that vertex on the sheet's nearest crossing.
"""

from __future__ import annotations

import numpy as np

from implgen.mesh.crossings import piece_value_gradient
from implgen.mesh.region import Clip
from implgen.mesh.shapelib import ShapeLib

# The QEF is one C loop over the cells (ig_mesh_sheet_points, runtime_c/mesh_kernels.c), given these two:
DROP = 0.1  # eigenvalues below DROP x the largest are dropped (the usual truncation of the QEF's SVD)
CREASE = 0.9  # a sheet whose crossing normals all lie within acos(0.9) = 26 degrees of their mean is smooth
NOISE = 1e-10  # a Newton step still this large (times the box) after the last step: f's rounding, accepted


def piece_mask(vid: np.ndarray, piece: np.ndarray, nverts: int) -> np.ndarray:
    """Per vertex, the bit mask of the pieces (bit j: piece j) of its crossings."""
    mask = np.zeros(nverts, dtype=np.int64)
    for j in np.unique(piece):
        mask[np.bincount(vid[piece == j], minlength=nverts) > 0] |= np.int64(1) << np.int64(j)
    return mask


def _pieces_eval(lib: ShapeLib, clips: list[Clip], ids: list[int], p: np.ndarray):
    """Residuals (n, k) and gradients (n, k, 3) of the pieces `ids` (0: f, j: clips[j - 1]) at p."""
    res, jac = zip(*(piece_value_gradient(lib, clips, j, p) for j in ids))
    return np.stack(res, axis=1), np.stack(jac, axis=1)


def project(
    lib: ShapeLib,
    clips: list[Clip],
    start: np.ndarray,
    mask: np.ndarray,
    h: float,
    scale: float,
    steps: int = 40,
) -> tuple[np.ndarray, np.ndarray]:
    """Each start point moved onto every piece in its bit mask (bit j: piece j): (points, projected flags).
    Converged: a step below 1e-13 of `scale` (the box), or the last of `steps` below NOISE of it."""
    tol = 1e-13 * scale
    out = start.copy()
    done = np.zeros(len(start), dtype=bool)
    for m in np.unique(mask):
        ids = [j for j in range(int(m).bit_length()) if (int(m) >> j) & 1]
        sel = np.nonzero(mask == m)[0]
        if not ids or len(ids) > 3:
            continue
        if ids == [0]:  # f alone (most vertices): the same steps in one C loop, the same reach
            p, ok = lib.project(start[sel], steps, tol, NOISE * scale, 2 * h)
        else:
            p, ok = _newton_pieces(lib, clips, ids, start[sel], steps, tol, scale)
            ok &= (np.abs(p - start[sel]) <= 2 * h).all(axis=1)  # NaN fails it too
        out[sel[ok]] = p[ok]
        done[sel[ok]] = True
    return out, done


def _newton_pieces(
    lib: ShapeLib, clips: list[Clip], ids: list[int], start: np.ndarray, steps: int, tol: float, scale: float
) -> tuple[np.ndarray, np.ndarray]:
    """project() onto the pieces `ids` at once (a rim, a box's edge), or onto one clip: (points, converged)."""
    p = start.copy()
    ok = np.zeros(len(p), dtype=bool)
    live = np.arange(len(p))
    last = live_before = np.zeros(0)
    prev = np.full(len(p), np.inf)
    for _ in range(steps):
        if live.size == 0:
            break
        r, jac = _pieces_eval(lib, clips, ids, p[live])
        with np.errstate(all="ignore"):
            if len(ids) == 1:  # one piece: the step along its gradient, no solve
                g = jac[:, 0, :]
                step = -(r[:, 0] / (g * g).sum(axis=1))[:, None] * g
            else:
                jjt = np.einsum("nki,nli->nkl", jac, jac)
                jjt += (1e-14 * np.trace(jjt, axis1=1, axis2=2) + 1e-300)[:, None, None] * np.eye(len(ids))
                y = np.linalg.solve(jjt, r[..., None])[..., 0]
                step = -np.einsum("nki,nk->ni", jac, y)
        bad = ~np.isfinite(step).all(axis=1)
        step[bad] = 0.0
        p[live] += step
        size = np.linalg.norm(step, axis=1)
        # converged: a step below tol, or at f's rounding (no longer halving, and below NOISE)
        stalled = (size > 0.5 * prev[live]) & (size <= NOISE * scale)
        small = (size <= tol) | stalled
        ok[live[small & ~bad]] = True
        prev[live] = size
        last = size
        live_before = live
        live = live[~small & ~bad]
    if live.size:  # still moving by f's rounding only: as near as f can tell
        ok[live] = last[np.searchsorted(live_before, live)] <= NOISE * scale
    return p, ok


def outside_pieces(lib: ShapeLib, clips: list[Clip], p: np.ndarray, mask: np.ndarray, size: float) -> np.ndarray:
    """Bit mask, per point, of the pieces not in `mask` that are positive there by more than 1e-12 of the box
    (to first order): a cap vertex outside f, a surface vertex outside a clip. Each piece is evaluated only at
    the points whose mask lacks it, its gradient only where it is positive."""
    out = np.zeros(len(p), dtype=np.int64)
    for j in range(len(clips) + 1):
        sel = np.flatnonzero(((mask >> j) & 1) == 0)
        at = p if sel.size == len(p) else p[sel]  # most often every point: no copy
        v = lib.value(at) if j == 0 else clips[j - 1].value(at)
        sel = sel[v > 0]
        if sel.size == 0:
            continue
        v, g = piece_value_gradient(lib, clips, j, p[sel])
        dist = v / np.maximum(np.linalg.norm(g, axis=1), 1e-300)
        out[sel[dist > 1e-12 * size]] |= np.int64(1) << np.int64(j)
    return out
