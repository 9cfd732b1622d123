"""Critical points of f near its zero set: where a thin neck, a narrow gap or a small piece of the solid can hide
between grid vertices, even where no grid line meets it.

The solid {f < 0} changes its topology only through critical points of f (Morse theory). Near a critical point
p with value f(p) and Hessian H, f reaches 0 from p along an eigenvector of H whose eigenvalue λ has the sign
opposite to f(p), at about sqrt(2 |f(p)| / |λ|): the radius of a neck (f < 0, a saddle), the half-width of a gap
(f > 0, a saddle), the radius of a small piece or hole (an extremum). That distance, the smallest over such
eigenvalues, is the feature's size; a feature less than half a cell across is one the grid may misread.

The search starts from the grid's own samples: a grid vertex where the vertex values g = max(f, clips) turn
along each of the three axes (the differences to its two neighbours along the axis of opposite signs, or zero)
is a discrete critical point; Newton's method on grad f = 0 from each (the Hessian by central differences of
the generated gradient, steps capped at a cell) finds the critical point near it. Those that stay within two
cells of their start, inside the grid and every clip, and where f does not vanish (a node is singular.py's),
are returned with their feature size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.crossings import clip_values
from implgen.mesh.region import Clip, Grid
from implgen.mesh.shapelib import ShapeLib

SLAB = 32  # grid planes along x examined at once (bounded memory on a 256-cell grid)
MAX_SEEDS = 200_000  # more discrete critical points than this: not isolated features; none is followed


@dataclass
class Critical:
    points: np.ndarray  # (k, 3)
    value: np.ndarray  # (k,) f there
    size: np.ndarray  # (k,) the feature's size: the distance at which f reaches 0, to second order


def seeds(g: np.ndarray) -> np.ndarray:
    """Flat indices of the interior grid vertices where g turns along every axis and whose feature, estimated
    from g's own differences (a parabola along each axis through the vertex and its two neighbours), is less
    than a cell across: the ones worth Newton's steps. The turns along the last axis first (contiguous, a plane
    of x at a time for bounded memory), then the other two at those vertices only."""
    found = []
    flat_g = g.reshape(-1)
    strides = (g.shape[1] * g.shape[2], g.shape[2], 1)
    for s in range(1, g.shape[0] - 1, SLAB):
        blk = g[s : min(s + SLAB, g.shape[0] - 1), 1:-1]
        d = np.diff(blk, axis=2)
        i, j, k = np.nonzero(d[..., :-1] * d[..., 1:] <= 0)
        flat = np.ravel_multi_index((i + s, j + 1, k + 1), g.shape)
        mid = flat_g[flat]
        sides = []
        for st in strides:
            lo, hi = flat_g[flat - st], flat_g[flat + st]
            sides.append((lo, hi))
            keep = (mid - lo) * (hi - mid) <= 0
            flat, mid, sides = flat[keep], mid[keep], [(lo_[keep], hi_[keep]) for lo_, hi_ in sides]
        found.append(flat[_estimate(mid, sides) < 1.0])
    return np.concatenate(found + [np.zeros(0, dtype=np.int64)])


def _estimate(mid: np.ndarray, sides: list) -> np.ndarray:
    """The feature's size in cells from the parabolas along the axes: the extreme value f* = g - sum d^2 / 2c
    (d the central difference, c the second), then sqrt(2 |f*| / |c|) for the largest |c| of sign opposite to
    f*; inf where none is."""
    d = np.stack([(hi - lo) / 2 for lo, hi in sides], axis=1)
    c = np.stack([hi - 2 * mid + lo for lo, hi in sides], axis=1)
    with np.errstate(all="ignore"):
        top = mid - np.where(c != 0, d * d / (2 * c), 0.0).sum(axis=1)
        opposite = np.where(c * np.sign(top)[:, None] < 0, np.abs(c), 0.0).max(axis=1)
        return np.where(opposite > 0, np.sqrt(2 * np.abs(top) / opposite), np.inf)


def _hessian(lib: ShapeLib, p: np.ndarray, eps: float) -> np.ndarray:
    hess = lib.gradient_jacobian(p, eps)
    return 0.5 * (hess + hess.transpose(0, 2, 1))


def newton(lib: ShapeLib, start: np.ndarray, h: float, size: float, steps: int = 40) -> tuple[np.ndarray, np.ndarray]:
    """Newton on grad f = 0 from each start, each step at most a cell: (points, converged)."""
    p = start.copy()
    ok = np.zeros(len(p), dtype=bool)
    live = np.arange(len(p))
    for _ in range(steps):
        if live.size == 0:
            break
        _, g = lib.value_gradient(p[live])
        hess = _hessian(lib, p[live], 1e-6 * size)
        hess += (1e-14 * np.abs(hess).sum(axis=(1, 2)) + 1e-300)[:, None, None] * np.eye(3)
        with np.errstate(all="ignore"):
            step = np.linalg.solve(hess, g[..., None])[..., 0]
        bad = ~np.isfinite(step).all(axis=1)
        step[bad] = 0.0
        longest = np.abs(step).max(axis=1)
        step *= np.minimum(1.0, h / np.maximum(longest, 1e-300))[:, None]
        p[live] -= step
        done = longest <= 1e-12 * size
        ok[live[done & ~bad]] = True
        live = live[~done & ~bad]
    return p, ok


def feature_size(value: np.ndarray, hess: np.ndarray) -> np.ndarray:
    """sqrt(2 |f| / |λ|) for the largest |λ| of sign opposite to f; inf where no eigenvalue is."""
    lam = np.linalg.eigvalsh(hess)
    opposite = np.where(lam * np.sign(value)[:, None] < 0, np.abs(lam), 0.0)
    top = opposite.max(axis=1)
    with np.errstate(divide="ignore"):
        return np.where(top > 0, np.sqrt(2 * np.abs(value) / np.maximum(top, 1e-300)), np.inf)


def critical_points(lib: ShapeLib, clips: list[Clip], grid: Grid, g: np.ndarray) -> Critical:
    """The critical points of f next to the grid's discrete ones (see the module's docstring)."""
    empty = Critical(np.zeros((0, 3)), np.zeros(0), np.zeros(0))
    flat = seeds(g)
    if flat.size == 0 or flat.size > MAX_SEEDS:
        return empty
    start = grid.point(flat)
    own = lib.value(start) == g.reshape(-1)[flat]  # g is f there, not a clip (the clips' max turns too)
    start = start[own]
    p, ok = newton(lib, start, grid.h, grid.size)
    ok &= (np.abs(p - start).max(axis=1) <= 2 * grid.h) & np.isfinite(p).all(axis=1)
    p = p[ok]
    if not len(p):
        return empty
    _, first = np.unique(np.round((p - grid.origin) / (1e-6 * grid.size)).astype(np.int64), axis=0, return_index=True)
    p = p[np.sort(first)]
    cv = clip_values(clips, p)
    keep = (cv <= 0).all(axis=0) if len(cv) else np.ones(len(p), dtype=bool)
    f = lib.value(p)
    keep &= np.abs(f) > 1e-12 * max(float(np.abs(g).max()), 1e-300)  # f vanishes too: a singular point
    p, f = p[keep], f[keep]
    if not len(p):
        return empty
    return Critical(p, f, feature_size(f, _hessian(lib, p, 1e-6 * grid.size)))
