"""High-degree ray polynomials (degree 12-24) for the solver report and the tests, computed without the generator.

Each surface is written as polynomial arithmetic on the ray's coordinates X(s) = o'_x + s d_x (and Y, Z), with
one row of coefficients per ray (lowest power first), exactly like the generated code does it: the expanded
power form of the field, evaluated on polynomials in s. The rays are aimed like the example shapes' rays
(`implgen.measure.cases.polys.ray_polys`: from far, near and inside the box), clipped to the box and shifted to the
point of the clipped interval closest to the box centre, as runtime_c/shape.c does.

- Chmutov surfaces T_n(x) + T_n(y) + T_n(z) = 0 (T_n: Chebyshev's polynomial, in its power form);
- four linked tori, the union written as the product of their quartics (degree 16);
- spiky superellipsoids x^n + y^n + z^n = c (x^2 + y^2 + z^2)^(n/2 - 1): radius sqrt(c) on the axes, and eight
  thin spikes 3^((n - 2)/4) times longer along the diagonals.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.polynomial import chebyshev

from implgen.roots import raycast

Poly = np.ndarray  # (rays, degree + 1), lowest power first


def pmul(a: Poly, b: Poly) -> Poly:
    """Row-wise product of two batches of polynomials."""
    out = np.zeros((a.shape[0], a.shape[1] + b.shape[1] - 1))
    for i in range(a.shape[1]):
        out[:, i : i + b.shape[1]] += a[:, i : i + 1] * b
    return out


def padd(*ps: Poly) -> Poly:
    n = max(p.shape[1] for p in ps)
    out = np.zeros((ps[0].shape[0], n))
    for p in ps:
        out[:, : p.shape[1]] += p
    return out


def horner(coeffs: np.ndarray, x: Poly) -> Poly:
    """sum_k coeffs[k] x^k for a batch of polynomials x, by Horner's rule in polynomial arithmetic."""
    v = np.full((x.shape[0], 1), float(coeffs[-1]))
    for ck in coeffs[-2::-1]:
        v = pmul(v, x)
        v[:, 0] += float(ck)
    return v


def chmutov(n: int) -> Callable[[Poly, Poly, Poly], Poly]:
    tn = chebyshev.cheb2poly([0.0] * n + [1.0])  # exact integers for n <= 24
    return lambda x, y, z: padd(horner(tn, x), horner(tn, y), horner(tn, z))


def _rot(ax: float, ay: float) -> np.ndarray:
    ca, sa, cb, sb = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay)
    rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    return ry @ rx


#: the linked tori: centre, frame (rows: the torus axes), major radius R, tube radius r
LINKED_TORI = [
    (np.array([-0.9, 0.0, 0.0]), _rot(0.0, 0.0), 0.5, 0.12),
    (np.array([-0.3, 0.0, 0.0]), _rot(np.pi / 2, 0.1), 0.5, 0.12),
    (np.array([0.3, 0.0, 0.0]), _rot(0.05, -0.1), 0.5, 0.12),
    (np.array([0.9, 0.0, 0.0]), _rot(np.pi / 2, 0.2), 0.5, 0.12),
]


def linked_tori(x: Poly, y: Poly, z: Poly) -> Poly:
    out = None
    for c, m, big, small in LINKED_TORI:
        loc = []
        for i in range(3):
            v = padd(*(m[i, j] * (x, y, z)[j] for j in range(3)))
            v[:, 0] -= float(m[i] @ c)
            loc.append(v)
        lx, ly, lz = loc
        sq = padd(pmul(lx, lx), pmul(ly, ly))
        q = padd(sq, pmul(lz, lz))
        q[:, 0] += big * big - small * small
        f = padd(pmul(q, q), -4.0 * big * big * sq)
        out = f if out is None else pmul(out, f)
    return out


def spiky(n: int, c: float) -> Callable[[Poly, Poly, Poly], Poly]:
    def field(x: Poly, y: Poly, z: Poly) -> Poly:
        xn = [np.ones((x.shape[0], 1))] * 3
        for _ in range(n):
            xn = [pmul(a, b) for a, b in zip(xn, (x, y, z))]
        r2 = padd(pmul(x, x), pmul(y, y), pmul(z, z))
        rk = np.ones((x.shape[0], 1))
        for _ in range(n // 2 - 1):
            rk = pmul(rk, r2)
        return padd(*xn, -c * rk)

    return field


def spiky_c(n: int, tip: float = 1.0) -> float:
    """c so that the diagonal spikes reach distance tip from the centre."""
    return (tip / 3.0 ** ((n - 2) / 4)) ** 2


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def field_rays(field: Callable[[Poly, Poly, Poly], Poly], box: np.ndarray, count: int, rng: np.random.Generator):
    """count rays at the surface field = 0 inside box (xmin, ymin, zmin, xmax, ymax, zmax): far (1e4 units), near
    (3-6 box radii) and inside, a third each, aimed at random points of the box; clipped and shifted as the
    runtime does. Returns (coeffs, lo, hi) in the shifted parameter s."""
    lo_b, hi_b = box[:3], box[3:]
    radius = 0.5 * np.linalg.norm(hi_b - lo_b)
    m = 2 * count
    target = lo_b + rng.random((m, 3)) * (hi_b - lo_b)
    u = _unit(rng.normal(size=(m, 3)))
    kind = rng.integers(0, 3, size=m)
    dist = np.where(kind == 0, 1e4, radius * (3 + 3 * rng.random(m)))
    o = target - dist[:, None] * u
    inside = kind == 2
    o[inside] = lo_b + rng.random((int(inside.sum()), 3)) * (hi_b - lo_b)
    d = u * (0.5 + 1.5 * rng.random(m))[:, None]
    t0, t1, valid = raycast._clip(box, o, d, np.zeros(m), np.full(m, np.inf))
    keep = np.nonzero(valid)[0][:count]
    o, d, t0, t1 = o[keep], d[keep], t0[keep], t1[keep]
    ts = raycast._shift_point(box, o, d, t0, t1)
    os_ = o + ts[:, None] * d
    x, y, z = (np.stack([os_[:, i], d[:, i]], axis=1) for i in range(3))
    return field(x, y, z), t0 - ts, t1 - ts


def chmutov_box(n: int) -> np.ndarray:
    """A box holding T_n(x) + T_n(y) + T_n(z) = 0: beyond cosh(acosh(2) / n) T_n > 2."""
    e = float(np.cosh(np.arccosh(2.0) / n)) * 1.001
    return np.array([-e, -e, -e, e, e, e])


TORI_BOX = np.array([-1.55, -0.65, -0.65, 1.55, 0.65, 0.65])


def spiky_box(tip: float = 1.0) -> np.ndarray:
    e = tip / np.sqrt(3.0) * 1.01
    return np.array([-e, -e, -e, e, e, e])


def chmutov_set(n: int, count: int, rng: np.random.Generator):
    return field_rays(chmutov(n), chmutov_box(n), count, rng)


def tori_set(count: int, rng: np.random.Generator):
    return field_rays(linked_tori, TORI_BOX, count, rng)


def spiky_set(n: int, count: int, rng: np.random.Generator):
    return field_rays(spiky(n, spiky_c(n)), spiky_box(), count, rng)
