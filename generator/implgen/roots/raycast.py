"""Ray/shape intersection for the generated Python modules: NumPy twin of `ig_shape_roots` (runtime_c/shape.c).

The ray is clipped to the shape's box; the coefficients of f(o + t d) are computed at a shifted origin
o' = o + ts d next to the object (the point of the clipped interval closest to the centre of the box's
finite axes, or to the coordinate origin when there is none) and solved in s = t - ts by the C batch
solver; t = ts + s. Computed at a far origin, the coefficients would lose everything to cancellation.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from implgen.abi import grown_box
from implgen.roots.solvers import first_root_batch, real_roots_batch

CoeffsFn = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _clip(box: np.ndarray | None, o: np.ndarray, d: np.ndarray, t0: np.ndarray, t1: np.ndarray):
    """Slab clip against box (any bound may be +-inf); returns (t0, t1, valid)."""
    valid = t0 <= t1
    if box is None:
        return t0, t1, valid
    lo, hi = grown_box(box)  # as shape.c grows it: a surface touching its box keeps that root
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        ta = (lo - o) * inv
        tb = (hi - o) * inv
    near = np.minimum(ta, tb)
    far = np.maximum(ta, tb)
    parallel = d == 0.0
    outside = parallel & ((o < lo) | (o > hi))
    near = np.where(parallel, -np.inf, near)
    far = np.where(parallel, np.inf, far)
    t0 = np.maximum(t0, near.max(axis=-1))
    t1 = np.minimum(t1, far.min(axis=-1))
    valid = valid & ~outside.any(axis=-1) & (t0 <= t1)
    return t0, t1, valid


def _shift_point(box: np.ndarray | None, o: np.ndarray, d: np.ndarray, t0: np.ndarray, t1: np.ndarray):
    """Same rule as shift_point() in shape.c."""
    num = np.zeros(o.shape[:-1])
    den = np.zeros(o.shape[:-1])
    if box is not None:
        finite = np.isfinite(box[:3]) & np.isfinite(box[3:])
        if finite.any():
            centre = np.where(finite, 0.5 * np.where(finite, box[:3], 0.0) + 0.5 * np.where(finite, box[3:], 0.0), 0.0)
            w = finite.astype(np.float64)
            num = (w * d * (centre - o)).sum(axis=-1)
            den = (w * d * d).sum(axis=-1)
    fallback = ~(den > 0.0)
    num = np.where(fallback, -(o * d).sum(axis=-1), num)
    den = np.where(fallback, (d * d).sum(axis=-1), den)
    with np.errstate(divide="ignore", invalid="ignore"):
        ts = num / den
    ts = np.where(np.isfinite(ts), ts, 0.0)
    return np.clip(ts, t0, t1)


def _solve(
    coeffs_fn: CoeffsFn,
    box: ArrayLike | None,
    o: ArrayLike,
    d: ArrayLike,
    tmin: ArrayLike,
    tmax: ArrayLike,
    method: str,
    first: bool = False,
):
    """(batch shape, t per ray with NaN padding, counts); first=True asks the solver for the smallest root only
    (first_root_batch: one column, counts 0 or 1)."""
    o = np.asarray(o, dtype=np.float64)
    d = np.asarray(d, dtype=np.float64)
    if o.shape[-1:] != (3,) or d.shape[-1:] != (3,):
        raise ValueError("o and d need a last axis of length 3")
    batch = np.broadcast_shapes(o.shape[:-1], d.shape[:-1], np.shape(tmin), np.shape(tmax))
    o = np.broadcast_to(o, batch + (3,)).reshape(-1, 3)
    d = np.broadcast_to(d, batch + (3,)).reshape(-1, 3)
    t0 = np.broadcast_to(np.asarray(tmin, dtype=np.float64), batch).reshape(-1).copy()
    t1 = np.broadcast_to(np.asarray(tmax, dtype=np.float64), batch).reshape(-1).copy()
    bx = None if box is None else np.asarray(box, dtype=np.float64).reshape(6)
    good = np.isfinite(o).all(axis=-1) & np.isfinite(d).all(axis=-1) & (d != 0.0).any(axis=-1)
    good &= ~(np.isnan(t0) | np.isnan(t1))
    t0, t1, valid = _clip(bx, np.where(good[:, None], o, 0.0), np.where(good[:, None], d, 1.0), t0, t1)
    valid &= good
    ts = _shift_point(bx, o, d, np.where(valid, t0, 0.0), np.where(valid, t1, 0.0))
    ts = np.where(valid, ts, 0.0)
    shifted = np.where(valid[:, None], o + ts[:, None] * d, 0.0)
    c = np.asarray(coeffs_fn(shifted, np.where(valid[:, None], d, 1.0)), dtype=np.float64)
    c = c.reshape(shifted.shape[0], -1)
    lo = np.where(valid, t0 - ts, 1.0)
    hi = np.where(valid, t1 - ts, 0.0)  # lo > hi: no roots for rays that miss the box
    if first:
        s1, counts = first_root_batch(c, lo, hi, method)
        s = s1[:, None]
    else:
        s, counts = real_roots_batch(c, lo, hi, method)
    with np.errstate(invalid="ignore"):
        t = np.clip(ts[:, None] + s, t0[:, None], t1[:, None])
    return batch, t, counts


def nearest_hit(
    coeffs_fn: CoeffsFn,
    box: ArrayLike | None,
    o: ArrayLike,
    d: ArrayLike,
    tmin: ArrayLike = 0.0,
    tmax: ArrayLike = np.inf,
    method: str = "auto",
) -> np.ndarray:
    """Nearest root t in [tmin, tmax] per ray (np.inf for a miss), shape = broadcast batch shape."""
    return _nearest(coeffs_fn, box, o, d, tmin, tmax, method, first=False)


def first_hit(
    coeffs_fn: CoeffsFn,
    box: ArrayLike | None,
    o: ArrayLike,
    d: ArrayLike,
    tmin: ArrayLike = 0.0,
    tmax: ArrayLike = np.inf,
    method: str = "auto",
) -> np.ndarray:
    """nearest_hit through the first-root solver (`ig_first_root`: it stops at the smallest root instead of
    isolating all of them): nearest root t in [tmin, tmax] per ray, np.inf for a miss."""
    return _nearest(coeffs_fn, box, o, d, tmin, tmax, method, first=True)


def _nearest(coeffs_fn, box, o, d, tmin, tmax, method: str, first: bool) -> np.ndarray:
    """The smallest root per ray, np.inf where there is none, in the broadcast batch shape."""
    batch, t, counts = _solve(coeffs_fn, box, o, d, tmin, tmax, method, first=first)
    near = t[:, 0] if t.shape[1] else np.full(t.shape[0], np.inf)  # degree 0: no root column
    return np.where(counts > 0, near, np.inf).reshape(batch)


def all_hits(
    coeffs_fn: CoeffsFn,
    box: ArrayLike | None,
    o: ArrayLike,
    d: ArrayLike,
    tmin: float = 0.0,
    tmax: float = np.inf,
    method: str = "auto",
) -> np.ndarray:
    """All distinct roots t in [tmin, tmax] of ONE ray, ascending."""
    o = np.asarray(o, dtype=np.float64).reshape(3)
    d = np.asarray(d, dtype=np.float64).reshape(3)
    _, t, counts = _solve(coeffs_fn, box, o, d, tmin, tmax, method)
    return np.unique(t[0, : counts[0]])
