"""`implgen bench render [SCENE.yaml ...] [--threads 1,2] [--runs 5] [--width 800 --height 600 --spp 1]
[--fold-compare] [-o bench/results/render.md]`

Renders each scene (default: bench/scenes/*.yaml and examples/scenes/*.yaml under the current folder) on each
thread count, interleaved: round by round, every thread count once per scene, in alternating order, so a
change in the machine's load hits every count alike. Reports the medians of --runs rounds: wall time of the
C render loop (rt_render_run alone, as POV-Ray's "Trace Time" times its own), millions of rays per second by
kind (primary, shadow, secondary), and how the first thread count scales to the last:

  speed-up = median wall time on the first count / median wall time on the last;
  work     = median CPU time of the process during the render on the last count / on the first: above 1
             when the threads get in each other's way (shared cache lines, memory, a busy sibling core);
  busy     = CPU time / wall time on the last count: the cores the render kept busy (the thread count when
             nothing waits and nothing else runs).

The target checked is a speed-up of at least TARGET_SPEEDUP from 1 to 2 threads on every scene whose
1-thread render takes over MIN_SECONDS. The library is built before timing. With --fold-compare it also
renders every scene with the shape params folded into the generated code (1 thread, interleaved). The table
is printed and written, with the machine and the load average, to the output file.
"""

from __future__ import annotations

import os
import resource
import statistics
from collections.abc import Sequence
from pathlib import Path

from implgen.args import ArgumentParser
from implgen.errors import UserError, printable
from implgen.measure.machine import cpu_model, load_average
from implgen.outputs import atomic_write, check_output_file
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.model import Scene
from implgen.scene.render import MAX_THREADS, image_options
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene

TARGET_SPEEDUP = 1.85
MIN_SECONDS = 0.1


def _default_scenes() -> list[Path]:
    here = Path.cwd()
    return sorted((here / "bench" / "scenes").glob("*.yaml")) + sorted((here / "examples" / "scenes").glob("*.yaml"))


def _cpu_seconds() -> float:
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def _thread_counts(text: str) -> list[int]:
    try:
        counts = [int(v) for v in text.split(",")]
    except ValueError:
        raise UserError("--threads", f"{text!r} is not a list of whole numbers such as 1,2") from None
    if not counts or any(not 1 <= c <= MAX_THREADS for c in counts):
        raise UserError("--threads", f"thread counts must be 1 to {MAX_THREADS}")
    return counts


def _measure(cs: CScene, sc: Scene, args, threads: int) -> tuple[float, float, dict[str, float]]:
    """(wall seconds, CPU seconds of the process, rays by kind) of one run of the C render loop, timed around
    rt_render_run alone: the render context and its image are made before (RenderJob's entry), and render()'s
    progress polling and Python thread are not there."""
    with RenderJob(cs, args.width, args.height, args.spp, sc.max_depth, threads) as job:
        c0 = _cpu_seconds()
        img = job.run()
        cpu = _cpu_seconds() - c0
        if img is None:
            raise RuntimeError("render failed (cancelled)")
        return job.seconds, cpu, job.stats().rays


def _prepared(sc: Scene, fold: bool = False) -> tuple[CScene, Scene]:
    return CScene(sc, build_scene(sc, fold=fold)), sc


class _Report(list):
    """Lines of the results file, each printed as it comes."""

    def add(self, *lines: str) -> None:
        for line in lines:
            print(line, flush=True)
            self.append(line)


def _scaling(scenes: dict[Path, Scene], args, counts: list[int], out: _Report) -> None:
    first, last = counts[0], counts[-1]
    out.add(
        f"| scene | {' | '.join(f'{c} thr. (s)' for c in counts)} | speed-up {first}→{last} | work | busy | "
        f"primary Mrays/s | shadow Mrays/s | secondary Mrays/s | all Mrays/s ({first} thr.) |",
        "|---|" + "---:|" * (len(counts) + 7),
    )
    verdicts = []
    for path, scene in scenes.items():
        cs, sc = _prepared(scene)  # compiled before timing
        _measure(cs, sc, args, last)  # warm: pages touched, the threads' stacks mapped once
        wall: dict[int, list[float]] = {c: [] for c in counts}
        cpu: dict[int, list[float]] = {c: [] for c in counts}
        rays: dict[str, float] = {}
        for k in range(max(1, args.runs)):
            for c in counts if k % 2 == 0 else counts[::-1]:
                w, u, rays = _measure(cs, sc, args, c)
                wall[c].append(w)
                cpu[c].append(u)
        med = {c: statistics.median(wall[c]) for c in counts}
        cmed = {c: statistics.median(cpu[c]) for c in counts}
        speedup = med[first] / med[last]
        work = cmed[last] / cmed[first]
        busy = cmed[last] / med[last]
        t = med[first]
        kinds = " | ".join(f"{rays.get(k, 0.0) / t / 1e6:.2f}" for k in ("primary", "shadow", "secondary"))
        out.add(
            f"| {path.stem} | {' | '.join(f'{med[c]:.3f}' for c in counts)} | {speedup:.2f}× | {work:.2f} | "
            f"{busy:.2f} | {kinds} | {sum(rays.values()) / t / 1e6:.2f} |"
        )
        if (first, last) == (1, 2) and med[1] > MIN_SECONDS:
            verdicts.append((path.stem, speedup))
    if verdicts:
        missed = [f"{n} {s:.2f}×" for n, s in verdicts if s < TARGET_SPEEDUP]
        out.add(
            "",
            f"Target: at least {TARGET_SPEEDUP}× from 1 to 2 threads on every scene whose 1-thread render takes "
            f"over {MIN_SECONDS} s ({len(verdicts)} scenes): "
            + (f"**missed** on {', '.join(missed)}." if missed else "**met** on all."),
        )


def _fold(scenes: dict[Path, Scene], args, out: _Report) -> None:
    rows = []
    for path, scene in scenes.items():
        variants = {fold: _prepared(scene, fold) for fold in (False, True)}
        times: dict[bool, list[float]] = {False: [], True: []}
        for k in range(max(1, args.runs)):
            for fold in (False, True) if k % 2 == 0 else (True, False):
                times[fold].append(_measure(*variants[fold], args, 1)[0])
        rows.append((path.stem, statistics.median(times[False]), statistics.median(times[True])))
    out.add("", "| scene | params at run time (s) | params folded (s) | change |", "|---|---:|---:|---:|")
    out.add(*(f"| {n} | {a:.3f} | {b:.3f} | {100 * (b - a) / a:+.1f}% |" for n, a, b in rows))


EXAMPLES = (
    ("the table of bench/results/render.md, from the repository's root", "implgen bench render --fold-compare"),
    (
        "one scene on 1, 2 and 4 threads, 3 rounds",
        "implgen bench render bench/scenes/heart.yaml --threads 1,2,4 --runs 3 -o out/render.md",
    ),
)


def main(argv: Sequence[str]) -> int:
    ap = ArgumentParser(
        prog="implgen bench render",
        description="Render speed by ray kind, and how it scales from the first thread count to the last.",
        examples=EXAMPLES,
    )
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--threads", default="1,2", help="thread counts, interleaved (default 1,2)")
    ap.add_argument("--runs", type=int, default=5, help="rounds; medians are reported (default 5)")
    ap.add_argument("--fold-compare", action="store_true")
    ap.add_argument("-o", "--output", type=Path, default=Path("bench/results/render.md"))
    args = ap.parse_args(list(argv))
    counts = _thread_counts(args.threads)
    check_output_file(args.output, "-o", (".md",))
    paths = args.scenes or _default_scenes()
    if not paths:
        raise UserError("bench render", "no scenes given and none in ./bench/scenes or ./examples/scenes")
    scenes = {path: load_scene(path) for path in paths}  # a bad scene: one line, before the report's first line
    for sc in scenes.values():  # and an option out of range
        image_options(sc, width=args.width, height=args.height, spp=args.spp)
    out = _Report()
    out.add(
        "# Render speed and thread scaling",
        "",
        f"Written by `implgen bench render --threads {args.threads} --runs {args.runs} --width {args.width} "
        f"--height {args.height} --spp {args.spp}{' --fold-compare' if args.fold_compare else ''}` on {cpu_model()}, "
        f"{os.cpu_count()} cores. Load average before: {load_average()}.",
        "",
        f"{args.width}×{args.height}, {args.spp} sample(s) per pixel; median of {args.runs} interleaved rounds. "
        "Speed-up: wall time on the first thread count over the last; work: CPU time on the last over the first "
        "(1.00: the threads do not slow each other down); busy: CPU time over wall time on the last.",
        "",
    )
    _scaling(scenes, args, counts, out)
    if args.fold_compare:
        _fold(scenes, args, out)
    out.add("", f"Load average after: {load_average()}.")
    data = ("\n".join(out) + "\n").encode()
    atomic_write(args.output, lambda fh: fh.write(data))
    print(f"wrote {printable(str(args.output))}")
    return 0
