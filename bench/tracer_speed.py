"""The render loop of a base copy of the C runtime (main's) against this one, interleaved, on one thread.

    .venv/bin/python bench/tracer_speed.py --base /work/main/runtime_c [SCENE.yaml ...] [--runs 7]
        [--width 800 --height 600] [-o bench/results/tracer_speed.md]

Each scene (default: examples/scenes/glassware.yaml, examples/scenes/high_degree.yaml and the POV-Ray comparison's
scenes, bench/scenes/*.yaml) is built against the base runtime_c folder and against this checkout's, with the same
generated shapes, and a second time against the base: the control. Round by round the three render it, in an order
that turns through all six, 1 sample per pixel, one thread, the C render loop alone (rt_render_run, as `implgen
bench render` times it). Reported: medians of the wall time and of the process's CPU time during the loop, and the
ratios of each round's CPU times -- base/this, and base/control, which differ only by the noise -- as their median
and quartiles. On a machine shared with other work a round's three runs see about the same load, so the paired
ratio is the steadier figure, and the control's spread says how far one can trust it; the load average before and
after is given. The target checked is the paired base/this >= TARGET on every scene.

The base folder is copied to a temporary one first; a file this checkout's runtime lists that the base lacks
(tracer_floor.c, the floor report's, which the render loop never calls) is given an empty stand-in there.
"""

from __future__ import annotations

import argparse
import itertools
import shutil
import statistics
import tempfile
from pathlib import Path

import picture_diff

from implgen.measure.machine import describe, load_average, write_results
from implgen.measure.render import _measure
from implgen.resources import TRACER_SOURCES
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.tracer import CScene

ROOT = Path(__file__).resolve().parents[1]
TARGET = 2.0
DEFAULT_SCENES = [ROOT / "examples" / "scenes" / "glassware.yaml", ROOT / "examples" / "scenes" / "high_degree.yaml"]
DEFAULT_SCENES += sorted((ROOT / "bench" / "scenes").glob("*.yaml"))


def base_copy(base: Path, into: Path) -> Path:
    """base copied into `into`, with an empty stand-in for each tracer source it lacks."""
    folder = into / "runtime_c"
    shutil.copytree(base, folder)
    for name in TRACER_SOURCES:
        if not (folder / name).exists():
            (folder / name).write_text("/* stand-in: the base runtime has no such file */\ntypedef int ig_absent;\n")
    return folder


def built(scene: Path, runtime: Path) -> tuple[CScene, object]:
    picture_diff._use_runtime(runtime)
    sc = load_scene(scene)
    return CScene(sc, build_scene(sc)), sc


SIDES = 3  # base, this, control (the base again)
ORDERS = list(itertools.permutations(range(SIDES)))


def time_scene(scene: Path, runtimes: list[Path], size: argparse.Namespace, runs: int) -> dict[str, list[float]]:
    """Wall and CPU seconds of the render loop per side and round ("wall0", "cpu0" base; "wall1", "cpu1" this;
    "wall2", "cpu2" the control: the base built again)."""
    sides = [built(scene, rt) for rt in (runtimes[0], runtimes[1], runtimes[0])]
    got: dict[str, list[float]] = {f"{k}{i}": [] for k in ("wall", "cpu") for i in range(SIDES)}
    try:
        for cs, sc in sides:  # warm: pages touched, threads' stacks mapped
            _measure(cs, sc, size, 1)
        for r in range(runs):
            for i in ORDERS[r % len(ORDERS)]:
                wall, cpu, _ = _measure(*sides[i], size, 1)
                got[f"wall{i}"].append(wall)
                got[f"cpu{i}"].append(cpu)
    finally:
        for cs, _ in sides:
            cs.close()
    return got


def paired(a: list[float], b: list[float]) -> tuple[float, float, float]:
    """Median and quartiles of the round-by-round ratios a/b."""
    ratios = [x / y for x, y in zip(a, b)]
    med = statistics.median(ratios)
    if len(ratios) < 2:
        return med, med, med
    q1, _, q3 = statistics.quantiles(ratios, n=4)
    return med, q1, q3


def row(name: str, t: dict[str, list[float]]) -> tuple[str, float]:
    m = {k: statistics.median(v) for k, v in t.items()}
    this, control = paired(t["cpu0"], t["cpu1"]), paired(t["cpu0"], t["cpu2"])
    line = (
        f"| {name} | {m['cpu0'] * 1e3:.1f} | {m['cpu1'] * 1e3:.1f} | {this[0]:.2f}× ({this[1]:.2f}–{this[2]:.2f}) | "
        f"{control[0]:.2f}× ({control[1]:.2f}–{control[2]:.2f}) | {m['wall0'] * 1e3:.1f} | {m['wall1'] * 1e3:.1f} |"
    )
    return line, this[0]


def report(args: argparse.Namespace, rows: list[tuple[str, float]], before: str) -> str:
    missed = [f"{line.split('|')[1].strip()} {ratio:.2f}×" for line, ratio in rows if ratio < TARGET]
    verdict = f"**missed** on {', '.join(missed)}" if missed else "**met** on all"
    return "\n".join(
        [
            "# The render loop against main's",
            "",
            f"Written by `bench/tracer_speed.py --base {args.base} --runs {args.runs} --width {args.width} "
            f"--height {args.height}` on {describe()}. Load average before: {before}; after: {load_average()}.",
            "",
            f"{args.width}×{args.height}, 1 sample per pixel, one thread; {args.runs} rounds of the C render loop, "
            "each round running the base, this checkout's and the control (the base again) in turn, the order "
            "turning through all six. Base: the runtime in --base; this: this checkout's. CPU: the process's CPU "
            "time during the loop, medians; paired: the median of the rounds' CPU ratios, with their quartiles in "
            "brackets. The control's ratio differs from 1 only by the noise: a base/this inside its spread is no "
            "change.",
            "",
            "| scene | base CPU ms | this CPU ms | base/this (paired CPU) | base/control (paired CPU) | base wall ms | "
            "this wall ms |",
            "|---|---:|---:|---:|---:|---:|---:|",
            *(line for line, _ in rows),
            "",
            f"Target: this at least {TARGET:.0f}× faster than the base (paired CPU medians) on every scene: {verdict}.",
        ]
    )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--base", type=Path, required=True, help="the runtime_c folder to compare against")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "tracer_speed.md")
    args = ap.parse_args(argv)
    size = argparse.Namespace(width=args.width, height=args.height, spp=1)
    before = load_average()
    rows = []
    with tempfile.TemporaryDirectory() as tmp, picture_diff.runtime_restored():
        runtimes = [base_copy(args.base, Path(tmp)), ROOT / "runtime_c"]
        for scene in args.scenes or DEFAULT_SCENES:
            line, ratio = row(scene.stem, time_scene(scene, runtimes, size, max(1, args.runs)))
            print(line, flush=True)
            rows.append((line, ratio))
    text = report(args, rows, before) + "\n"
    print(text)
    write_results(args.output, text)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
