"""Polynomials at the edges of the double range, for the tests: quartics whose real roots spread over ~150
decades close to the overflow limit, and torus ray polynomials written at a far origin (not shifted), where
rounding the coefficients to double moves the roots: every root of the double polynomial counts, and the exact
reference (`implgen.measure.cases.reference`) works on those doubles."""

from __future__ import annotations

import numpy as np

from implgen.measure.cases import rays_high as raysets_high


def _from_roots(roots: list[float]) -> np.ndarray:
    """Coefficients (lowest power first) of prod (x - r), each product rounded once: the double polynomial."""
    c = np.array([1.0])
    for r in roots:
        c = np.convolve(c, [1.0, -r])
    return c[::-1].copy()


def spread_quartics(count: int, rng: np.random.Generator) -> np.ndarray:
    """count quartics with four real roots: two of magnitude 1e-3 .. 1e3 and two of 1e140 .. 1e154 (random signs),
    so that the constant coefficient is near 1e307; the first one is 1, 10, 1e152, 1e154."""
    rows = [_from_roots([1.0, 10.0, 1e152, 1e154])]
    while len(rows) < count:
        small = 10.0 ** rng.uniform(-3, 3, size=2)
        big = 10.0 ** rng.uniform(140, 154, size=2)
        mags = np.concatenate([small, big]) * rng.choice([-1.0, 1.0], size=4)
        c = _from_roots(list(mags))
        if np.all(np.isfinite(c)):
            rows.append(c)
    return np.array(rows)


def far_torus_rays(count: int, rng: np.random.Generator, dist: float = 1e4):
    """Rays from dist units at a torus (major radius 1, tube 0.25, axis z) aimed near its tube, with the coefficients
    of f(o + t d) computed at the far origin itself (no shift), and t on the box-clipped interval. Returns
    (coeffs, lo, hi)."""
    big, small = 1.0, 0.25

    def torus(x, y, z):
        sq = raysets_high.padd(raysets_high.pmul(x, x), raysets_high.pmul(y, y))
        q = raysets_high.padd(sq, raysets_high.pmul(z, z))
        q[:, 0] += big * big - small * small
        return raysets_high.padd(raysets_high.pmul(q, q), -4.0 * big * big * sq)

    box = np.array([-1.25, -1.25, -0.25, 1.25, 1.25, 0.25])
    # aimed at points of the tube's core circle, so that most rays hit
    phi = rng.random(count) * 2 * np.pi
    target = np.stack([big * np.cos(phi), big * np.sin(phi), np.zeros(count)], 1) + rng.normal(0, 0.1, (count, 3))
    u = raysets_high._unit(rng.normal(size=(count, 3)))
    o = target - dist * u
    d = u
    from implgen.roots import raycast

    t0, t1, valid = raycast._clip(box, o, d, np.zeros(count), np.full(count, np.inf))
    o, d, t0, t1 = o[valid], d[valid], t0[valid], t1[valid]
    x, y, z = (np.stack([o[:, i], d[:, i]], axis=1) for i in range(3))
    return torus(x, y, z), t0, t1
