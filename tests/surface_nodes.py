"""Real double points (nodes) of a surface, counted in projective space: the check of the gallery's equations
against the literature's node counts (tests/test_gallery_surfaces.py).

f(x, y, z) is homogenised to F(x, y, z, w). In each of the four charts (one coordinate set to 1) the critical
points of F restricted to the chart are found by Newton's method from a grid of seeds in [-1.05, 1.05]^3, steps
capped in length; a critical point where F vanishes is singular. Every point of projective space has a chart in
which its other coordinates lie in [-1, 1], so the four grids cover it. The points are merged as unit vectors up
to sign; an ordinary double point has a Hessian of rank 3 in its chart.
"""

from __future__ import annotations

import itertools

import numpy as np
import sympy as sp

X, Y, Z, W = sp.symbols("x y z w", real=True)


class _Poly:
    """A polynomial in three variables as exponents and double coefficients, evaluated on many points at once."""

    def __init__(self, exps: np.ndarray, coeffs: np.ndarray):
        keep = coeffs != 0
        self.exps, self.coeffs = exps[keep], coeffs[keep]

    def diff(self, v: int) -> _Poly:
        e = self.exps.copy()
        c = self.coeffs * e[:, v]
        e[:, v] = np.maximum(e[:, v] - 1, 0)
        return _Poly(e, c)

    def __call__(self, powers: list[np.ndarray]) -> np.ndarray:
        """Values at the points whose coordinates' powers 0..degree are `powers` (powers_of)."""
        if len(self.coeffs) == 0:
            return np.zeros(len(powers[0]))
        e = self.exps
        return (powers[0][:, e[:, 0]] * powers[1][:, e[:, 1]] * powers[2][:, e[:, 2]]) @ self.coeffs


def powers_of(p: np.ndarray, degree: int) -> list[np.ndarray]:
    """[x^0..x^degree, y^0.., z^0..] for every point, by repeated products."""
    return [np.cumprod(np.column_stack([np.ones(len(p))] + [p[:, v]] * degree), axis=1) for v in range(3)]


def _chart_points(F: sp.Expr, k: int, seeds: np.ndarray, iters: int) -> list[tuple[np.ndarray, float]]:
    variables = [X, Y, Z, W]
    free = [v for i, v in enumerate(variables) if i != k]
    poly = sp.Poly(F.subs(variables[k], 1), *free)
    g = _Poly(np.array(poly.monoms(), dtype=int), np.array([float(c) for c in poly.coeffs()]))
    grad = [g.diff(v) for v in range(3)]
    hess = [[gi.diff(v) for v in range(3)] for gi in grad]

    degree = int(g.exps.max())

    def grad_hess(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pw = powers_of(p, degree)
        G = np.stack([gi(pw) for gi in grad], axis=1)
        H = np.stack([np.stack([h(pw) for h in row], axis=1) for row in hess], axis=1)
        return G, H

    p = seeds.copy()
    for _ in range(iters):
        G, H = grad_hess(p)
        ok = np.abs(np.linalg.det(H)) > 1e-300
        step = np.zeros_like(p)
        step[ok] = np.linalg.solve(H[ok], G[ok][..., None])[..., 0]
        length = np.linalg.norm(step, axis=1)
        p = np.clip(p - np.minimum(1.0, 0.25 / np.maximum(length, 1e-300))[:, None] * step, -9.0, 9.0)
    G, H = grad_hess(p)
    value = g(powers_of(p, degree))
    scale = np.abs(g.coeffs).max() * (1 + np.abs(p).sum(axis=1)) ** sp.total_degree(F)
    tiny = 1e-9 * scale
    good = (np.abs(value) < tiny) & (np.linalg.norm(G, axis=1) < tiny) & (np.abs(p) <= 1.0 + 1e-9).all(axis=1)
    out = []
    for q, h in zip(p[good], H[good]):
        v = np.insert(q, k, 1.0)
        sv = np.linalg.svd(h, compute_uv=False)
        out.append((v / np.linalg.norm(v), sv[-1] / sv[0]))
    return out


def real_nodes(f: sp.Expr, grid: int = 13, iters: int = 40, charts: tuple[int, ...] = (0, 1, 2, 3)):
    """The real singular points of f = 0 in projective space: a list of (unit homogeneous vector (x, y, z, w),
    smallest/largest singular value of the Hessian in its chart)."""
    F = sp.Poly(sp.expand(f), X, Y, Z).homogenize(W).as_expr()
    axis = np.linspace(-1.05, 1.05, grid)
    seeds = np.array(list(itertools.product(axis, axis, axis)))
    found: list[tuple[np.ndarray, float]] = []
    for k in charts:
        for v, cond in _chart_points(F, k, seeds, iters):
            v = v * np.sign(v[np.argmax(np.abs(v) > 1e-6)])
            if not any(np.linalg.norm(v - u) < 1e-6 for u, _ in found):
                found.append((v, cond))
    return found
