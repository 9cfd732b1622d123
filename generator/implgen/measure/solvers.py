"""`implgen bench solvers`: speed against error of the root solvers, written as a Markdown table and a plot.

    implgen bench solvers [-o DIR] [--timed N] [--ref N] [--quick] [--seed S] [--shapes DIR]

For each case set and method: ns per solve measured in C (clock_gettime around every solve, median over
--timed polynomials, plus the mean of an untimed pass), and against the exact reference
(implgen.measure.cases.reference, on a --ref subset): max relative error on well-conditioned roots, median relative
error, missed simple roots, phantom roots. Methods in FIRST_METHODS are also timed in first-root mode
(ig_first_root) and scored against the smallest exact root. numpy.roots runs on the same polynomials as an
outside reference (its time is a Python call, not comparable with the C figures). The ray sets are the
example shapes (examples/shapes/*.yaml, or --shapes) through the generator, clipped and shifted as the
runtime does. Output: DIR/solvers.md, DIR/solvers.png (default DIR: bench/results).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from implgen.args import ArgumentParser
from implgen.errors import UserError, printable
from implgen.measure.cases.polys import CASE_SETS, HIGH_CASE_SETS, HIGH_RAYS, CaseSet, find_shapes_dir, prepare_shapes
from implgen.measure.cases.reference import Score, reference, score_first, score_one
from implgen.measure.machine import describe as machine
from implgen.measure.solvers_high import degree_table, high_targets
from implgen.outputs import check_output_folder
from implgen.roots.solvers import bench_fallbacks, bench_first_batch, bench_solve_batch

METHODS = ["closed_plain", "closed", "sturm", "bracket", "bernstein", "auto"]
#: on the degree 12-24 sets the closed forms are bracketing (degree > 4), so they are left out
HIGH_METHODS = ["sturm", "bracket", "bernstein", "auto"]


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
    method: str  # a METHODS name, "<method> (first root)" or "numpy.roots"
    median_ns: float
    mean_ns: float
    score: Score
    timed: int
    fallback: float = float("nan")  # share of polynomials with a Bernstein piece handed to bracketing


#: methods also timed in first-root mode (ig_first_root: the nearest hit, what the tracer asks for)
FIRST_METHODS = ["bracket", "bernstein", "auto"]
FIRST = " (first root)"


def _score(c, lo, hi, roots_of: Callable[[int], np.ndarray], ref, scorer=score_one) -> Score:
    total = Score()
    for i, rr in enumerate(ref):
        total.add(scorer(c[i], lo[i], hi[i], roots_of(i), rr))
    return total


#: polynomials per round of the interleaved timing (see _time_interleaved)
CHUNK = 5000


def _time_interleaved(
    c: np.ndarray, lo: np.ndarray, hi: np.ndarray, methods: list[str], first_methods: list[str]
) -> dict[str, tuple[np.ndarray, np.ndarray, np.ndarray, float]]:
    """Time every method (all roots) and every first-root method on the same CHUNK polynomials in turn, chunk
    after chunk, and join the pieces: each method then sees the machine in the same state. On a shared virtual
    machine the speed drifts by tens of percent within a minute, which timing one method after the other turned
    into ratio errors of the same size. Returns {name: (roots, counts, ns per solve, untimed total ns)}."""
    jobs = [(m, m, bench_solve_batch) for m in methods] + [(m + FIRST, m, bench_first_batch) for m in first_methods]
    parts: dict[str, list] = {name: [] for name, _, _ in jobs}
    for s in range(0, c.shape[0], CHUNK):
        sl = slice(s, s + CHUNK)
        for name, m, fn in jobs:
            parts[name].append(fn(c[sl], lo[sl], hi[sl], m))
    return {
        name: (
            np.concatenate([p[0] for p in ps]),
            np.concatenate([p[1] for p in ps]),
            np.concatenate([p[2] for p in ps]),
            float(sum(p[3] for p in ps)),
        )
        for name, ps in parts.items()
    }


def run(
    timed: int,
    nref: int,
    seed: int,
    methods: list[str],
    sets: list[CaseSet],
    log=print,
    first_methods: list[str] | None = None,
    shapes_dir: str | Path | None = None,
) -> list[Row]:
    first_methods = FIRST_METHODS if first_methods is None else first_methods
    rows: list[Row] = []
    for cs in sets:
        rng = np.random.default_rng(seed)
        c, lo, hi = cs.make(timed, rng, shapes_dir)
        t = time.time()
        ref = reference(c[:nref])
        log(
            f"  {cs.name}: {c.shape[0]} polynomials (degree <= {c.shape[1] - 1}), reference on {len(ref)} "
            f"in {time.time() - t:.1f} s"
        )
        timings = _time_interleaved(c, lo, hi, methods, first_methods)
        for m in methods:
            roots, counts, ns, total = timings[m]
            sc = _score(c, lo, hi, lambda i: roots[i, : counts[i]], ref)
            fb = _fallback_share(c, lo, hi, m, False)
            rows.append(Row(cs.name, m, float(np.median(ns)), total / c.shape[0], sc, c.shape[0], fb))
        for m in first_methods:
            r1, n1, ns, total = timings[m + FIRST]
            sc = _score(c, lo, hi, lambda i: r1[i : i + n1[i]], ref, score_first)
            fb = _fallback_share(c, lo, hi, m, True)
            rows.append(Row(cs.name, m + FIRST, float(np.median(ns)), total / c.shape[0], sc, c.shape[0], fb))
        k = min(c.shape[0], max(nref, 2000))
        t0 = time.perf_counter_ns()
        npr = [numpy_real_roots(c[i], lo[i], hi[i]) for i in range(k)]
        el = (time.perf_counter_ns() - t0) / k
        sc = _score(c, lo, hi, lambda i: npr[i], ref)
        rows.append(Row(cs.name, "numpy.roots", float("nan"), el, sc, k))
    return rows


def _fallback_share(c, lo, hi, method: str, first: bool) -> float:
    """Share of the polynomials where the Bernstein subdivision handed a piece to bracketing (an untimed pass)."""
    if method not in ("bernstein", "auto"):
        return float("nan")
    return float(np.mean(bench_fallbacks(c, lo, hi, method, first) > 0))


def _fmt_err(v: list) -> str:
    return f"{max(v):.1e}" if v else "-"


def _fmt_share(v: float) -> str:
    return "-" if np.isnan(v) else f"{100 * v:.2f} %"


def _fmt_med(v: list) -> str:
    return f"{np.median(v):.1e}" if v else "-"


def _worst(r: Row) -> float:
    return max(r.score.errors_well) if r.score.errors_well else 0.0


def _bad(r: Row) -> int:
    return r.score.missed + r.score.phantom


def _no_missed_roots(rows: list[Row]) -> str:
    bad = [(r.case, r.method) for r in rows if r.method != "numpy.roots" and _bad(r)]
    auto_bad = [k for k in bad if k[1] in ("auto", "auto" + FIRST)]
    return (
        f"- No missed/phantom simple roots: auto {'MET' if not auto_bad else 'NOT MET ' + str(auto_bad)}; "
        f"all methods with any: {bad if bad else 'none'}."
    )


def _error_bound(rows: list[Row]) -> str:
    worst = max((_worst(r) for r in rows if r.method in ("auto", "auto" + FIRST)), default=0.0)
    return (
        f"- Rel. error <= 1e-12 on well-conditioned roots (auto, all sets, both modes): max {worst:.1e} "
        f"{'MET' if worst <= 1e-12 else 'NOT MET'}."
    )


def _against_closed_form(by: dict, case: str) -> str | None:
    """auto against the fastest closed-form quartic on one torus ray set, or None when either is missing."""
    closed = [by[(case, m)] for m in ("closed_plain", "closed") if (case, m) in by]
    if (case, "auto") not in by or not closed:
        return None
    auto = by[(case, "auto")]
    fastest = min(closed, key=lambda r: r.median_ns)
    ratio = auto.median_ns / fastest.median_ns
    ea, ef = _worst(auto), _worst(fastest)
    better = (ea < ef) or (_bad(auto) < _bad(fastest))
    return (
        f"- auto within 2x the fastest closed-form quartic ({fastest.method}) on {case}: "
        f"{auto.median_ns:.0f} vs {fastest.median_ns:.0f} ns = {ratio:.2f}x, max error {ea:.1e} vs "
        f"{ef:.1e}, missed+phantom {_bad(auto)} vs {_bad(fastest)}: "
        f"{'MET' if ratio <= 2 and better else 'NOT MET'}."
    )


def _bracketing_against_sturm(by: dict) -> str | None:
    if (HIGH_RAYS, "bracket") not in by or (HIGH_RAYS, "sturm") not in by:
        return None
    b, st = by[(HIGH_RAYS, "bracket")], by[(HIGH_RAYS, "sturm")]
    ratio = st.median_ns / b.median_ns
    return (
        f"- Bracketing >= 3x faster than Sturm on degree 6-12 ray polynomials ({HIGH_RAYS}: the "
        f"example shapes reach degree 10): {b.median_ns:.0f} vs {st.median_ns:.0f} ns = {ratio:.1f}x, "
        f"max error {_worst(b):.1e} vs {_worst(st):.1e}: {'MET' if ratio >= 3 else 'NOT MET'}."
    )


def _first_root_mode(rows: list[Row], by: dict) -> str | None:
    firsts = [r for r in rows if r.method == "auto" + FIRST and (r.case, "auto") in by]
    if not firsts:
        return None
    ray_cases = [r for r in firsts if "rays" in r.case]
    speed = ", ".join(f"{r.case} {by[(r.case, 'auto')].median_ns / r.median_ns:.2f}x" for r in ray_cases)
    first_bad = [(r.case, r.method) for r in rows if r.method.endswith(FIRST) and _bad(r)]
    # where a render spends its solver time: tori and the high-degree shapes
    key = [r for r in ray_cases if r.case in ("torus rays (no exact grazing)", HIGH_RAYS)]
    faster = all(r.median_ns < by[(r.case, "auto")].median_ns for r in key)
    line = (
        f"- First-root mode (ig_first_root, what the tracer calls; a report line, not an issue target): "
        f"auto (first root) against auto (all roots), median speed-up: {speed}"
    )
    if ("torus rays (no exact grazing)", "closed_plain") in by:
        case = "torus rays (no exact grazing)"
        f, cp = by[(case, "auto" + FIRST)], by[(case, "closed_plain")]
        line += (
            f"; on {case} {f.median_ns:.0f} ns against {cp.median_ns:.0f} for closed_plain (all roots) "
            f"= {f.median_ns / cp.median_ns:.2f}x"
        )
    return line + (
        f"; missed/phantom first roots: {first_bad if first_bad else 'none'}. Faster than all roots on "
        f"torus rays (no exact grazing) and {HIGH_RAYS}, with no missed/phantom first root on any set: "
        f"{'MET' if faster and not first_bad else 'NOT MET'}."
    )


def targets(rows: list[Row]) -> list[str]:
    """The report's three targets (plus the error bound), then first-root mode, each evaluated on these rows."""
    by = {(r.case, r.method): r for r in rows}
    lines = [_no_missed_roots(rows), _error_bound(rows)]
    lines += [_against_closed_form(by, c) for c in ("torus rays", "torus rays (no exact grazing)")]
    lines += [_bracketing_against_sturm(by), _first_root_mode(rows, by)]
    return [line for line in lines if line is not None]


def table(rows: list[Row], sets: list[CaseSet], timed: int, nref: int, seconds: float) -> str:
    lines = [
        f"Measured on: {machine()}. Maximum degree: 24. {timed} polynomials timed per set, exact reference on "
        f"the first {nref}; run took {seconds:.0f} s.",
        "",
        "| case set | method | median ns/solve (C) | mean ns (C, untimed pass) | max rel err (well-cond.) | "
        "median rel err | missed simple | phantom | near-tangent reports | fallback |",
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        s = r.score
        med = "-" if np.isnan(r.median_ns) else f"{r.median_ns:.0f}"
        mean = f"{r.mean_ns:.0f}" + (" (Python)" if r.method == "numpy.roots" else "")
        lines.append(
            f"| {r.case} | {r.method} | {med} | {mean} | {_fmt_err(s.errors_well)} | {_fmt_med(s.errors_all)} | "
            f"{s.missed}/{s.ref_simple} | {s.phantom} | {s.near_tangent} | {_fmt_share(r.fallback)} |"
        )
    lines += [
        "",
        f'Rows "<method>{FIRST}" time ig_first_root (the nearest root only) and are scored against the '
        'smallest exact root in [lo, hi]: "missed" counts polynomials whose first required root (simple, '
        'condition <= 1e8, inside) was skipped or not returned, out of those that have one; "phantom" a '
        "returned root that is no root.",
    ]
    high = [cs for cs in sets if cs in HIGH_CASE_SETS]
    if high:
        lines += ["", "Per degree (medians of the rows above):", ""] + degree_table(rows, high)
    lines += ["", "Case sets:", ""]
    lines += [f"- **{cs.name}**: {cs.describe}" for cs in sets]
    lines += ["", "Targets:", ""] + targets(rows) + high_targets(rows)
    return "\n".join(lines) + "\n"


def plot(rows: list[Row], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 5.5))
    markers = {
        "closed_plain": "s",
        "closed": "D",
        "sturm": "^",
        "bracket": "o",
        "bernstein": "v",
        "auto": "*",
        "bernstein" + FIRST: "1",
        "auto" + FIRST: "P",
        "numpy.roots": "x",
    }
    cases = list(dict.fromkeys(r.case for r in rows))
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for r in rows:
        x = r.mean_ns if r.method == "numpy.roots" else r.median_ns
        y = max(r.score.errors_well) if r.score.errors_well else 1e-17
        ax.scatter(
            x,
            max(y, 1e-17),
            marker=markers.get(r.method, "."),
            s=70,
            color=colors[cases.index(r.case) % len(colors)],
            alpha=0.85,
        )
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


EXAMPLES = (
    ("the report of bench/results/solvers.md and solvers.png", "implgen bench solvers"),
    ("a quick run (small sizes) into out/bench/", "implgen bench solvers --quick -o out/bench"),
)


def main(argv: list[str] | None = None) -> int:
    ap = ArgumentParser(prog="implgen bench solvers", description=__doc__.splitlines()[0], examples=EXAMPLES)
    ap.add_argument("-o", "--out", default="bench/results", help="output folder (default bench/results)")
    ap.add_argument("--timed", type=int, default=100_000, help="polynomials timed per case set (default 1e5)")
    ap.add_argument("--ref", type=int, default=400, help="polynomials per set checked against the exact reference")
    ap.add_argument("--seed", type=int, default=2024)
    ap.add_argument("--quick", action="store_true", help="small sizes (for tests): 2000 timed, 40 referenced")
    ap.add_argument(
        "--shapes",
        default=None,
        help="folder of the example shape specs the ray sets come from (default: examples/shapes)",
    )
    args = ap.parse_args(list(argv) if argv is not None else None)
    if args.quick:
        args.timed, args.ref = 2000, 40
    if args.timed < 1 or args.ref < 1 or args.ref > args.timed:
        raise UserError("bench solvers", "need 1 <= --ref <= --timed")
    shapes = find_shapes_dir(args.shapes)
    out = Path(args.out)
    check_output_folder(out, "-o")
    prepare_shapes(shapes)  # a missing or broken shape: one line, before the header and before -o is made
    t = time.time()
    print(
        f"implgen bench solvers: {len(CASE_SETS)} case sets x {len(METHODS)} methods and {len(HIGH_CASE_SETS)} "
        f"of degree 12-24 x {len(HIGH_METHODS)}, "
        f"{len(FIRST_METHODS)} in first-root mode, + numpy.roots; ray sets from {shapes}/"
    )
    rows = run(args.timed, args.ref, args.seed, METHODS, CASE_SETS, shapes_dir=shapes)
    rows += run(args.timed, args.ref, args.seed, HIGH_METHODS, HIGH_CASE_SETS, shapes_dir=shapes)
    seconds = time.time() - t
    md = table(rows, CASE_SETS + HIGH_CASE_SETS, args.timed, args.ref, seconds)
    out.mkdir(parents=True, exist_ok=True)
    (out / "solvers.md").write_text(md)
    plot(rows, out / "solvers.png")
    print(md)
    print(f"wrote {printable(str(out / 'solvers.md'))} and {printable(str(out / 'solvers.png'))}")
    return 0
