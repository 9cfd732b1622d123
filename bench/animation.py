"""Frames on Dask against frames in one process, the scheduler's cost per task, and the bytes each frame moves.

    .venv/bin/python bench/animation.py [--scene FILE] [--frames 48] [--width 640 --height 480] [--runs 3]
                                        [--tasks 200] [-o bench/results/animation.md] [--quick]

1. The animation (default examples/scenes/torus_opening.yaml, 48 frames at 640x480) rendered to PNG files
   serially in this process (the tracer on all cores, one frame after the other), and on a LocalCluster of
   2 worker processes (`--local-workers 2`: one frame per worker, the tracer on 1 core each), interleaved,
   `--runs` times each; medians and their ratio. The cluster is started, and each worker has built the
   scene library, before the timed runs; their one-off costs are measured on their own.
2. The cost per task of the scheduler: `--tasks` tasks that do nothing, and as many 1x1 frames of the same
   scene, through the same in-order submission the render command uses.
3. Bytes per frame: what a task carries to the worker (the pickled frame scene and options) and what comes
   back (the PNG).

Writes the report (which names this script and the machine at its top) and prints it. --quick is a smoke run
(6 frames at 64x48, 1 run, 20 tasks) whose figures mean nothing.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import pickle
import statistics
import sys
import tempfile
import time
from pathlib import Path

from implgen.measure.machine import describe as machine
from implgen.measure.machine import write_results

ROOT = Path(__file__).resolve().parent.parent


def nothing(*_args) -> bytes:
    return b""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=ROOT / "examples" / "scenes" / "torus_opening.yaml")
    ap.add_argument("--frames", type=int, default=48)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--tasks", type=int, default=200)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "animation.md")
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    if args.quick:
        args.frames, args.width, args.height, args.runs, args.tasks = 6, 64, 48, 1, 20

    from implgen.animation import cluster
    from implgen.animation.batch import Runner, render_frames
    from implgen.animation.frameout import plan_output
    from implgen.animation.frames import FrameOptions, load_frames, render_frame_png
    from implgen.scene.build import build_scene

    t_start = time.perf_counter()
    frames = load_frames(args.scene)
    todo = range(min(args.frames, frames.count))
    sc = frames.first
    serial_opts = FrameOptions(width=args.width, height=args.height, spp=sc.spp, max_depth=sc.max_depth)
    worker_opts = dataclasses.replace(serial_opts, threads=cluster.local_threads(args.workers))
    one_px = FrameOptions(width=1, height=1, spp=1, max_depth=sc.max_depth, threads=1)

    # one-off costs: generating and compiling the scene library from an empty cache, and starting a cluster
    with tempfile.TemporaryDirectory() as cold:
        saved = os.environ.get("IMPLGEN_CACHE")
        os.environ["IMPLGEN_CACHE"] = cold
        t0 = time.perf_counter()
        build_scene(sc)
        cold_build = time.perf_counter() - t0
        if saved is None:
            del os.environ["IMPLGEN_CACHE"]
        else:
            os.environ["IMPLGEN_CACHE"] = saved
    build_scene(sc)  # the cache the workers share on this machine is warm from here on

    serial_times: list[float] = []
    dask_times: list[float] = []
    png_bytes: list[int] = []
    t0 = time.perf_counter()
    with cluster.connect(local_workers=args.workers) as client:
        client.wait_for_workers(args.workers)
        cluster_start = time.perf_counter() - t0
        t0 = time.perf_counter()
        client.gather(client.map(render_frame_png, [sc] * args.workers, [one_px] * args.workers, pure=False))
        first_tasks = time.perf_counter() - t0  # each worker imports the tracer and loads the library
        dask = Runner(client=client)
        serial = Runner()
        for run in range(args.runs):
            for name, runner, opts, times in (
                ("serial", serial, serial_opts, serial_times),
                ("dask", dask, worker_opts, dask_times),
            ):
                with tempfile.TemporaryDirectory() as tmp:
                    out = plan_output(Path(tmp) / "f_%04d.png", len(todo), todo[-1], args.width, args.height)
                    report = render_frames(frames, todo, opts, out, runner)
                    times.append(report.seconds)
                    if name == "dask":
                        png_bytes.append(report.bytes_moved)
                print(f"run {run + 1}/{args.runs} {name}: {times[-1]:.2f} s", flush=True)

        # scheduler cost per task: tasks that do nothing, and 1x1 frames, through the same submission
        per_task = {}
        for label, fn, opts in (("empty task", nothing, None), ("1x1 frame", render_frame_png, one_px)):
            t0 = time.perf_counter()
            jobs = ((i, (frames.scene(i % frames.count), opts)) for i in range(args.tasks))
            for _ in cluster.ordered(client, fn, jobs, window=3 * args.workers, retries=3, name="bench"):
                pass
            per_task[label] = (time.perf_counter() - t0) / args.tasks
    sent = statistics.median(len(pickle.dumps((frames.scene(f), worker_opts))) for f in todo)

    s_med, d_med = statistics.median(serial_times), statistics.median(dask_times)
    n = len(todo)
    lines = [
        "# Frames on Dask: measured",
        "",
        f"Written by `bench/animation.py` on {machine()}.",
        f"Scene `{args.scene.relative_to(ROOT) if args.scene.is_relative_to(ROOT) else args.scene}`, "
        f"{n} frames at {args.width}x{args.height}, {sc.spp} samples per pixel; {args.runs} interleaved runs "
        f"of each; whole script {time.perf_counter() - t_start:.0f} s.",
        "",
        "| how | median s (runs) | s per frame | speed-up |",
        "|---|---|---:|---:|",
        f"| serial, this process, tracer on {os.cpu_count()} threads | {s_med:.2f} "
        f"({', '.join(f'{t:.2f}' for t in serial_times)}) | {s_med / n:.3f} | 1.00 |",
        f"| `--local-workers {args.workers}`, tracer on {worker_opts.threads} thread(s) per frame | {d_med:.2f} "
        f"({', '.join(f'{t:.2f}' for t in dask_times)}) | {d_med / n:.3f} | {s_med / d_med:.2f} |",
        "",
        "| one-off or per-task cost | value |",
        "|---|---:|",
        f"| generate + compile the scene library, empty cache | {cold_build:.2f} s |",
        f"| start a LocalCluster of {args.workers} processes | {cluster_start:.2f} s |",
        f"| first task on each worker (imports, library load) | {first_tasks:.2f} s |",
        f"| scheduler round trip per task, empty task ({args.tasks} tasks, {3 * args.workers} in flight) | "
        f"{per_task['empty task'] * 1e3:.2f} ms |",
        f"| per task, 1x1 frame (scene sent, library checked, tracer set up, PNG back) | "
        f"{per_task['1x1 frame'] * 1e3:.2f} ms |",
        f"| bytes to the worker per frame (pickled scene + options, median) | {sent:,.0f} B |",
        f"| bytes back per frame (PNG, mean) | {statistics.mean(png_bytes) / n:,.0f} B |",
        "",
    ]
    text = "\n".join(lines)
    write_results(args.output, text)
    print(text)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
