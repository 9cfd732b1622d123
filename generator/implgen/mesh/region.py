"""Where the mesh lives: the clip the user asks for (`--clip sphere:R|box:H`), the spec's own box, and the grid
of cubic cells that covers their intersection.

The solid meshed is f < 0 intersected with every clip, each a set c < 0: a ball (|p|^2 - R^2), or half-spaces
(one per finite side of a box: x - hi, lo - x). Clips are kept as separate simple pieces so each has an exact
value, gradient and crossing with an axis-parallel grid line. The grid is shifted off the box by a small
irrational fraction of a cell, so no grid vertex falls on a symmetry plane of the shape (where nodes, axes
and cusps of the example shapes sit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from implgen.errors import UserError
from implgen.validate import MAX_COORDINATE

SHIFT = (math.sqrt(2) - 1) / 7  # of a cell, per axis times (1, 1.37, 1.71): irrational, small, never symmetric


@dataclass(frozen=True)
class Sphere:
    """The ball |p - center| < radius (a scene's clip may have its centre off the origin)."""

    radius: float
    center: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def value(self, p: np.ndarray) -> np.ndarray:
        q = p - np.asarray(self.center)
        return np.einsum("...i,...i->...", q, q) - self.radius**2

    def gradient(self, p: np.ndarray) -> np.ndarray:
        return 2.0 * (p - np.asarray(self.center))

    def on_grid(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """The value at every (x[i], y[j], z[k]), by broadcasting."""
        x, y, z = x - self.center[0], y - self.center[1], z - self.center[2]
        return (x * x)[:, None, None] + (y * y)[None, :, None] + (z * z)[None, None, :] - self.radius**2

    def crossings(self, axis: int, others: np.ndarray) -> np.ndarray:
        """Where lines along `axis` (through the points `others`, (n, 3), the axis' own column ignored) meet
        the sphere: (n, 2) coordinates along the axis, NaN where they miss."""
        q = np.delete(others - np.asarray(self.center), axis, axis=1)
        disc = self.radius**2 - (q * q).sum(axis=1)
        r = np.sqrt(np.where(disc > 0, disc, np.nan))
        return np.stack([-r, r], axis=1) + self.center[axis]

    def along(self, axis: int, starts: np.ndarray, line: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The value at starts[line] + t along `axis` (points on grid lines)."""
        p = starts[line].copy()
        p[:, axis] += t
        return self.value(p)

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        return np.asarray(self.center) - self.radius, np.asarray(self.center) + self.radius


@dataclass(frozen=True)
class HalfSpace:
    """sign * (p[axis] - at) < 0: x < at for sign +1, x > at for sign -1."""

    axis: int
    at: float
    sign: float

    def value(self, p: np.ndarray) -> np.ndarray:
        return self.sign * (p[..., self.axis] - self.at)

    def on_grid(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        v = self.sign * ((x, y, z)[self.axis] - self.at)
        return v.reshape(tuple(-1 if a == self.axis else 1 for a in range(3)))

    def gradient(self, p: np.ndarray) -> np.ndarray:
        g = np.zeros(p.shape)
        g[..., self.axis] = self.sign
        return g

    def along(self, axis: int, starts: np.ndarray, line: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The value at starts[line] + t along `axis`: constant on a line across the plane's axis."""
        if axis == self.axis:
            return self.sign * ((starts[line, axis] + t) - self.at)
        return (self.sign * (starts[:, self.axis] - self.at))[line]

    def crossings(self, axis: int, others: np.ndarray) -> np.ndarray:
        if axis != self.axis:
            return np.full((others.shape[0], 0), np.nan)
        return np.full((others.shape[0], 1), self.at)

    def box(self) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = np.full(3, -np.inf), np.full(3, np.inf)
        (hi if self.sign > 0 else lo)[self.axis] = self.at
        return lo, hi


Clip = Sphere | HalfSpace


def parse_clip(text: str) -> list[Clip]:
    """`sphere:R` (the ball of radius R about the origin) or `box:H` (the cube [-H, H]^3)."""
    kind, _, size = text.partition(":")
    if kind not in ("sphere", "box") or not size:
        raise UserError(f"--clip {text}", "expected sphere:R or box:H (R, H > 0)")
    try:
        value = float(size)
    except ValueError:
        raise UserError(f"--clip {text}", f"{size!r} is not a number") from None
    if not (0 < value <= MAX_COORDINATE):
        raise UserError(f"--clip {text}", f"the size must be in (0, {MAX_COORDINATE:g}]")
    if kind == "sphere":
        return [Sphere(value)]
    return box_clips([-value] * 3, [value] * 3)


def box_clips(lo, hi) -> list[Clip]:
    """The half-spaces of a box's finite sides."""
    out: list[Clip] = []
    for a in range(3):
        if math.isfinite(lo[a]):
            out.append(HalfSpace(a, float(lo[a]), -1.0))
        if math.isfinite(hi[a]):
            out.append(HalfSpace(a, float(hi[a]), 1.0))
    return out


@dataclass(frozen=True)
class Grid:
    """Cubic cells of side h; vertex (i, j, k) at origin + h (i, j, k), i < n[0] + 1 and so on."""

    origin: np.ndarray
    h: float
    n: tuple[int, int, int]

    def coords(self, axis: int) -> np.ndarray:
        return self.origin[axis] + self.h * np.arange(self.n[axis] + 1)

    @property
    def shape(self) -> tuple[int, int, int]:
        return (self.n[0] + 1, self.n[1] + 1, self.n[2] + 1)

    def point(self, flat: np.ndarray) -> np.ndarray:
        """Coordinates of vertices given by flat (C order) index, (k, 3): the same doubles coords() holds."""
        idx = np.stack(np.unravel_index(flat, self.shape), axis=1)
        return self.origin + self.h * idx.astype(np.float64)

    @property
    def size(self) -> float:
        return self.h * max(self.n)


def spec_box_clips(box: list[float] | None, margin: float) -> list[Clip]:
    """The spec's box as half-spaces, grown by `margin` on every finite side (so a closed surface that touches
    its own box, the torus at |x| = a + b, is never capped there)."""
    if box is None:
        return []
    lo = [v - margin for v in box[:3]]
    hi = [v + margin for v in box[3:]]
    return box_clips(lo, hi)


def region_box(box: list[float] | None, user: list[Clip], what: str) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi): the box of (spec box ∩ user clip). A region open along some axis is a UserError naming `what`."""
    lo = np.array(box[:3] if box else [-np.inf] * 3, dtype=np.float64)
    hi = np.array(box[3:] if box else [np.inf] * 3, dtype=np.float64)
    for c in user:
        clo, chi = c.box()
        lo, hi = np.maximum(lo, clo), np.minimum(hi, chi)
    if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
        raise UserError(what, "the shape is unbounded along some axis: give --clip sphere:R or --clip box:H")
    if not (hi > lo).all():
        raise UserError(what, "the clip and the shape's box do not overlap")
    return lo, hi


def make_grid(box: list[float] | None, user: list[Clip], cells: int, what: str) -> tuple[Grid, list[Clip]]:
    """The grid over (spec box ∩ user clip), `cells` cells along its longest side, and every clip that bounds
    the solid. A region open along some axis is a UserError naming `what`."""
    lo, hi = region_box(box, user, what)
    ext = hi - lo
    h = float(ext.max()) / cells
    margin = 0.25 * h
    shift = SHIFT * h * np.array([1.0, 1.37, 1.71])
    origin = lo - margin - h + shift
    n = tuple(int(v) for v in np.ceil((hi + margin + h - origin) / h))
    clips = spec_box_clips(box, margin) + list(user)
    return Grid(origin=origin, h=h, n=n), clips  # type: ignore[arg-type]
