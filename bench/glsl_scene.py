"""Every example scene drawn by the GLSL scene tracer on OpenGL 4.5 through EGL (Mesa's llvmpipe here: a CPU)
against `implgen render` at one sample: the pictures compared (implgen.measure.glslscene) and both timed.

    .venv/bin/python bench/glsl_scene.py [--size 160x120] [--runs 3] [-o bench/results/glsl_scene.md]

Per scene: the program's size and compile time (the first draw), the median draw time of --runs draws, the
median `implgen render` time (one sample, one thread) of as many runs, interleaved with the draws; the pixels:
flagged, silhouettes, the object wrong at unflagged pixels off silhouettes, and the colours within 0.02.
llvmpipe is not a GPU: its times say nothing of a GPU's frame rate (the issue's targets, glassware at 1920x1080
at 30 frames/s, need one), only how the scenes compare with each other and with the C tracer on this CPU.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

from implgen.measure import glslscene, machine
from implgen.measure.glslegl import Egl
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.render import render
from implgen.share.scenegpu import camera_uniforms, decode, scene_fragment

ROOT = Path(__file__).resolve().parent.parent
SCENES = sorted((ROOT / "examples" / "scenes").glob("*.yaml"))


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("-o", "--out", type=Path, default=ROOT / "bench" / "results" / "glsl_scene.md")
    args = ap.parse_args(argv)
    return args, tuple(int(v) for v in args.size.lower().split("x"))


def measure(gl, path: Path, size, runs: int) -> dict:
    scene = load_scene(path)
    frag = scene_fragment(scene, "450")
    uniforms = camera_uniforms(scene, size, output=1)
    built = build_scene(scene)
    t0 = time.perf_counter()
    out, _ = gl.run(frag, size, uniforms, band=size[1])
    first = time.perf_counter() - t0
    draws, renders = [], []
    for _ in range(runs):
        draws.append(gl.run(frag, size, uniforms, band=size[1])[1] / 1000.0)
        t0 = time.perf_counter()
        render(scene, width=size[0], height=size[1], spp=1, threads=1, built=built)
        renders.append(time.perf_counter() - t0)
    g_rgb, g_obj, g_flag = decode(out)
    c_rgb, c_obj = glslscene.c_reference(scene, size)
    r = glslscene.compare(c_rgb, c_obj, g_rgb, g_obj, g_flag, 0.02)
    return {
        "name": path.stem,
        "chars": len(frag),
        "first": first,
        "draw": statistics.median(draws),
        "render": statistics.median(renders),
        "r": r,
    }


def report(rows, size, runs, renderer, load_before, seconds, argv) -> str:
    lines = [
        "# The GLSL scene tracer against `implgen render`",
        "",
        f"Written by `.venv/bin/python bench/glsl_scene.py{' ' + ' '.join(argv) if argv else ''}` on "
        f"{machine.describe()}, {time.strftime('%Y-%m-%d')}. Load average before: {load_before}, after: "
        f"{machine.load_average()}. Whole run {seconds / 60:.1f} min.",
        "",
        f"OpenGL 4.5 through EGL, renderer `{renderer}`: **llvmpipe runs the shader on the CPU; its times are "
        "indicative only, and say nothing of a GPU's frame rate** (this machine's 2 cores were shared with other "
        f"work). {size[0]}×{size[1]} pixels, one ray a pixel; medians of {runs} interleaved runs. `implgen "
        "render`: one sample, one thread, the scene's library built beforehand. Compared: the unflagged pixels "
        "off silhouettes (object), and of those off the C picture's own edges (colour within 0.02).",
        "",
        "| scene | program (chars) | first draw, compile included (s) | draw (s) | `implgen render` (s) | draw / "
        "render | flagged | silhouette | object compared / wrong | colour compared / off by > 0.02 | largest "
        "difference |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for row in rows:
        r = row["r"]
        lines.append(
            f"| {row['name']} | {row['chars']} | {row['first']:.1f} | {row['draw']:.2f} | {row['render']:.2f} "
            f"| {row['draw'] / row['render']:.1f} | {r.flagged} | {r.silhouette} | {r.compared} / {r.object_wrong} "
            f"| {r.colour_compared} / {r.colour_wrong} | {r.colour_max:.3f} |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args, size = parse_args(argv)
    load_before, t0 = machine.load_average(), time.perf_counter()
    rows = []
    with Egl() as gl:
        renderer = gl.info()[1]
        for path in SCENES:
            row = measure(gl, path, size, args.runs)
            rows.append(row)
            print(row["name"], f"draw {row['draw']:.2f} s render {row['render']:.2f} s", row["r"], flush=True)
    text = report(rows, size, args.runs, renderer, load_before, time.perf_counter() - t0, argv)
    machine.write_results(args.out, text)
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
