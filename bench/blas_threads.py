"""What NumPy's OpenBLAS thread pool costs `implgen render`'s render loop.

    .venv/bin/python bench/blas_threads.py [--scene SCENE] [--runs 7] [-o bench/results/blas_threads.md]

OpenBLAS starts a thread per core when NumPy is imported, and each spins for a while on the cores the render's
threads need. `implgen` sets OPENBLAS_NUM_THREADS=1 unless the user has set it (implgen.cli), so setting it
to the core count brings the pool back. This script renders the scene at 800x600 on 1 thread and on all cores,
with the pool (OPENBLAS_NUM_THREADS=<cores>) and without it (=1), interleaved run by run, and reports the
medians of the render loop's own time as `implgen render` prints it (default scene: bench/scenes/heart.yaml).
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results

ROOT = Path(__file__).resolve().parents[1]


def render_seconds(scene: Path, out: Path, threads: int, blas: int) -> float:
    script = Path(sys.executable).parent / "implgen"
    cmd = [str(script), "render", str(scene), "-o", str(out), "--width", "800", "--height", "600", "--spp", "1"]
    env = {**os.environ, "OPENBLAS_NUM_THREADS": str(blas), "TQDM_DISABLE": "1"}
    p = subprocess.run([*cmd, "--threads", str(threads)], capture_output=True, text=True, env=env, check=False)
    m = re.search(r"([\d.]+) s on \d+ thread", p.stdout + p.stderr)
    if p.returncode != 0 or not m:
        raise SystemExit(f"bench/blas_threads.py: implgen render failed:\n{p.stderr[-2000:]}")
    return float(m.group(1))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", type=Path, default=ROOT / "bench" / "scenes" / "heart.yaml")
    ap.add_argument("--runs", type=int, default=7)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "blas_threads.md")
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    before = load_average()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "frame.png"
        render_seconds(args.scene, out, cores, 1)  # warm-up: builds and caches the scene's library
        for threads in sorted({1, cores}):
            pool, alone = [], []
            for _ in range(args.runs):  # interleaved: both see the same machine
                pool.append(render_seconds(args.scene, out, threads, cores))
                alone.append(render_seconds(args.scene, out, threads, 1))
            rows.append((threads, pool, alone))
    lines = [
        "# NumPy's BLAS threads beside the render loop",
        "",
        f"Written by `bench/blas_threads.py --runs {args.runs}` on {machine()}. Scene `{args.scene.name}`, "
        f"800x600, 1 sample; the render loop's time as `implgen render` prints it; medians of {args.runs} "
        f"interleaved runs. Load average before: {before}; after: {load_average()}.",
        "",
        f"| render threads | with the pool (OPENBLAS_NUM_THREADS={cores}) s | without (=1, implgen's default) s "
        "| ratio | range with | range without |",
        "|---:|---:|---:|---:|---|---|",
    ]
    for threads, pool, alone in rows:
        a, b = statistics.median(pool), statistics.median(alone)
        lines.append(
            f"| {threads} | {a:.3f} | {b:.3f} | {a / b:.2f} | {min(pool):.3f}-{max(pool):.3f} "
            f"| {min(alone):.3f}-{max(alone):.3f} |"
        )
    text = "\n".join(lines) + "\n"
    print(text)
    write_results(args.output, text)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
