"""The polynomial case sets shared by the solver tests and the solver benchmark.

Random polynomials of a given degree, hard polynomials (multiple roots, clusters, roots spread over many
decades, scaled near the overflow limit), and ray polynomials of the example shapes through the generator:
spec -> derive -> the generated Python module's coeffs() and bounds(), clipped and shifted by
implgen.raycast's twin of runtime_c/shape.c, so they are the polynomials the runtime itself solves.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import ModuleType

import numpy as np

from implgen.errors import UserError
from implgen.measure.cases import rays_high as raysets_high
from implgen.resources import gallery_dir
from implgen.roots import raycast

SHAPES_DIR = Path("examples/shapes")


def find_shapes_dir(folder: str | Path | None = None) -> Path:
    """The example shapes: folder if given, else ./examples/shapes, else those installed (UserError if none)."""
    if folder is not None:
        candidates = [Path(folder)]
    else:
        candidates = [SHAPES_DIR, gallery_dir()]  # installed: the same specs (resources.gallery_dir)
    for cand in candidates:
        if cand.is_dir() and any(cand.glob("*.yaml")):
            return cand
    raise UserError(candidates[0], "no example shape specs (*.yaml) here; run from the repository or pass --shapes")


@cache
def _shape_module(path: str, mtime: float) -> tuple[ModuleType, dict]:
    """The generated Python module of one spec (generated in memory, not written anywhere) and its params."""
    from implgen.codegen.emit import generate
    from implgen.spec.entry import load_spec

    spec = load_spec(path)
    text = generate(spec, ("python",))[f"{spec.name}.py"]
    module = ModuleType(f"_bench_{spec.name}")
    exec(compile(text, f"<generated {spec.name}.py>", "exec"), module.__dict__)  # noqa: S102 -- our own output
    return module, dict(spec.params)


def shape_module(name: str, folder: str | Path | None = None) -> tuple[ModuleType, dict]:
    path = find_shapes_dir(folder) / f"{name}.yaml"
    if not path.exists():
        raise UserError(path, "no such example shape")
    return _shape_module(str(path.resolve()), path.stat().st_mtime)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# Exactly tangent rays need a surface point and its normal: analytic for the shapes that have a simple
# parametrisation. The points and normals are rounded to doubles, so "exact" means a double root, or two roots
# or none within rounding of it -- what a silhouette pixel sees.
def _graze_sphere(p: dict, rng: np.random.Generator, k: int):
    n = _unit(rng.normal(size=(k, 3)))
    return p["r"] * n, n


def _graze_cylinder(p: dict, rng: np.random.Generator, k: int):  # axis y
    u = rng.random(k) * 2 * np.pi
    n = np.stack([np.cos(u), np.zeros(k), np.sin(u)], 1)
    pts = p["r"] * n + np.stack([np.zeros(k), rng.uniform(-1, 1, k), np.zeros(k)], 1)
    return pts, n


def _graze_torus_y(p: dict, rng: np.random.Generator, k: int):  # swept radius a, tube b, axis y
    a, b = p["a"], p["b"]
    u, v = rng.random(k) * 2 * np.pi, rng.random(k) * 2 * np.pi
    n = np.stack([np.cos(v) * np.cos(u), np.sin(v), np.cos(v) * np.sin(u)], 1)
    pts = np.stack([(a + b * np.cos(v)) * np.cos(u), b * np.sin(v), (a + b * np.cos(v)) * np.sin(u)], 1)
    return pts, n


def _graze_torus_z(p: dict, rng: np.random.Generator, k: int):  # major radius R, minor r, axis z
    R, r = p["R"], p["r"]
    u, v = rng.random(k) * 2 * np.pi, rng.random(k) * 2 * np.pi
    n = np.stack([np.cos(v) * np.cos(u), np.cos(v) * np.sin(u), np.sin(v)], 1)
    pts = np.stack([(R + r * np.cos(v)) * np.cos(u), (R + r * np.cos(v)) * np.sin(u), r * np.sin(v)], 1)
    return pts, n


@dataclass(frozen=True)
class BenchShape:
    """An example shape as the bench casts rays at it."""

    params: tuple = ({},)  # param sets the rays are spread over ({}: the spec's defaults)
    outer: tuple | None = None  # for an unbounded shape: the box of the CSG parent that clips its rays first
    graze: Callable | None = None  # (params, rng, k) -> surface points, unit normals, for exactly tangent rays


BENCH_SHAPES: dict[str, BenchShape] = {
    "sphere": BenchShape(graze=_graze_sphere),
    "cylinder": BenchShape(graze=_graze_cylinder),  # bounded in x and z only
    "cone": BenchShape(),  # unbounded: solved on [0, inf) as a top-level leaf
    "piriform": BenchShape(),  # d_x = 0 drops the degree
    # the spec's defaults and the thin foot ring of examples/scenes/glassware.yaml
    "torus_y": BenchShape(params=({}, {"a": 0.36, "b": 0.04}), graze=_graze_torus_y),
    "torus_z": BenchShape(graze=_graze_torus_z),
    "heart": BenchShape(),
    # unbounded; examples/scenes/high_degree.yaml cuts it with a ball of radius 1.2, whose box clips first
    "barth6": BenchShape(outer=(-1.2, -1.2, -1.2, 1.2, 1.2, 1.2)),
    "chmutov8": BenchShape(),
    "blobs10": BenchShape(),
}

KINDS = ("far", "near", "grazing", "inside")


@dataclass
class Rays:
    """Ray polynomials of one shape as the runtime solves them: coefficients of f(o + (ts + s) d) in s,
    bounds lo = t0 - ts, hi = t1 - ts; kind indexes KINDS; t_tangent: the ray parameter t of the tangent point
    of a grazing ray (NaN for the others); params: the param overrides of each ray ({}: spec defaults)."""

    c: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    kind: np.ndarray
    o: np.ndarray
    d: np.ndarray
    ts: np.ndarray
    t_tangent: np.ndarray
    params: list


def _aim_box(bs: BenchShape, own: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The box the rays are aimed at: the shape's own where finite, else its CSG parent's, else [-1, 1]^3."""
    aim = np.array([-1.0, -1.0, -1.0, 1.0, 1.0, 1.0])
    if bs.outer is not None:
        aim = np.asarray(bs.outer, dtype=float)
    if own is not None:
        aim = np.where(np.isfinite(own), own, aim)
    return aim[:3], aim[3:]


def _sample_rays(bs: BenchShape, prm: dict, rng: np.random.Generator, box, m: int, grazing: bool):
    """m rays at random points of the box: (o, d, kind, t_tangent). kind 0 from far (1e4 units), 1 from near (3-6
    box radii), 2 exactly tangent to the surface (with grazing and a tangent-point sampler), 3 from inside."""
    lo_b, hi_b = box
    radius = 0.5 * np.linalg.norm(hi_b - lo_b)
    target = lo_b + rng.random((m, 3)) * (hi_b - lo_b)
    u = _unit(rng.normal(size=(m, 3)))
    kind = rng.integers(0, 4, size=m)
    if not (grazing and bs.graze):
        kind[kind == 2] = 1
    dist = np.where(kind == 0, 1e4, radius * (3 + 3 * rng.random(m)))
    o = target - dist[:, None] * u
    inside = kind == 3
    o[inside] = lo_b + rng.random((int(inside.sum()), 3)) * (hi_b - lo_b)
    graze = kind == 2
    k = int(graze.sum())
    if k:
        pts, nrm = bs.graze(prm, rng, k)
        tang = _unit(np.cross(nrm, rng.normal(size=(k, 3))))
        o[graze] = pts - (radius * (3 + 3 * rng.random(k)))[:, None] * tang
        u[graze] = tang
    scale = 0.5 + 1.5 * rng.random(m)
    t_tan = np.full(m, np.nan)
    if k:
        t_tan[graze] = np.linalg.norm(pts - o[graze], axis=1) / scale[graze]
    return o, u * scale[:, None], kind, t_tan


def _clip_rays(bs: BenchShape, own: np.ndarray | None, o: np.ndarray, d: np.ndarray):
    """(t0, t1, valid): the rays clipped to the shape's box (an unbounded shape: to its CSG parent's, or [0, inf))."""
    m = len(o)
    t0, t1 = np.zeros(m), np.full(m, np.inf)
    valid = np.ones(m, dtype=bool)
    if own is None and bs.outer is not None:
        t0, t1, valid = raycast._clip(np.asarray(bs.outer, dtype=float), o, d, t0, t1)
    if own is not None:
        t0, t1, v2 = raycast._clip(own, o, d, t0, t1)
        valid &= v2
    return t0, t1, valid


def ray_polys(
    name: str, count: int, rng: np.random.Generator, grazing: bool = True, shapes_dir: str | Path | None = None
) -> Rays:
    """count rays at an example shape, split evenly over its param sets: from far (1e4 units), from near (3-6
    box radii) and from inside the box, aimed at random points of the box, direction lengths 0.5-2 (not unit);
    with grazing (and a tangent-point sampler for the shape) a quarter of them exactly tangent to the surface,
    else near rays in their place. Clipped to the shape's box (an unbounded shape: to its CSG parent's box, or
    [0, inf)) and shifted exactly as runtime_c/shape.c does (implgen.raycast's twin of it)."""
    module, defaults = shape_module(name, shapes_dir)
    bs = BENCH_SHAPES.get(name, BenchShape())
    per = -(-count // len(bs.params))
    parts = []
    for given in bs.params:
        prm = {**defaults, **given}
        own = module.bounds(**prm)
        own = None if own is None else np.asarray(own, dtype=float)
        o, d, kind, t_tan = _sample_rays(bs, prm, rng, _aim_box(bs, own), per * 2, grazing)
        t0, t1, valid = _clip_rays(bs, own, o, d)
        keep = np.nonzero(valid)[0][:per]
        o, d, t0, t1, kind, t_tan = o[keep], d[keep], t0[keep], t1[keep], kind[keep], t_tan[keep]
        ts = raycast._shift_point(own, o, d, t0, t1)
        c = np.asarray(module.coeffs(o + ts[:, None] * d, d, **prm), dtype=float).reshape(len(keep), -1)
        parts.append(Rays(c, t0 - ts, t1 - ts, kind, o, d, ts, t_tan, [given] * len(keep)))
    perm = rng.permutation(sum(len(p.lo) for p in parts))[:count]
    params = [q for p in parts for q in p.params]
    fields = ("c", "lo", "hi", "kind", "o", "d", "ts", "t_tangent")
    return Rays(*(np.concatenate([getattr(p, f) for p in parts])[perm] for f in fields), [params[i] for i in perm])


def _pad(c: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros((c.shape[0], n + 1))
    out[:, : c.shape[1]] = c
    return out


def shape_set(
    names: list[str],
    count: int,
    rng: np.random.Generator,
    grazing: bool = True,
    shapes_dir: str | Path | None = None,
    weights: list[float] | None = None,
):
    """Ray polynomials of several example shapes, count in all (split evenly, or in proportion to weights),
    padded to the highest degree (leading zeros: the solvers lower the degree) and shuffled.
    Returns (coeffs, lo, hi)."""
    w = np.ones(len(names)) if weights is None else np.asarray(weights, dtype=float)
    per = [int(np.ceil(count * wi / w.sum())) for wi in w]
    parts = [ray_polys(nm, k, rng, grazing, shapes_dir) for nm, k in zip(names, per)]
    n = max(p.c.shape[1] - 1 for p in parts)
    c = np.concatenate([_pad(p.c, n) for p in parts])
    lo = np.concatenate([p.lo for p in parts])
    hi = np.concatenate([p.hi for p in parts])
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
    make: Callable[[int, np.random.Generator, Path | None], tuple[np.ndarray, np.ndarray, np.ndarray]]


TORUS = ["torus_y", "torus_z"]
RAYS_LOW = ["sphere", "cylinder", "cone", "piriform"]
RAYS_HIGH = ["heart", "barth6", "chmutov8", "blobs10"]
_RAY_MIX = "from far (1e4 units), near (3-6 box radii) and inside the box"


def prepare_shapes(folder: str | Path | None = None) -> None:
    """Every example shape the ray sets use, read and generated now (shape_module keeps them): a folder that
    lacks one, or holds a broken one, is refused before a benchmark prints or writes anything."""
    for name in (*TORUS, *RAYS_LOW, *RAYS_HIGH):
        shape_module(name, folder)


CASE_SETS = [
    CaseSet("random-4", "random quartics, N(0,1) coefficients, whole line", lambda k, r, s=None: random_set(4, k, r)),
    CaseSet(
        "torus rays",
        f"torus_y (a=1 b=0.25, and the glassware ring a=0.36 b=0.04), torus_z (R=1 r=0.25): "
        f"rays {_RAY_MIX}, and exactly tangent ones, a quarter each; box-clipped and shifted as "
        "runtime_c/shape.c does",
        lambda k, r, s=None: shape_set(TORUS, k, r, True, s),
    ),
    CaseSet(
        "torus rays (no exact grazing)",
        "the same tori and ray mix without the exactly tangent rays (a "
        "measure-zero set in a render): far 1/4, near 1/2, inside 1/4",
        lambda k, r, s=None: shape_set(TORUS, k, r, False, s),
    ),
    CaseSet(
        "rays deg 2-4",
        "sphere and cylinder (2, a quarter of their rays exactly tangent), cone (2, "
        "unbounded: [0, inf)), 1/9 each, and piriform (4, d_x = 0 drops the degree), 2/3 -- every method "
        "solves a quadratic the same way, so the median is the quartic's; padded to 4",
        lambda k, r, s=None: shape_set(RAYS_LOW, k, r, True, s, weights=[1, 1, 1, 6]),
    ),
    CaseSet(
        "rays deg 6-10",
        "heart (6), barth6 (6, unbounded: clipped by the box of the ball that cuts it in "
        "examples/scenes/high_degree.yaml), chmutov8 (8), blobs10 (10): the highest-degree example shapes, "
        "padded to 10",
        lambda k, r, s=None: shape_set(RAYS_HIGH, k, r, True, s),
    ),
    CaseSet(
        "random-12", "random degree-12, N(0,1) coefficients, whole line", lambda k, r, s=None: random_set(12, k, r)
    ),
    CaseSet(
        "hard",
        "double/quadruple roots, clusters, 1e-30..1e30 roots, 1e+-150 scale, root at lo/hi, tiny "
        "minimum, deg 12-24 products (padded to 24)",
        lambda k, r, s=None: hard_set(k, r),
    ),
]
#: the set the solver report's "degree 6-12 ray polynomials" target is measured on (the example shapes reach 10)
HIGH_RAYS = "rays deg 6-10"


def _high(name: str, describe: str, make) -> CaseSet:
    rays = "rays from far (1e4 units), near (3-6 box radii) and inside the box, a third each"
    return CaseSet(
        name,
        f"{describe}; {rays}, box-clipped and shifted as runtime_c/shape.c does (implgen.measure.cases.rays_high)",
        lambda k, r, s=None: make(k, r),
    )


#: degree 12-24 ray sets (implgen.measure.cases.rays_high): the report's cost and fallback rate per degree
HIGH_CASE_SETS = [
    *(
        _high(
            f"chmutov {n}",
            f"Chmutov surface T{n}(x) + T{n}(y) + T{n}(z) = 0, degree {n}",
            lambda k, r, n=n: raysets_high.chmutov_set(n, k, r),
        )
        for n in (12, 16, 20, 24)
    ),
    _high("linked tori 16", "four linked tori, the product of their quartics (degree 16)", raysets_high.tori_set),
    *(
        _high(
            f"spiky {n}",
            f"spiky superellipsoid x^{n} + y^{n} + z^{n} = c (x^2 + y^2 + z^2)^{n // 2 - 1} (degree {n})",
            lambda k, r, n=n: raysets_high.spiky_set(n, k, r),
        )
        for n in (20, 24)
    ),
]
