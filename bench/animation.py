"""Frames per second of an animation, in this process and on a LocalCluster, at a tiny and at a real size.

    .venv/bin/python bench/animation.py [--scene FILE] [--runs 3] [--workers 2] [--tasks 200]
                                        [-o bench/results/animation.md] [--throughput-only] [--quick]

1. Throughput. The example animation (default examples/scenes/torus_opening.yaml) is rendered to PNG files as
   `implgen render` renders it, at two sizes: 200 frames at 32x24 (the scene's frame count raised to 200;
   its keys hold after the last one), where the cost around each frame's render shows, and 48 frames at
   640x480, where the render is most of it. Each size runs serially in this process (the tracer on all
   cores) and on a LocalCluster of `--workers` processes (`--local-workers`: the tracer on cores / workers
   threads each), the runs of all four interleaved, `--runs` times; medians. Frames per second count the
   batch alone (what the command's `wrote N frames ... in T s` reports); a LocalCluster is started afresh
   for each run, so its workers load the scene library in the timed batch, and its start and close are
   timed on their own. Each cluster run's frames are compared byte for byte with the serial run's.
2. One-off and per-task costs: the scene library generated and compiled into an empty cache; on a warm
   LocalCluster, the round trip per task of `--tasks` tasks that do nothing and of as many chunks of one 1x1
   frame, through the in-order submission the render command uses (what a chunk of frames amortizes); the
   bytes a chunk sends per frame, and the PNG bytes back per frame.

Writes the report (the script, the machine and the load average before and after at its top) and prints
it. --quick is a smoke run (20 and 4 frames, 1 run, 20 tasks) whose figures mean nothing.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import yaml

from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results

ROOT = Path(__file__).resolve().parent.parent
SIZES = ((32, 24, 200), (640, 480, 48))  # width, height, frames
TARGETS = {  # the frames per second each row must reach on 2 cores (serial 32x24, cluster 32x24)
    (32, "serial"): 300.0,
    (32, "cluster"): 200.0,
}


def nothing(*_args) -> bytes:
    return b""


def scene_with_frames(scene: Path, frames: int, folder: Path) -> Path:
    """The scene file with its frame count set, its shape paths made absolute (it is written elsewhere)."""
    data = yaml.safe_load(scene.read_text())
    data["animation"]["frames"] = max(frames, data["animation"]["frames"])
    for obj in data["objects"]:
        if isinstance(obj, dict) and isinstance(obj.get("shape"), str):
            obj["shape"] = str((scene.parent / obj["shape"]).resolve())
    path = folder / f"{scene.stem}_{frames}.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def one_run(frames, todo, opts, workers: int, folder: Path) -> dict:
    """One batch as `implgen render` runs it: {'batch': s, 'start': s, 'close': s, 'files': {name: bytes}}."""
    from implgen.animation import cluster
    from implgen.animation.batch import Runner, render_frames
    from implgen.animation.frameout import plan_output

    out = plan_output(folder / "f_%04d.png", len(todo), todo[-1], opts.width, opts.height)
    if workers == 0:
        report = render_frames(frames, todo, opts, out, Runner())
        return {"batch": report.seconds, "start": 0.0, "close": 0.0, "files": _files(folder)}
    t0 = time.perf_counter()
    with cluster.connect(local_workers=workers) as client:
        start = time.perf_counter() - t0
        report = render_frames(frames, todo, opts, out, Runner(client=client, label="--local-workers"))
        t1 = time.perf_counter()
    close = time.perf_counter() - t1
    return {"batch": report.seconds, "start": start, "close": close, "files": _files(folder)}


def _files(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.glob("f_*.png"))}


def throughput(args, tmp: Path) -> tuple[list[str], list[str], float]:
    """Section 1: the table's rows, the targets' lines, and the mean PNG size of the largest frames."""
    import dataclasses

    from implgen.animation import cluster
    from implgen.animation.frames import FrameOptions, load_frames

    cases = []
    for w, h, n in SIZES:
        n = min(n, args.max_frames)
        frames = load_frames(scene_with_frames(args.scene, n, tmp))
        sc = frames.first
        serial = FrameOptions(width=w, height=h, spp=sc.spp, max_depth=sc.max_depth)
        workers = dataclasses.replace(serial, threads=cluster.local_threads(args.workers))
        cases.append((w, h, frames, range(n), "serial", serial, 0))
        cases.append((w, h, frames, range(n), "cluster", workers, args.workers))
    runs: dict[tuple, list[dict]] = {}
    same = True
    sizes: list[int] = []
    for r in range(args.runs):
        serial_files = {}
        for w, h, frames, todo, how, opts, nw in cases:
            with tempfile.TemporaryDirectory(dir=tmp) as folder:
                got = one_run(frames, todo, opts, nw, Path(folder))
            files = got.pop("files")
            if how == "serial":
                serial_files[w] = files
                sizes += [len(b) for b in files.values()] if w == SIZES[-1][0] else []
            else:
                same = same and files == serial_files[w] and len(files) == len(todo)
            runs.setdefault((w, how), []).append(got)
            fps = len(todo) / got["batch"]
            print(f"run {r + 1}/{args.runs} {w}x{h} {how}: {fps:.1f} frames/s, load {load_average()}", flush=True)
    return _rows(cases, runs, args.workers), _verdicts(cases, runs, same), statistics.mean(sizes)


def _rows(cases, runs, workers: int) -> list[str]:
    rows = []
    for w, h, _frames, todo, how, opts, nw in cases:
        got = runs[(w, how)]
        fps = [len(todo) / g["batch"] for g in got]
        med = statistics.median(g["batch"] for g in got)
        base = statistics.median(g["batch"] for g in runs[(w, "serial")])
        where = f"serial, tracer on {os.cpu_count()} threads" if nw == 0 else f"`--local-workers {workers}`, "
        where += "" if nw == 0 else f"tracer on {opts.threads} thread(s) each"
        start_close = (
            "-"
            if nw == 0
            else (
                f"{statistics.median(g['start'] for g in got):.2f} + {statistics.median(g['close'] for g in got):.2f}"
            )
        )
        rows.append(
            f"| {len(todo)} at {w}x{h} | {where} | {len(todo) / med:.1f} ({', '.join(f'{v:.1f}' for v in fps)}) "
            f"| {med:.3f} | {base / med:.2f} | {start_close} |"
        )
    return rows


def _verdicts(cases, runs, same: bool) -> list[str]:
    out = [
        f"- Frames from the cluster byte for byte those of the serial run, every run: **{'yes' if same else 'NO'}**."
    ]
    for (w, how), target in TARGETS.items():
        n, h = next((len(todo), ch) for cw, ch, _, todo, chow, _, _ in cases if cw == w and chow == how)
        fps = n / statistics.median(g["batch"] for g in runs[(w, how)])
        out.append(
            f"- {n} frames at {w}x{h}, {how}: {fps:.1f} frames/s, target {target:.0f}: "
            f"**{'met' if fps >= target else 'missed'}**."
        )
    big = [w for w, _, _ in SIZES if w != 32][0]
    ratio = statistics.median(g["batch"] for g in runs[(big, "serial")]) / statistics.median(
        g["batch"] for g in runs[(big, "cluster")]
    )
    out.append(
        f"- At {big}x480 the cluster against serial: {ratio:.2f}x, target 0.95x: "
        f"**{'met' if ratio >= 0.95 else 'missed'}**."
    )
    return out


def cold_build(scene) -> float:
    """Seconds to generate and compile a scene's library into an empty cache (what each worker pays once)."""
    from implgen.scene.build import build_scene

    saved = os.environ.get("IMPLGEN_CACHE")
    with tempfile.TemporaryDirectory() as cold:
        os.environ["IMPLGEN_CACHE"] = cold
        try:
            t0 = time.perf_counter()
            build_scene(scene)
            return time.perf_counter() - t0
        finally:
            if saved is None:
                del os.environ["IMPLGEN_CACHE"]
            else:
                os.environ["IMPLGEN_CACHE"] = saved


def task_costs(args) -> dict[str, float]:
    """Section 2: seconds per task through cluster.ordered (3 per worker in flight), tasks that do nothing
    and chunks of one 1x1 frame, on a warm LocalCluster; bytes a chunk sends per frame."""
    import pickle

    from implgen.animation import cluster
    from implgen.animation.chunks import render_chunk
    from implgen.animation.frames import FrameOptions, load_frames

    frames = load_frames(args.scene)
    sc = frames.first
    one_px = FrameOptions(width=1, height=1, spp=1, max_depth=sc.max_depth, threads=1)
    costs = {"cold": cold_build(sc)}
    with cluster.connect(local_workers=args.workers) as client:
        client.wait_for_workers(args.workers)
        warm = ((i, ((sc,), one_px)) for i in range(2 * args.workers))
        for _ in cluster.ordered(client, render_chunk, warm, retries=3, name="warm"):
            pass
        for label, fn, make in (
            ("empty", nothing, lambda i: ()),
            ("1x1", render_chunk, lambda i: ((frames.scene(i % frames.count),), one_px)),
        ):
            t0 = time.perf_counter()
            jobs = ((i, make(i)) for i in range(args.tasks))
            for _ in cluster.ordered(client, fn, jobs, window=3 * args.workers, retries=3, name="bench"):
                pass
            costs[label] = (time.perf_counter() - t0) / args.tasks
    for n in (1, 20):
        chunk = (tuple(frames.scene(f % frames.count) for f in range(n)), one_px, None, False, True)
        costs[f"bytes{n}"] = len(pickle.dumps(chunk)) / n
    return costs


def _cost_rows(args, costs: dict[str, float], png_mean: float) -> list[str]:
    return [
        "| one-off, or per task on a warm LocalCluster | value |",
        "|---|---:|",
        f"| generate + compile the scene library, empty cache (each worker pays it once) | {costs['cold']:.2f} s |",
        f"| scheduler round trip, tasks that do nothing ({args.tasks} tasks, {3 * args.workers} in flight) | "
        f"{costs['empty'] * 1e3:.2f} ms |",
        "| a chunk of one 1x1 frame (scene sent, library kept, tracer set up, PNG back) | "
        f"{costs['1x1'] * 1e3:.2f} ms |",
        f"| bytes sent per frame, chunk of 1 frame / of 20 frames (pickled scenes and options) | "
        f"{costs['bytes1']:,.0f} B / {costs['bytes20']:,.0f} B |",
        f"| bytes back per frame at {SIZES[-1][0]}x{SIZES[-1][1]} (PNG, mean) | {png_mean:,.0f} B |",
        "",
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=ROOT / "examples" / "scenes" / "torus_opening.yaml")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--tasks", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--max-frames", type=int, default=10_000, help="fewer frames per size (a smoke run)")
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "animation.md")
    ap.add_argument("--throughput-only", action="store_true", help="section 1 alone (it runs on older implgen too)")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.max_frames, args.runs, args.tasks = 4, 1, 20

    t_start = time.perf_counter()
    load_before = load_average()
    with tempfile.TemporaryDirectory() as tmp:
        rows, verdicts, png_mean = throughput(args, Path(tmp))
    costs = None if args.throughput_only else task_costs(args)
    lines = [
        "# Frames per second: measured",
        "",
        f"Written by `bench/animation.py` on {machine()}. Load average before: {load_before}; "
        f"after: {load_average()}. Scene `{_rel(args.scene)}` (2 samples per pixel, depth 4); {args.runs} "
        f"interleaved runs of each row; whole script {time.perf_counter() - t_start:.0f} s.",
        "",
        "Frames per second count the batch (the command's `wrote N frames ... in T s`); a LocalCluster is "
        "started afresh for every run, its start and close timed apart.",
        "",
        "| frames | how | frames/s median (runs) | batch s | speed-up | cluster start + close s |",
        "|---|---|---|---:|---:|---|",
        *rows,
        "",
        *verdicts,
        "",
        *([] if costs is None else _cost_rows(args, costs, png_mean)),
    ]
    text = "\n".join(lines)
    write_results(args.output, text)
    print(text)
    print(f"wrote {args.output}")
    return 0


def _rel(path: Path) -> Path:
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


if __name__ == "__main__":
    sys.exit(main())
