"""Rays per second through Embree 3 with implgen's user-geometry callbacks (runtime_c/embree_shape.c) against
implgen's own tracer, on 1, 100 and 10,000 algebraic objects and on a mixed scene with a 100k-triangle mesh.

    nice .venv/bin/python bench/embree.py [--runs 7] [--size 640x360] [-o bench/results/embree.md]

The driver is tests/c/embree_check.c built with -O2 (its `bench` mode): both tracers, one thread, the same
float camera rays (primary: closest hit) and the same shadow rays toward the light (any hit, tfar = 1).
Embree runs single rays (rtcIntersect1) and 8-wide coherent packets (rtcIntersect8); the tracer runs
rt_scene_intersect. Times are the thread's CPU time (CLOCK_THREAD_CPUTIME_ID), so other work on a shared
machine counts against neither. Every repetition times every method once, in turn;
the table gives medians, and the ratios' medians and ranges taken within each repetition. The tracer has no
triangle meshes: on the mixed scene it traces the same scene without the mesh (its column says so). Needs
Debian's libembree-dev (`make embree`).
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import tempfile
from pathlib import Path

from embree_scenes import build_driver, grid  # beside this script

from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results

ROOT = Path(__file__).resolve().parents[1]


COLUMNS = ("tracer", "embree1", "embree8", "tracer_shadow", "embree_shadow")


def scenes():
    """Shapes alone (no ground: the algebraic work only), then the 100 shapes with the ground and a mesh."""
    alone = [grid(n) for n in (1, 100, 10_000)]
    for scene in alone:
        scene.ground = 0.0
    mixed = grid(100)
    mixed.mesh = 100_000
    return [
        ("1 shape", alone[0]),
        ("100 shapes", alone[1]),
        ("10,000 shapes", alone[2]),
        ("100 shapes, ground, 100k-triangle mesh", mixed),
    ]


def measure(driver: Path, scene, size: tuple[int, int], runs: int, tmp: Path) -> dict[str, float]:
    path = tmp / "scene.txt"
    path.write_text(scene.text())
    out = subprocess.run(
        [str(driver), "bench", str(path), str(size[0]), str(size[1]), str(runs)],
        capture_output=True,
        text=True,
        check=False,
    )
    if out.returncode != 0:
        raise SystemExit(f"bench/embree.py: the driver failed:\n{out.stderr}")
    rows = [line for line in out.stdout.splitlines() if line.startswith("bench:")]
    values: dict[str, list[float]] = {c: [] for c in COLUMNS}
    for line in rows:
        for c in COLUMNS:
            values[c].append(float(re.search(rf" {c} (\S+)", line)[1]))
    result = {c: statistics.median(v) for c, v in values.items()}
    # ratios within each repetition (the methods ran back to back), then their median and range
    for name, num, den in (("ratio", "embree1", "tracer"), ("ratio_shadow", "embree_shadow", "tracer_shadow")):
        r = [a / b for a, b in zip(values[num], values[den])]
        result[name], result[name + "_lo"], result[name + "_hi"] = statistics.median(r), min(r), max(r)
    return result


def report(results: list[tuple[str, dict[str, float]]], size: tuple[int, int], runs: int) -> str:
    lines = [
        "# Embree with implgen's callbacks against implgen's tracer",
        "",
        f"Machine: {machine()}; load average before the run: {load_average()}.",
        f"Written by `bench/embree.py --runs {runs} --size {size[0]}x{size[1]}`: one thread, {size[0]}x{size[1]} "
        f"camera rays and as many shadow rays per scene, medians of {runs} interleaved repetitions, in millions "
        "of rays per second of the thread's CPU time (other work on the shared machine counts against neither). "
        "Embree 3 (Debian's libembree3), rtcIntersect1 and 8-wide coherent packets; the tracer: "
        "rt_scene_intersect. The shapes: the example shapes of degree 2 to 10 in turn, small, turned at random, "
        "on a grid; the last scene adds a ground square (two triangles in Embree, the plane y = 0 in the "
        "tracer) and, in Embree only, a sphere of 100,000 triangles among the shapes.",
        "",
        "Ratios are taken within each repetition and given as median (lowest-highest).",
        "",
        "| scene | tracer | Embree, single rays | Embree, packets of 8 | Embree / tracer | tracer, shadow "
        "| Embree, shadow | Embree / tracer, shadow |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results:
        note = " (no mesh)" if "mesh" in name else ""
        lines.append(
            f"| {name} | {r['tracer'] / 1e6:.2f}{note} | {r['embree1'] / 1e6:.2f} | {r['embree8'] / 1e6:.2f} | "
            f"{r['ratio']:.2f}x ({r['ratio_lo']:.2f}-{r['ratio_hi']:.2f}) | {r['tracer_shadow'] / 1e6:.2f}{note} | "
            f"{r['embree_shadow'] / 1e6:.2f} | {r['ratio_shadow']:.2f}x ({r['ratio_shadow_lo']:.2f}-"
            f"{r['ratio_shadow_hi']:.2f}) |"
        )
    lines += ["", "Where each wins and why: [docs/embree.md](../../docs/embree.md#speed).", ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--size", default="640x360")
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "embree.md")
    args = ap.parse_args(argv)
    size = tuple(int(v) for v in args.size.split("x"))
    with tempfile.TemporaryDirectory() as tmp:
        driver = build_driver(Path(tmp) / "embree_check", sanitize=False)
        results = []
        for name, scene in scenes():
            r = measure(driver, scene, size, args.runs, Path(tmp))
            print(f"{name}: " + ", ".join(f"{c} {r[c] / 1e6:.2f} M/s" for c in COLUMNS), flush=True)
            results.append((name, r))
    write_results(args.output, report(results, size, args.runs))
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
