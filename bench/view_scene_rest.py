"""A scene file at rest in the viewer: the server's full frame against what a GPU-drawn scene asks of the server
instead, the pixels its GLSL flags traced in double (view/fix.py).

    nice .venv/bin/python bench/view_scene_rest.py [--size 320x240] [--runs 3] [-o bench/results/view.md]

Per example scene, the viewer's view of it at --size (Document.for_scene: the file's camera and lights): the
scene's GLSL program (the scene tracer, as the page draws it) is drawn once on OpenGL 4.5 through EGL
(implgen.measure.glslegl: Mesa's llvmpipe on this machine, a GPU's driver where there is one) for its flags,
its draw timed (*GLSL frame*; the page draws it twice, the picture and the status pass); then, interleaved
over --runs: *server frame*, the C render at 4 samples a pixel on 2 threads (the picture the viewer's
refinement ladder ends with; the ladder's earlier passes add to it); *fix*, view/fix.py tracing the flagged
pixels at one sample on 2 threads (what the server does for a GPU-drawn scene at rest). Reported: medians,
the flagged pixels, and the ratio server frame / fix -- on a real GPU the GLSL frame is milliseconds and the
page's rest is about the fix; on llvmpipe (a CPU) the GLSL frame is seconds and the column says so: it is
indicative only. The section is written between markers into the results file (--output).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from implgen.measure import machine
from implgen.measure.glslegl import Egl
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.render import render
from implgen.share.scenegpu import camera_uniforms, decode, scene_fragment
from implgen.view.document import Document
from implgen.view.fix import fix_pixels

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "examples" / "scenes").glob("*.yaml"))
BEGIN, END = "<!-- bench/view_scene_rest.py: begin -->", "<!-- bench/view_scene_rest.py: end -->"


def measure(gl, path: Path, size: tuple[int, int], runs: int) -> dict:
    sc = Document.for_scene(load_scene(path)).scene(size[0], size[1], 4)
    lib = build_scene(sc)
    frag = scene_fragment(sc, "450")
    uniforms = camera_uniforms(sc, size, output=1)
    out, draw_ms = gl.run(frag, size, uniforms, band=size[1])  # the flags; one draw timed (compiled before)
    _, _, flag = decode(out)
    flagged = [int(i) for i in np.flatnonzero(flag.reshape(-1))]
    frames, fixes = [], []
    for _ in range(runs):
        t0 = time.perf_counter()
        render(sc, spp=4, threads=2, built=lib)
        frames.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        if flagged:
            fix_pixels(sc, lib, flagged, threads=2)
        fixes.append(time.perf_counter() - t0)
    return {
        "name": path.stem,
        "frame": statistics.median(frames),
        "fix": statistics.median(fixes),
        "draw": draw_ms / 1000.0,
        "flagged": len(flagged),
    }


def report(rows, args, size, renderer: str, load_before: str) -> str:
    w, h = size
    lines = [
        BEGIN,
        "## A scene at rest: the server's frame, or only the pixels the GPU's GLSL flags",
        "",
        f"Written by `bench/view_scene_rest.py --size {args.size} --runs {args.runs}` on {machine.describe()}, "
        f"{time.strftime('%Y-%m-%d')}; load average before: {load_before}, after: {machine.load_average()}. "
        f"The GLSL ran on `{renderer}`: **llvmpipe is a CPU, so the GLSL frame column is indicative only**; no "
        "GPU was available for this run (on one the GLSL frame is milliseconds, and a resting scene costs the "
        "page about the fix). The machine's 2 cores were shared with other work.",
        "",
        f"{w}×{h} pixels, the viewer's view of each example scene. *server frame*: the C render at 4 samples a "
        "pixel, 2 threads (what the viewer's refinement ends with; its earlier passes add to it); *fix*: the "
        "flagged pixels traced in double at one sample, 2 threads (`view/fix.py`: what the server does for a "
        "GPU-drawn scene at rest; none flagged: nothing asked); *GLSL frame*: one draw of the scene's program, "
        "once (the page draws it twice, the picture and the status). The server frame and the fix: medians of "
        f"{args.runs} interleaved runs.",
        "",
        "| scene | server frame (s) | flagged pixels | fix (s) | server frame / fix | GLSL frame (s, llvmpipe) |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        ratio = f"{r['frame'] / r['fix']:.0f}" if r["flagged"] else "no fix"
        pc = 100 * r["flagged"] / (w * h)
        lines.append(
            f"| {r['name']} | {r['frame']:.3f} | {r['flagged']} ({pc:.2f} %) | {r['fix']:.4f} | {ratio} "
            f"| {r['draw']:.2f} |"
        )
    return "\n".join([*lines, "", END])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "view.md")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    load_before = machine.load_average()
    rows = []
    with Egl() as gl:
        renderer = gl.info()[1]
        for path in SCENES:
            rows.append(measure(gl, path, size, args.runs))
            print(rows[-1], file=sys.stderr, flush=True)
    section = report(rows, args, size, renderer, load_before)
    print(section)
    machine.write_section(args.output, BEGIN, END, section)
    return 0


if __name__ == "__main__":
    sys.exit(main())
