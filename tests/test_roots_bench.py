"""`implgen bench solvers`: the ray sets come from the example shapes as the runtime solves them, first-root
mode is timed and scored, and `--quick` runs end to end with its table, targets and plot."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from conftest import SHAPES_DIR
from implgen.cli import main as cli_main
from implgen.measure.cases.polys import (
    BENCH_SHAPES,
    CASE_SETS,
    HIGH_CASE_SETS,
    HIGH_RAYS,
    KINDS,
    RAYS_HIGH,
    RAYS_LOW,
    TORUS,
    ray_polys,
    shape_module,
    shape_set,
)
from implgen.measure.cases.reference import exact_roots, reference, score_first, score_one
from implgen.measure.solvers import FIRST, FIRST_METHODS, HIGH_METHODS, METHODS, main
from implgen.roots.solvers import (
    bench_fallbacks,
    bench_first_batch,
    bench_solve_batch,
    first_root_batch,
    real_roots_batch,
)
from implgen.spec import gallery

RAY_SETS = [cs.name for cs in CASE_SETS if "rays" in cs.name]
HIGH_SETS = [cs.name for cs in HIGH_CASE_SETS]


def test_every_example_shape_is_in_a_ray_set() -> None:
    """Every example shape outside the gallery of famous surfaces (docs/surfaces.md: those are checked against
    the literature and rendered in tests/test_gallery*.py) is in a ray set of the solver benchmark."""
    gallery_only = {e.name for e in gallery.entries(SHAPES_DIR)} - {"heart", "barth6", "chmutov8"}
    examples = sorted(p.stem for p in SHAPES_DIR.glob("*.yaml") if p.stem not in gallery_only)
    assert sorted(TORUS + RAYS_LOW + RAYS_HIGH) == sorted(BENCH_SHAPES) == examples
    assert set(RAY_SETS) == {"torus rays", "torus rays (no exact grazing)", "rays deg 2-4", HIGH_RAYS}


@pytest.mark.parametrize(
    "name", ["sphere", "cylinder", "piriform", "torus_y", "torus_z", "heart", "chmutov8", "blobs10"]
)
def test_ray_polynomials_are_the_generated_intersectors_own(name: str) -> None:
    """Bench polynomial + shift back gives bit for bit what the generated module's intersect() returns (its
    box clip and origin shift, implgen.raycast, are the twin of runtime_c/shape.c)."""
    r = ray_polys(name, 120, np.random.default_rng(4), shapes_dir=SHAPES_DIR)
    module, defaults = shape_module(name, SHAPES_DIR)
    assert r.c.shape == (120, module.DEGREE + 1) and np.all(np.isfinite(r.c))
    assert np.all(r.lo <= r.hi) and np.all(np.isfinite(r.lo)) and np.all(np.isfinite(r.hi))
    s, counts = first_root_batch(r.c, r.lo, r.hi)
    ours = np.where(counts > 0, np.clip(r.ts + s, r.ts + r.lo, r.ts + r.hi), np.inf)
    theirs = np.array(
        [module.intersect(r.o[i], r.d[i], 0.0, np.inf, **{**defaults, **r.params[i]}) for i in range(120)]
    )
    np.testing.assert_array_equal(ours, theirs)
    assert np.isfinite(ours).sum() > 40  # they hit, not just pass by


def test_ray_mix_far_near_inside_grazing() -> None:
    r = ray_polys("torus_y", 400, np.random.default_rng(2), shapes_dir=SHAPES_DIR)
    counts = np.bincount(r.kind, minlength=4)
    assert all(counts[KINDS.index(k)] > 60 for k in KINDS), counts
    far = r.kind == KINDS.index("far")
    assert np.all(np.linalg.norm(r.o[far], axis=1) > 9e3)
    assert {tuple(sorted(p.items())) for p in r.params} == {(), (("a", 0.36), ("b", 0.04))}
    # exactly tangent: p and p' vanish (to rounding) at the tangent point, and the exact polynomial has two
    # roots next to it or none (never one simple root there)
    g = np.nonzero(r.kind == KINDS.index("grazing"))[0]
    for i in g:
        c, x = r.c[i], r.t_tangent[i] - r.ts[i]
        big = np.max(np.abs(c)) * max(1.0, abs(x)) ** (len(c) - 1)
        assert abs(np.polyval(c[::-1], x)) <= 1e-13 * big
        assert abs(np.polyval(np.polyder(c[::-1]), x)) <= 1e-13 * big
    for i in g[:12]:
        x = r.t_tangent[i] - r.ts[i]
        near = [q for q in exact_roots(r.c[i]) if abs(q.value - x) < 1e-6]
        assert len(near) in (0, 2) or (len(near) == 1 and near[0].mult == 2)
    # no exact grazing: the same shapes, tangent rays replaced by near ones
    r2 = ray_polys("torus_y", 400, np.random.default_rng(2), grazing=False, shapes_dir=SHAPES_DIR)
    assert not np.any(r2.kind == KINDS.index("grazing")) and np.all(np.isnan(r2.t_tangent))
    assert ray_polys("heart", 100, np.random.default_rng(2), shapes_dir=SHAPES_DIR).t_tangent.size == 100


def test_unbounded_shapes_clip_like_the_runtime() -> None:
    cone = ray_polys("cone", 60, np.random.default_rng(1), shapes_dir=SHAPES_DIR)
    assert np.all(np.isinf(cone.hi)) and np.allclose(cone.lo, -cone.ts)  # a top-level leaf: [0, inf)
    barth = ray_polys("barth6", 60, np.random.default_rng(1), shapes_dir=SHAPES_DIR)
    t0, t1 = barth.ts + barth.lo, barth.ts + barth.hi
    for t in (t0, t1):  # clipped by the box of the ball of examples/scenes/high_degree.yaml
        p = barth.o + t[:, None] * barth.d
        assert np.all(np.abs(p) <= 1.2 + 1e-6)


def test_shape_set_pads_to_the_highest_degree() -> None:
    c, lo, hi = shape_set(["sphere", "piriform"], 50, np.random.default_rng(0), shapes_dir=SHAPES_DIR)
    assert c.shape == (50, 5) and lo.shape == hi.shape == (50,)
    assert np.any(np.all(c[:, 3:] == 0.0, axis=1)) and np.any(c[:, 4] != 0.0)


def test_score_first() -> None:
    c = np.poly([1.0, 2.0, 3.0])[::-1]
    ref = exact_roots(c)
    ok = score_first(c, -np.inf, np.inf, np.array([1.0]), ref)
    assert (ok.ref_simple, ok.missed, ok.phantom, ok.errors_well) == (1, 0, 0, [0.0])
    assert score_first(c, -np.inf, np.inf, np.array([2.0]), ref).missed == 1  # skipped the nearest root
    assert score_first(c, -np.inf, np.inf, np.array([]), ref).missed == 1  # saw through the surface
    bad = score_first(c, -np.inf, np.inf, np.array([0.5]), ref)  # a hit where there is none
    assert (bad.phantom, bad.missed) == (1, 0)
    assert score_first(c, 1.5, 10.0, np.array([2.0]), ref).missed == 0  # nearest in [lo, hi]
    none = score_first(c, 3.5, 10.0, np.array([]), ref)
    assert (none.ref_simple, none.missed) == (0, 0)
    tangent = np.poly([1.0, 1.0, 3.0])[::-1]  # a grazing root first
    assert score_first(tangent, 0.0, 10.0, np.array([1.0]), exact_roots(tangent)).missed == 0


def test_bench_first_batch_matches_first_root_batch() -> None:
    c, lo, hi = shape_set(["torus_y", "torus_z"], 300, np.random.default_rng(9), shapes_dir=SHAPES_DIR)
    for m in FIRST_METHODS:
        r1, n1, ns, total = bench_first_batch(c, lo, hi, m)
        r2, n2 = first_root_batch(c, lo, hi, m)
        np.testing.assert_array_equal(n1, n2)
        np.testing.assert_array_equal(r1, r2)
        assert ns.shape == (300,) and np.all(np.isfinite(ns)) and total > 0
        allr, counts = real_roots_batch(c, lo, hi, m)  # the first of all roots
        assert np.array_equal(n1, np.minimum(counts, 1))
        first_of_all = np.where(counts > 0, allr[:, 0], np.nan)[n1 > 0]
        # bracket: the very same computation; Bernstein visits the same pieces left to right in both modes
        np.testing.assert_array_equal(first_of_all, r1[n1 > 0])
    roots, counts, ns, _ = bench_solve_batch(c, lo, hi, "auto")
    assert roots.shape == (300, 4) and ns.shape == (300,) and np.all(np.isfinite(ns))


def _table(md: str) -> dict[tuple[str, str], list[str]]:
    rows = {}
    for line in md.splitlines():
        cells = [x.strip() for x in line.strip().strip("|").split("|")]
        if len(cells) == 10 and cells[0] not in ("case set", "---"):
            rows[(cells[0], cells[1])] = cells[2:]
    return rows


def test_bench_solvers_refuses_a_shapes_folder_without_its_shapes_before_any_output(tmp_path: Path, capsys) -> None:
    """A --shapes folder that lacks a shape the ray sets use: one line naming it, no header printed, and no -o
    folder made (before, the folder was created and a case set run before the refusal)."""
    shapes = tmp_path / "shapes"
    shapes.mkdir()
    shutil.copy(SHAPES_DIR / "sphere.yaml", shapes)
    out = tmp_path / "out" / "bench"
    assert cli_main(["bench", "solvers", "--quick", "--shapes", str(shapes), "-o", str(out)]) == 2
    said = capsys.readouterr()
    assert said.out == "" and said.err.count("\n") == 1
    assert said.err.startswith(f"implgen: error: {shapes}/") and "no such example shape" in said.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["shapes"]


def test_bench_solvers_quick(tmp_path: Path) -> None:
    assert main(["--quick", "-o", str(tmp_path), "--shapes", str(SHAPES_DIR)]) == 0
    md = (tmp_path / "solvers.md").read_text()
    rows = _table(md)
    methods = METHODS + [m + FIRST for m in FIRST_METHODS] + ["numpy.roots"]
    high = HIGH_METHODS + [m + FIRST for m in FIRST_METHODS] + ["numpy.roots"]
    assert set(rows) == {(cs.name, m) for cs in CASE_SETS for m in methods} | {
        (cs.name, m) for cs in HIGH_CASE_SETS for m in high
    }
    for (case, method), cells in rows.items():
        median, mean, worst, _, missed, phantom, _, fallback = cells
        assert (fallback == "-") == (method.split(" ")[0] not in ("auto", "bernstein")), (case, method, fallback)
        found, required = (int(v) for v in missed.split("/"))
        assert required > 0, (case, method)
        if method != "numpy.roots":
            assert float(median) > 0 and float(mean) > 0
        if case in RAY_SETS or case.startswith("random") or case in HIGH_SETS:
            if method in ("auto", "bracket", "bernstein", "auto" + FIRST, "bernstein" + FIRST):
                # the accurate methods: no missed or phantom root on rays and random polynomials
                assert found == 0 and int(phantom) == 0, (case, method, cells)
                assert float(worst) <= 1e-12, (case, method, cells)
    # first-root rows: one required root at most per polynomial (40 referenced)
    assert int(rows[("torus rays", "auto" + FIRST)][4].split("/")[1]) <= 40
    for cs in CASE_SETS:
        assert f"- **{cs.name}**:" in md
    targets = md.split("Targets:")[1]
    assert re.search(r"- No missed/phantom simple roots: auto (MET|NOT MET)", targets)
    assert re.search(r"- Rel\. error <= 1e-12 .*: max \S+ (MET|NOT MET)", targets)
    for case in ("torus rays", "torus rays (no exact grazing)"):
        assert re.search(
            rf"- auto within 2x the fastest closed-form quartic \(closed(_plain)?\) on "
            rf"{re.escape(case)}: \d+ vs \d+ ns = [\d.]+x.*: (MET|NOT MET)\.",
            targets,
        )
    assert re.search(
        rf"- Bracketing >= 3x faster than Sturm on degree 6-12 ray polynomials \({HIGH_RAYS}.*"
        r"= [\d.]+x.*: (MET|NOT MET)\.",
        targets,
    )
    first = re.search(r"- First-root mode .*torus rays [\d.]+x.*rays deg 2-4 [\d.]+x.*: (MET|NOT MET)\.", targets)
    assert first, targets
    assert re.search(r"- First-root cost from degree 12 to 24 .* grows as n\^[\d.]+ .*(MET|NOT MET)\.", targets)
    assert re.search(r"- Degree 20 Chmutov rays, auto first root: \d+ ns <= 2500 (MET|NOT MET)\.", targets)
    assert re.search(r"- auto within 10 % of the fastest accurate method .* worst ratio [\d.]+ (MET|NOT MET)", targets)
    per_degree = md.split("Per degree")[1].split("Case sets:")[0]
    for cs in HIGH_CASE_SETS:
        assert f"| {cs.name} |" in per_degree
    assert (tmp_path / "solvers.png").stat().st_size > 10_000


def test_high_degree_ray_sets_against_exact_reference() -> None:
    """The degree 12-24 ray sets: every simple root found, no phantom, by auto and bracketing in both modes, and
    at most one ray of 60 with a Bernstein piece left to bracketing (the rounding certificate decides the rest); the ray
    polynomials have the degree of their surface and hit it."""
    for cs in HIGH_CASE_SETS:
        c, lo, hi = cs.make(60, np.random.default_rng(11))
        deg = int(cs.name.split()[-1])
        assert c.shape == (60, deg + 1) and np.all(c[:, deg] != 0) and np.all(lo < hi)
        ref = reference(c[:25])
        hits = 0
        for method in ("auto", "bracket"):
            roots, counts = real_roots_batch(c, lo, hi, method)
            first, fcounts = first_root_batch(c, lo, hi, method)
            assert np.array_equal(fcounts, (counts > 0).astype(fcounts.dtype))
            assert np.array_equal(first[fcounts > 0], roots[fcounts > 0, 0])
            for i in range(25):
                s = score_one(c[i], lo[i], hi[i], roots[i, : counts[i]], ref[i])
                assert s.missed == 0 and s.phantom == 0, (cs.name, method, i)
                hits += s.ref_simple
        assert hits > 0, cs.name
        # a nearly tangent ray may still need bracketing: 1 in 1000 at degree 24 in the report
        assert (bench_fallbacks(c, lo, hi, "bernstein") > 0).sum() <= 1, cs.name
