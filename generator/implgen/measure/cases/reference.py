"""The truth the root solvers are measured against: exact real-root isolation on the rationals.

Each double coefficient is converted to the exact rational it stands for, SymPy isolates the real roots
of that exact polynomial (with multiplicities) and refines each to ~1e-24 relative; mpmath at 50 digits
then gives each root's condition number. Nothing here calls the C solvers, so it is an independent reference.

`score` compares a solver's output with it:
  - a reference root is *well-conditioned* when it is simple and its relative condition number
    kappa = sum|c_k||r|^k / (|r| |p'(r)|) is at most WELL_KAPPA (expected error ~ kappa * 2^-53 <= 1e-13);
  - a computed root *matches* the nearest reference root within a tolerance that grows with the root's
    conditioning (and its multiplicity), but never beyond half the distance to its neighbours;
  - *missed*: a simple reference root with kappa <= SIMPLE_KAPPA inside [lo, hi] that nothing matches;
  - *phantom*: a computed root that matches nothing, or a second computed root on one simple root, unless
    p is zero there to working precision (|p(x)| <= 64 u sum|c_k||x|^k): those are counted apart as
    "near-tangent" reports (e.g. a tangent root reported where the exact polynomial has a tiny minimum).

`score_first` does the same for first-root mode (one computed root: the nearest hit of a ray) against the
smallest reference root in [lo, hi]: *missed* when a required root (as above) lies before what was returned
(or nothing was returned), *phantom* when the returned root matches no reference root.
"""

from __future__ import annotations

import hashlib
import json
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import mpmath
import numpy as np
import sympy as sp

from implgen.cachedir import cache_dir, read_file, write_file

U = 2.0**-53
WELL_KAPPA = 1e3
SIMPLE_KAPPA = 1e8
_X = sp.Symbol("x")


@dataclass
class RefRoot:
    value: float  # nearest double to the exact root
    mult: int  # multiplicity in the exact polynomial
    kappa: float  # relative condition number (inf for multiple roots)
    exact: mpmath.mpf = field(repr=False, default=None)


def exact_roots(coeffs: np.ndarray) -> list[RefRoot]:
    """Real roots of the exact rational polynomial given by the doubles coeffs (lowest power first)."""
    c = [Fraction(float(v)) for v in coeffs]
    while len(c) > 1 and c[-1] == 0:
        c.pop()
    if len(c) <= 1:
        return []
    poly = sp.Poly([sp.Rational(v.numerator, v.denominator) for v in reversed(c)], _X, domain="QQ")
    sqf = poly.sqf_part()
    mpmath.mp.dps = 50
    mc = [mpmath.mpf(v.numerator) / v.denominator for v in c]
    out: list[RefRoot] = []
    for (s, t), mult in poly.intervals():
        if s == t:
            r = mpmath.mpf(s.p) / s.q
        else:
            # refine until the width is 1e-24 RELATIVE to the root (a root at 1e-28 needs far more than an
            # absolute 1e-24): shrink by 1e6 per round until the interval excludes 0 and is narrow enough
            for _ in range(40):
                small = min(abs(s), abs(t)) if s * t > 0 else 0
                if small > 0 and t - s <= small * sp.Rational(1, 10**24):
                    break
                s, t = sqf.refine_root(s, t, eps=(t - s) / 10**6)
                if s == t:
                    break
            r = (mpmath.mpf(s.p) / s.q + mpmath.mpf(t.p) / t.q) / 2
        if mult == 1 and r != 0:
            big = sum(abs(ck) * abs(r) ** k for k, ck in enumerate(mc))
            dp = sum(k * ck * r ** (k - 1) for k, ck in enumerate(mc) if k)
            kappa = float(big / (abs(r) * abs(dp))) if dp != 0 else float("inf")
        elif mult == 1:
            kappa = 1.0
        else:
            kappa = float("inf")
        out.append(RefRoot(float(r), int(mult), kappa, r))
    return out


def _batch(rows: list[np.ndarray]) -> list[list[RefRoot]]:
    return [exact_roots(r) for r in rows]


def _cache_file(coeffs: np.ndarray) -> Path:
    h = hashlib.sha256(b"ref-v4" + np.ascontiguousarray(coeffs, dtype=np.float64).tobytes()).hexdigest()[:24]
    return cache_dir("roots_reference") / f"{h}.json"


MAX_REFERENCE_BYTES = 256 << 20  # a reference file of the largest case set is a few MB


def reference(coeffs: np.ndarray, workers: int | None = None, use_cache: bool = True) -> list[list[RefRoot]]:
    """exact_roots for every row, in parallel, cached on disk (keyed by the coefficient bytes)."""
    coeffs = np.ascontiguousarray(coeffs, dtype=np.float64)
    path = _cache_file(coeffs)
    if use_cache:
        cached = _read_reference(path, len(coeffs))
        if cached is not None:
            return cached
    rows = list(coeffs)
    workers = workers or min(os.cpu_count() or 1, 4)
    if workers > 1 and len(rows) > 50:
        chunks = [rows[i::workers] for i in range(workers)]
        with ProcessPoolExecutor(workers) as ex:
            parts = list(ex.map(_batch, chunks))
        result: list[list[RefRoot]] = [None] * len(rows)  # type: ignore[list-item]
        for w, part in enumerate(parts):
            result[w::workers] = part
    else:
        result = _batch(rows)
    for roots in result:  # mpf objects do not need to survive the cache
        for r in roots:
            r.exact = None
    if use_cache:  # data, not code: JSON of plain (value, multiplicity, condition) triples, never a pickle
        rows_out = [[[r.value, r.mult, r.kappa] for r in roots] for roots in result]
        write_file(path, json.dumps(rows_out, allow_nan=True).encode())
    return result


def _read_reference(path: Path, nrows: int) -> list[list[RefRoot]] | None:
    """The cached reference for `nrows` polynomials, or None when it is missing or not exactly what
    reference() writes (then it is computed again)."""
    raw = read_file(path, MAX_REFERENCE_BYTES)
    if raw is None:
        return None
    try:
        rows = json.loads(raw)
        if not isinstance(rows, list) or len(rows) != nrows:
            return None
        return [[RefRoot(float(v), int(m), float(k)) for v, m, k in roots] for roots in rows]
    except (ValueError, TypeError, RecursionError):
        return None


@dataclass
class Score:
    polys: int = 0
    ref_simple: int = 0  # simple well-separated reference roots in range (the ones that must be found)
    missed: int = 0
    phantom: int = 0
    near_tangent: int = 0  # reported where p is zero to working precision but the exact root is not there
    errors_well: list = field(default_factory=list)  # rel. errors on well-conditioned roots
    errors_all: list = field(default_factory=list)  # rel. errors on every matched root

    def add(self, other: Score) -> None:
        self.polys += other.polys
        self.ref_simple += other.ref_simple
        self.missed += other.missed
        self.phantom += other.phantom
        self.near_tangent += other.near_tangent
        self.errors_well += other.errors_well
        self.errors_all += other.errors_all


def _abs_sum(c: np.ndarray, x: float) -> float:
    ax = abs(x)
    s = 0.0
    for ck in c[::-1]:
        s = s * ax + abs(ck)
    return s


def _is_numerical_zero(c: np.ndarray, x: float) -> bool:
    val = mpmath.polyval([mpmath.mpf(float(v)) for v in c[::-1]], mpmath.mpf(x))
    return abs(float(val)) <= 64 * U * _abs_sum(c, x) * len(c)


def _tolerances(ref: list[RefRoot]) -> list[float]:
    """How far a computed root may lie from each reference root and still match it: grows with the root's
    conditioning (and multiplicity), never beyond half the distance to its neighbours."""
    vals = [r.value for r in ref]
    tol = []
    for i, r in enumerate(ref):
        gaps = [abs(r.value - v) for j, v in enumerate(vals) if j != i]
        half_gap = 0.5 * min(gaps) if gaps else np.inf
        if r.mult == 1:
            rel = max(1e-12, 1e3 * U * r.kappa)
        else:
            rel = max(1e-12, (1e3 * U) ** (1.0 / r.mult))
        tol.append(min(rel * abs(r.value) + 1e-300, half_gap))
    return tol


def _match(x: float, ref: list[RefRoot], tol: list[float]) -> int:
    """Index of the nearest reference root within its tolerance of x, or -1."""
    best, bd = -1, np.inf
    for i, r in enumerate(ref):
        dist = abs(x - r.value)
        if dist <= tol[i] and dist < bd:
            best, bd = i, dist
    return best


def _required(r: RefRoot, tol: float, lo: float, hi: float) -> bool:
    """A root every method must find: simple, condition <= SIMPLE_KAPPA, and inside [lo, hi] by more than its
    tolerance (a root within its tolerance of lo or hi may truly lie just outside: not required either way)."""
    return r.mult == 1 and r.kappa <= SIMPLE_KAPPA and lo + tol < r.value < hi - tol


def _error(x: float, r: RefRoot, sc: Score) -> None:
    if r.mult == 1:
        err = float(abs(mpmath.mpf(float(x)) - mpmath.mpf(r.value)) / abs(r.value)) if r.value else abs(x)
        sc.errors_all.append(err)
        if r.kappa <= WELL_KAPPA:
            sc.errors_well.append(err)


def score_one(c: np.ndarray, lo: float, hi: float, computed: np.ndarray, ref: list[RefRoot]) -> Score:
    sc = Score(polys=1)
    tol = _tolerances(ref)
    hits = [0] * len(ref)
    mpmath.mp.dps = 50
    for x in computed:
        best = _match(x, ref, tol)
        if best < 0:
            if _is_numerical_zero(c, float(x)):
                sc.near_tangent += 1
            else:
                sc.phantom += 1
            continue
        hits[best] += 1
        r = ref[best]
        if hits[best] > 1:
            if r.mult == 1 and not _is_numerical_zero(c, float(x)):
                sc.phantom += 1
            continue
        _error(x, r, sc)
    for i, r in enumerate(ref):
        if _required(r, tol[i], lo, hi):
            sc.ref_simple += 1
            if hits[i] == 0:
                sc.missed += 1
    return sc


def score_first(c: np.ndarray, lo: float, hi: float, computed: np.ndarray, ref: list[RefRoot]) -> Score:
    """First-root mode: computed holds at most one root, which should be the smallest reference root in
    [lo, hi]. ref_simple counts polynomials with a required root (1 or 0); missed: a required root lies before
    the returned one, or nothing was returned although one exists -- a ray that sees through a surface;
    phantom: the returned root matches no reference root (and p is not zero there to working precision) -- a
    hit where there is none. The returned root may also be a tangent or boundary root before the first
    required one: that is correct, and scored like score_one scores it."""
    sc = Score(polys=1)
    tol = _tolerances(ref)
    req = [r.value for i, r in enumerate(ref) if _required(r, tol[i], lo, hi)]
    first_req = min(req) if req else None
    if first_req is not None:
        sc.ref_simple += 1
    mpmath.mp.dps = 50
    computed = np.asarray(computed, dtype=float).reshape(-1)[:1]
    if computed.size == 0:
        if first_req is not None:
            sc.missed += 1
        return sc
    x = float(computed[0])
    best = _match(x, ref, tol)
    if best < 0:
        if _is_numerical_zero(c, x):
            sc.near_tangent += 1
        else:
            sc.phantom += 1
        if first_req is not None and x > first_req:
            sc.missed += 1
        return sc
    r = ref[best]
    if first_req is not None and r.value > first_req:
        sc.missed += 1  # skipped the nearest required root: returned a later one
        return sc
    _error(x, r, sc)
    return sc
