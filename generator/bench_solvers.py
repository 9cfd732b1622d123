"""`implgen bench solvers`: speed against error of the root solvers, written as a Markdown table and a plot.

    implgen bench solvers [-o DIR] [--timed N] [--ref N] [--quick] [--seed S]

For each case set and method: ns per solve measured in C (clock_gettime around every solve, median over
--timed polynomials, plus the mean of an untimed pass), and against the exact reference
(implgen.roots_reference, on a --ref subset): max relative error on well-conditioned roots, median relative
error, missed simple roots, phantom roots. numpy.roots runs on the same polynomials as an outside reference
(its time is a Python call, not comparable with the C figures). Output: DIR/solvers.md, DIR/solvers.png
(default DIR: bench/results).
"""

from __future__ import annotations

import argparse
import platform
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from . import raycast
from .errors import UserError
from .roots import bench_solve_batch
from .roots_reference import Score, reference, score_one

METHODS = ["closed_plain", "closed", "sturm", "bracket", "bernstein", "auto"]

# ------------------------------------------------------------------------------------------------ shapes
# f as {(i, j, k): coefficient of x^i y^j z^k}; written out here so the bench does not depend on the generator.


def _torus(a: float, b: float) -> dict:
    # (x^2+y^2+z^2)^2 - 2(a^2+b^2)(x^2+y^2+z^2) + 4 a^2 y^2 + (a^2-b^2)^2   (Suffern 19.20)
    f: dict = {}

    def add(m, v):
        f[m] = f.get(m, 0.0) + v

    for m, v in {(4, 0, 0): 1, (0, 4, 0): 1, (0, 0, 4): 1, (2, 2, 0): 2, (2, 0, 2): 2, (0, 2, 2): 2}.items():
        add(m, v)
    s = -2.0 * (a * a + b * b)
    for m in [(2, 0, 0), (0, 2, 0), (0, 0, 2)]:
        add(m, s)
    add((0, 2, 0), 4.0 * a * a)
    add((0, 0, 0), (a * a - b * b) ** 2)
    return f


SHAPES: dict[str, tuple[dict, tuple[float, ...]]] = {
    "sphere": ({(2, 0, 0): 1.0, (0, 2, 0): 1.0, (0, 0, 2): 1.0, (0, 0, 0): -1.0}, (-1, -1, -1, 1, 1, 1)),
    "torus": (_torus(1.0, 0.4), (-1.4, -0.4, -1.4, 1.4, 0.4, 1.4)),
    "piriform": ({(4, 0, 0): 1.0, (3, 0, 0): -1.0, (0, 2, 0): 1.0, (0, 0, 2): 1.0}, (0, -0.33, -0.33, 1, 0.33, 0.33)),
    # Clebsch-like cubic 4(x^3+y^3+z^3+1) - (x+y+z+1)^3, cut to a box
    "cubic": ({}, (-2, -2, -2, 2, 2, 2)),
    # heart (x^2 + 9/4 y^2 + z^2 - 1)^3 - x^2 z^3 - 9/80 y^2 z^3
    "heart": ({}, (-1.5, -1.0, -1.5, 1.5, 1.0, 1.5)),
    "tooth8": ({(8, 0, 0): 1.0, (0, 8, 0): 1.0, (0, 0, 8): 1.0, (2, 0, 0): -1.0, (0, 2, 0): -1.0, (0, 0, 2): -1.0},
               (-1.1, -1.1, -1.1, 1.1, 1.1, 1.1)),
    "super12": ({(12, 0, 0): 1.0, (0, 12, 0): 1.0, (0, 0, 12): 1.0, (0, 0, 0): -1.0}, (-1.01, -1.01, -1.01, 1.01, 1.01, 1.01)),
}


def _expand(poly_terms: list[tuple[float, list[tuple[int, int, int]]]]) -> dict:
    """Sum of coefficient * product of monomials -> monomial dict (tiny symbolic helper, exact in floats here)."""
    out: dict = {}
    for coef, mons in poly_terms:
        i = sum(m[0] for m in mons)
        j = sum(m[1] for m in mons)
        k = sum(m[2] for m in mons)
        out[(i, j, k)] = out.get((i, j, k), 0.0) + coef
    return {m: v for m, v in out.items() if v != 0.0}


def _mul(p: dict, q: dict) -> dict:
    out: dict = {}
    for a, u in p.items():
        for b, v in q.items():
            m = (a[0] + b[0], a[1] + b[1], a[2] + b[2])
            out[m] = out.get(m, 0.0) + u * v
    return out


def _addp(*ps: tuple[float, dict]) -> dict:
    out: dict = {}
    for s, p in ps:
        for m, v in p.items():
            out[m] = out.get(m, 0.0) + s * v
    return {m: v for m, v in out.items() if v != 0.0}


def _build_catalog() -> None:
    lin = {(1, 0, 0): 1.0, (0, 1, 0): 1.0, (0, 0, 1): 1.0, (0, 0, 0): 1.0}
    cube = _mul(_mul(lin, lin), lin)
    SHAPES["cubic"] = (_addp((4.0, {(3, 0, 0): 1.0, (0, 3, 0): 1.0, (0, 0, 3): 1.0, (0, 0, 0): 1.0}), (-1.0, cube)),
                       SHAPES["cubic"][1])
    g = {(2, 0, 0): 1.0, (0, 2, 0): 2.25, (0, 0, 2): 1.0, (0, 0, 0): -1.0}
    SHAPES["heart"] = (_addp((1.0, _mul(_mul(g, g), g)), (-1.0, {(2, 0, 3): 1.0}), (-9.0 / 80.0, {(0, 2, 3): 1.0})),
                       SHAPES["heart"][1])


_build_catalog()


def degree(f: dict) -> int:
    return max(sum(m) for m in f)


def ray_coeffs(f: dict, o: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Coefficients of f(o + t d) (lowest power first) for arrays of rays, shape (N, degree+1)."""
    o = np.atleast_2d(o)
    d = np.atleast_2d(d)
    n = degree(f)
    N = o.shape[0]
    # powers[axis][p] = (o_axis + t d_axis)^p as (N, p+1) coefficient arrays
    powers = []
    for ax in range(3):
        pw = [np.ones((N, 1))]
        for _ in range(n):
            prev = pw[-1]
            nxt = np.zeros((N, prev.shape[1] + 1))
            nxt[:, :-1] += prev * o[:, ax:ax + 1]
            nxt[:, 1:] += prev * d[:, ax:ax + 1]
            pw.append(nxt)
        powers.append(pw)
    out = np.zeros((N, n + 1))
    for (i, j, k), v in f.items():
        a, b, c = powers[0][i], powers[1][j], powers[2][k]
        ab = np.zeros((N, i + j + 1))
        for q in range(j + 1):
            ab[:, q:q + i + 1] += a * b[:, q:q + 1]
        abc = np.zeros((N, i + j + k + 1))
        for q in range(k + 1):
            abc[:, q:q + i + j + 1] += ab * c[:, q:q + 1]
        out[:, : i + j + k + 1] += v * abc
    return out


def ray_polys(name: str, count: int, rng: np.random.Generator):
    """Ray polynomials of a catalog shape as the runtime solves them (box clip + origin shift):
    a mix of rays from near (3-6 box radii), far (1e4) and inside the box, aimed at points in the box, with
    non-unit directions; for the torus and sphere also exactly grazing rays. Returns (coeffs, lo, hi)."""
    f, box = SHAPES[name]
    box = np.array(box, dtype=float)
    lo_b, hi_b = box[:3], box[3:]
    centre, radius = 0.5 * (lo_b + hi_b), 0.5 * np.linalg.norm(hi_b - lo_b)
    m = count * 2
    target = lo_b + rng.random((m, 3)) * (hi_b - lo_b)
    u = rng.normal(size=(m, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    kind = rng.integers(0, 4, size=m)
    dist = np.where(kind == 0, 1e4, radius * (3 + 3 * rng.random(m)))
    o = target - dist[:, None] * u
    inside = kind == 3
    o[inside] = lo_b + rng.random((int(inside.sum()), 3)) * (hi_b - lo_b)
    if name in ("torus", "sphere"):
        graze = kind == 2
        k = int(graze.sum())
        if name == "torus":
            a, b = 1.0, 0.4
            uu, vv = rng.random(k) * 2 * np.pi, rng.random(k) * 2 * np.pi
            p = np.stack([(a + b * np.cos(vv)) * np.cos(uu), b * np.sin(vv), (a + b * np.cos(vv)) * np.sin(uu)], 1)
            nrm = np.stack([np.cos(vv) * np.cos(uu), np.sin(vv), np.cos(vv) * np.sin(uu)], 1)
        else:
            p = rng.normal(size=(k, 3))
            p /= np.linalg.norm(p, axis=1, keepdims=True)
            nrm = p.copy()
        tang = np.cross(nrm, rng.normal(size=(k, 3)))
        tang /= np.linalg.norm(tang, axis=1, keepdims=True)
        o[graze] = p - 5.0 * tang
        u[graze] = tang
    d = u * (0.5 + 1.5 * rng.random((m, 1)))
    o = o + 0 * centre
    t0 = np.zeros(m)
    t1 = np.full(m, np.inf)
    t0, t1, valid = raycast._clip(box, o, d, t0, t1)
    o, d, t0, t1 = o[valid], d[valid], t0[valid], t1[valid]
    ts = raycast._shift_point(box, o, d, t0, t1)
    c = ray_coeffs(f, o + ts[:, None] * d, d)
    sel = np.arange(c.shape[0])[:count]
    return c[sel], (t0 - ts)[sel], (t1 - ts)[sel]


def _pad(c: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros((c.shape[0], n + 1))
    out[:, : c.shape[1]] = c
    return out


def shape_set(names: list[str], count: int, rng: np.random.Generator):
    per = -(-count // len(names))
    parts = [ray_polys(nm, per, rng) for nm in names]
    n = max(p[0].shape[1] - 1 for p in parts)
    c = np.concatenate([_pad(p[0], n) for p in parts])
    lo = np.concatenate([p[1] for p in parts])
    hi = np.concatenate([p[2] for p in parts])
    perm = rng.permutation(c.shape[0])[:count]
    return c[perm], lo[perm], hi[perm]


def random_set(deg: int, count: int, rng: np.random.Generator):
    c = rng.normal(size=(count, deg + 1))
    return c, np.full(count, -np.inf), np.full(count, np.inf)


def _from_roots(real: list[float], pairs: list[tuple[float, float]], scale: float = 1.0) -> np.ndarray:
    p = np.array([1.0])
    for r in real:
        p = np.convolve(p, [1.0, -r])
    for re, im in pairs:
        p = np.convolve(p, [1.0, -2 * re, re * re + im * im])
    return (p * scale)[::-1]


def hard_set(count: int, rng: np.random.Generator, n: int = 24):
    """Built hard cases, padded to degree n: double and quadruple roots (exact when the roots are dyadic),
    clusters 1.000 ... 1.003, roots spread over 1e-30 ... 1e30, coefficients near 1e+-150, a root exactly at
    lo or hi, a tiny minimum without real root, degree 12-24 products of known factors."""
    rows, los, his = [], [], []
    for i in range(count):
        kind = i % 8
        lo, hi = -np.inf, np.inf
        dy = lambda: float(rng.integers(-64, 64)) / 16.0  # noqa: E731  dyadic root: exact coefficients
        if kind == 0:
            r = dy() if rng.random() < 0.5 else float(rng.uniform(-4, 4))
            c = _from_roots([r, r, dy(), float(rng.uniform(-4, 4))], [])
        elif kind == 1:
            r = dy()
            c = _from_roots([r] * 4 + [float(rng.uniform(-4, 4))], [(float(rng.uniform(-2, 2)), 0.5)])
        elif kind == 2:
            base = float(rng.uniform(-2, 2))
            c = _from_roots([base + 0.001 * j for j in range(4)] + [float(rng.uniform(-4, 4))], [])
        elif kind == 3:
            mags = 10.0 ** rng.uniform(-30, 30, size=int(rng.integers(3, 6)))
            c = _from_roots(list(mags * rng.choice([-1, 1], size=mags.size)), [])
        elif kind == 4:
            s = 10.0 ** float(rng.choice([-150, 150]) + rng.uniform(-5, 5))
            c = _from_roots(list(rng.uniform(-3, 3, size=4)), [], scale=s)
        elif kind == 5:
            r = dy()
            c = _from_roots([r, dy() + 5.0, float(rng.uniform(-4, -1))], [(0.5, 0.25)])
            lo, hi = (r, r + 1.0) if rng.random() < 0.5 else (r - 1.0, r)
        elif kind == 6:
            r = dy()
            eps = 2.0 ** -float(rng.integers(20, 50))
            c = _from_roots([float(rng.uniform(-4, 4)), float(rng.uniform(-4, 4))], [(r, np.sqrt(eps))])
        else:
            deg = int(rng.integers(12, n + 1))
            nreal = int(rng.integers(2, deg // 2 + 1)) * 2 - (deg % 2 == 1)
            nreal = min(nreal, deg)
            npairs = (deg - nreal) // 2
            real = list(rng.uniform(-3, 3, size=deg - 2 * npairs))
            pairs = [(float(rng.uniform(-3, 3)), float(rng.uniform(0.05, 1))) for _ in range(npairs)]
            c = _from_roots(real, pairs)
        rows.append(c)
        los.append(lo)
        his.append(hi)
    out = np.zeros((count, n + 1))
    for i, c in enumerate(rows):
        out[i, : c.size] = c
    return out, np.array(los), np.array(his)


@dataclass
class CaseSet:
    name: str
    describe: str
    make: Callable[[int, np.random.Generator], tuple[np.ndarray, np.ndarray, np.ndarray]]


CASE_SETS = [
    CaseSet("random-4", "random quartics, N(0,1) coefficients, whole line", lambda k, r: random_set(4, k, r)),
    CaseSet("torus rays", "torus a=1 b=0.4: near/far(1e4)/inside/grazing rays, box-clipped, shifted",
            lambda k, r: shape_set(["torus"], k, r)),
    CaseSet("rays deg 2-4", "sphere, Clebsch cubic, piriform rays (padded to 4: degree drop)",
            lambda k, r: shape_set(["sphere", "cubic", "piriform"], k, r)),
    CaseSet("rays deg 6-12", "heart (6), x^8+y^8+z^8=r^2 (8), x^12+y^12+z^12=1 (12) rays, padded to 12",
            lambda k, r: shape_set(["heart", "tooth8", "super12"], k, r)),
    CaseSet("random-12", "random degree-12, N(0,1) coefficients, whole line", lambda k, r: random_set(12, k, r)),
    CaseSet("hard", "double/quadruple roots, clusters, 1e-30..1e30 roots, 1e+-150 scale, root at lo/hi, tiny "
            "minimum, deg 12-24 products (padded to 24)", lambda k, r: hard_set(k, r)),
]


def numpy_real_roots(c: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """numpy.roots, keeping roots with |imag| <= 1e-9 (1 + |re|): how it is commonly used."""
    nz = np.nonzero(c)[0]
    if nz.size == 0:
        return np.array([])
    c = c[: nz[-1] + 1]
    z = np.roots(c[::-1])
    r = np.sort(z[np.abs(z.imag) <= 1e-9 * (1 + np.abs(z.real))].real)
    r = r[(r >= lo) & (r <= hi)]
    return np.unique(r)


@dataclass
class Row:
    case: str
    method: str
    median_ns: float
    mean_ns: float
    score: Score
    timed: int


def _score(c, lo, hi, roots_of: Callable[[int], np.ndarray], ref) -> Score:
    total = Score()
    for i, rr in enumerate(ref):
        total.add(score_one(c[i], lo[i], hi[i], roots_of(i), rr))
    return total


def run(timed: int, nref: int, seed: int, methods: list[str], sets: list[CaseSet], log=print) -> list[Row]:
    rows: list[Row] = []
    for cs in sets:
        rng = np.random.default_rng(seed)
        c, lo, hi = cs.make(timed, rng)
        t = time.time()
        ref = reference(c[:nref])
        log(f"  {cs.name}: {c.shape[0]} polynomials (degree <= {c.shape[1] - 1}), reference on {len(ref)} "
            f"in {time.time() - t:.1f} s")
        for m in methods:
            roots, counts, ns, total = bench_solve_batch(c, lo, hi, m)
            sc = _score(c, lo, hi, lambda i: roots[i, : counts[i]], ref)
            rows.append(Row(cs.name, m, float(np.median(ns)), total / c.shape[0], sc, c.shape[0]))
        k = min(c.shape[0], max(nref, 2000))
        t0 = time.perf_counter_ns()
        npr = [numpy_real_roots(c[i], lo[i], hi[i]) for i in range(k)]
        el = (time.perf_counter_ns() - t0) / k
        sc = _score(c, lo, hi, lambda i: npr[i], ref)
        rows.append(Row(cs.name, "numpy.roots", float("nan"), el, sc, k))
    return rows


def _fmt_err(v: list) -> str:
    return f"{max(v):.1e}" if v else "-"


def _fmt_med(v: list) -> str:
    return f"{np.median(v):.1e}" if v else "-"


def machine() -> str:
    model = platform.processor() or "unknown CPU"
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        for line in out.splitlines():
            if line.startswith("Model name:"):
                model = line.split(":", 1)[1].strip()
    except OSError:
        pass
    import os

    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.machine()}, Python {platform.python_version()}"


def targets(rows: list[Row]) -> list[str]:
    by = {(r.case, r.method): r for r in rows}
    out = []
    bad = [(r.case, r.method) for r in rows if r.method in METHODS and (r.score.missed or r.score.phantom)]
    auto_bad = [k for k in bad if k[1] == "auto"]
    out.append(f"- No missed/phantom simple roots: auto {'MET' if not auto_bad else 'NOT MET ' + str(auto_bad)}; "
               f"all methods with any: {bad if bad else 'none'}.")
    worst = max((max(r.score.errors_well) for r in rows if r.method == "auto" and r.score.errors_well), default=0.0)
    out.append(f"- Rel. error <= 1e-12 on well-conditioned roots (auto, all sets): max {worst:.1e} "
               f"{'MET' if worst <= 1e-12 else 'NOT MET'}.")
    if ("torus rays", "auto") in by:
        auto = by[("torus rays", "auto")]
        closed = [by[("torus rays", m)] for m in ("closed_plain", "closed") if ("torus rays", m) in by]
        fastest = min(closed, key=lambda r: r.median_ns)
        ratio = auto.median_ns / fastest.median_ns
        ea = max(auto.score.errors_well) if auto.score.errors_well else 0.0
        ef = max(fastest.score.errors_well) if fastest.score.errors_well else 0.0
        better = (ea < ef) or (auto.score.missed + auto.score.phantom < fastest.score.missed + fastest.score.phantom)
        out.append(f"- auto within 2x the fastest closed-form quartic ({fastest.method}) on torus rays: "
                   f"{auto.median_ns:.0f} vs {fastest.median_ns:.0f} ns = {ratio:.2f}x, max error {ea:.1e} vs "
                   f"{ef:.1e}, missed+phantom {auto.score.missed + auto.score.phantom} vs "
                   f"{fastest.score.missed + fastest.score.phantom}: "
                   f"{'MET' if ratio <= 2 and better else 'NOT MET'}.")
    if ("rays deg 6-12", "bracket") in by and ("rays deg 6-12", "sturm") in by:
        b, s = by[("rays deg 6-12", "bracket")], by[("rays deg 6-12", "sturm")]
        ratio = s.median_ns / b.median_ns
        eb = max(b.score.errors_well) if b.score.errors_well else 0.0
        es = max(s.score.errors_well) if s.score.errors_well else 0.0
        out.append(f"- Bracketing >= 3x faster than Sturm on degree 6-12 ray polynomials: {b.median_ns:.0f} vs "
                   f"{s.median_ns:.0f} ns = {ratio:.1f}x, max error {eb:.1e} vs {es:.1e}: "
                   f"{'MET' if ratio >= 3 else 'NOT MET'}.")
    return out


def table(rows: list[Row], sets: list[CaseSet], timed: int, nref: int, seconds: float) -> str:
    lines = [
        f"Measured on: {machine()}. Maximum degree: 24. {timed} polynomials timed per set, exact reference on "
        f"the first {nref}; run took {seconds:.0f} s.",
        "",
        "| case set | method | median ns/solve (C) | mean ns (C, untimed pass) | max rel err (well-cond.) | "
        "median rel err | missed simple | phantom | near-tangent reports |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        s = r.score
        med = "-" if np.isnan(r.median_ns) else f"{r.median_ns:.0f}"
        mean = f"{r.mean_ns:.0f}" + (" (Python)" if r.method == "numpy.roots" else "")
        lines.append(
            f"| {r.case} | {r.method} | {med} | {mean} | {_fmt_err(s.errors_well)} | {_fmt_med(s.errors_all)} | "
            f"{s.missed}/{s.ref_simple} | {s.phantom} | {s.near_tangent} |")
    lines += ["", "Case sets:", ""]
    lines += [f"- **{cs.name}**: {cs.describe}" for cs in sets]
    lines += ["", "Targets:", ""] + targets(rows)
    return "\n".join(lines) + "\n"


def plot(rows: list[Row], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    markers = {"closed_plain": "s", "closed": "D", "sturm": "^", "bracket": "o", "bernstein": "v", "auto": "*", "numpy.roots": "x"}
    cases = list(dict.fromkeys(r.case for r in rows))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for r in rows:
        x = r.mean_ns if r.method == "numpy.roots" else r.median_ns
        y = max(r.score.errors_well) if r.score.errors_well else 1e-17
        ax.scatter(x, max(y, 1e-17), marker=markers.get(r.method, "."), s=70,
                   color=colors[cases.index(r.case) % len(colors)], alpha=0.85)
    for m, mk in markers.items():
        ax.scatter([], [], marker=mk, color="gray", label=m)
    for i, cname in enumerate(cases):
        ax.scatter([], [], marker="o", color=colors[i % len(colors)], label=cname)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(1e-12, color="gray", ls=":", lw=1)
    ax.set_xlabel("ns per solve (median, C; numpy.roots: mean Python call)")
    ax.set_ylabel("max relative error, well-conditioned roots")
    ax.set_title("implgen root solvers: speed against error")
    ax.legend(fontsize=7, ncol=2, loc="best")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="implgen bench solvers", description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--out", default="bench/results", help="output folder (default bench/results)")
    ap.add_argument("--timed", type=int, default=100_000, help="polynomials timed per case set (default 1e5)")
    ap.add_argument("--ref", type=int, default=400, help="polynomials per set checked against the exact reference")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--quick", action="store_true", help="small sizes (for tests): 2000 timed, 40 referenced")
    args = ap.parse_args(list(argv) if argv is not None else None)
    if args.quick:
        args.timed, args.ref = 2000, 40
    if args.timed < 1 or args.ref < 1 or args.ref > args.timed:
        raise UserError("bench solvers", "need 1 <= --ref <= --timed")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t = time.time()
    print(f"implgen bench solvers: {len(CASE_SETS)} case sets x {len(METHODS)} methods + numpy.roots")
    rows = run(args.timed, args.ref, args.seed, METHODS, CASE_SETS)
    seconds = time.time() - t
    md = table(rows, CASE_SETS, args.timed, args.ref, seconds)
    (out / "solvers.md").write_text(md)
    plot(rows, out / "solvers.png")
    print(md)
    print(f"wrote {out / 'solvers.md'} and {out / 'solvers.png'}")
    return 0
