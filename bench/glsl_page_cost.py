"""The shared page's fragment shader against the GLSL test harness's ray program on the same pixels: frame time,
and how many copies of the shape's tree each holds once every call is inlined.

    .venv/bin/python bench/glsl_page_cost.py [--size 320x240] [--runs 5] [--compare OLD_SURFACE_JS]
                                             [-o bench/results/glsl_page.md]

Each case is a Chmutov surface (degree 16, 20, 24; expanded, drawn from its box's Chebyshev form, and nested)
seen as implgen.measure.glslcases frames it. The page's program is assembled by the page's own surface.js
(IgSurface.fragmentSource, run in a headless Chromium without drawing), with the header for desktop GLSL 4.50;
with --compare, a second page program from another surface.js (an older one: `git show REV:...surface.js`).
The page draws with the share page's look (a sphere clip just outside the box, no shadows, one light); the ray
program answers the same camera's rays (glslcheck's). Every program is drawn once to compile, then the runs are
interleaved (page, old page, ray, page, ...), and the medians and their ratios come from that one run.

The drawing is OpenGL 4.5 through EGL (implgen.measure.glslegl): Mesa's llvmpipe here, a CPU. Its frame times
are indicative only: a CPU runs every branch of a loop body, a GPU's compiler and caches weigh code size
differently. The copies of the tree are the structure a GPU compiler sees on any machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, program, runtime_text, shape_defines
from implgen.measure import glslcases, glslcheck, machine
from implgen.measure.glslcalls import inlined_copies
from implgen.resources import surface_js

ROOT = Path(__file__).resolve().parent.parent

ASSEMBLE = "\nconst d = arguments[0];\nreturn IgSurface.fragmentSource(d.glsl_name, d.shape, d.runtime, d.header);"


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="320x240")
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--compare", type=Path, help="another surface.js: its page program drawn too")
    ap.add_argument("-o", "--out", type=Path, default=ROOT / "bench" / "results" / "glsl_page.md")
    args = ap.parse_args(argv)
    return args, tuple(int(v) for v in args.size.lower().split("x"))


def page_fragment(driver, surface: str, spec) -> str:
    """The page's program for `spec` as that surface.js assembles it, for GLSL 4.50."""
    data = {"glsl_name": glsl_name(spec.name), "shape": glslcheck.glsl_text(spec), "runtime": runtime_text()}
    data["header"] = HEADERS["es"]
    es = driver.execute_script(surface + ASSEMBLE, data)
    assert es.startswith(HEADERS["es"])
    return HEADERS["450"] + es[len(HEADERS["es"]) :]


def page_uniforms(case) -> dict[str, list[float]]:
    """The share page's look at the case's camera (glslcases.view_case: 3.2 radii along VIEW)."""
    box = np.array(case.spec.box(case.params), float)
    centre, radius = 0.5 * (box[:3] + box[3:]), 0.5 * float(np.linalg.norm(box[3:] - box[:3]))
    lights = [-0.6, 0.8, 1.0, 0.0] + [0.0] * 12
    return {
        "ig_page_size": list(case.size),
        "ig_page_eye": list(centre + 3.2 * radius * glslcases.VIEW),
        "ig_page_look": list(centre),
        "ig_page_up": [0.0, 1.0, 0.0],
        "ig_page_fov": [2.0 * float(np.degrees(np.arctan(1.05 / 3.2)))],
        "ig_page_clip": [1],
        "ig_page_clip_size": [1.2 * radius + float(np.linalg.norm(centre))],
        "ig_page_cut": [0],
        "ig_page_outside": [0.95, 0.75, 0.3],
        "ig_page_inside": [0.35, 0.55, 0.95],
        "ig_page_background": [0.12, 0.12, 0.14],
        "ig_page_material": [0.12, 0.75, 0.45, 40.0],
        "ig_page_nlights": [1],
        "ig_page_light": lights,
        "ig_page_light_colour": [1.0, 1.0, 1.0] + [0.0] * 9,
        "ig_page_shadows": [0],
        "ig_page_mark": [1],
        "ig_page_output": [0],
    }


def measure_case(gl, driver, surfaces, spec, size, runs):
    case = glslcases.view_case(spec.name, spec, size)
    frags = {k: page_fragment(driver, text, spec) for k, text in surfaces.items()}
    uniforms = page_uniforms(case)
    draws = {k: (lambda f=f: gl.run(f, size, uniforms, band=size[1])[1]) for k, f in frags.items()}
    draws["ray"] = lambda: glslcheck.run_glsl(gl, case, band=size[1])["ms"]
    first = {k: draw() for k, draw in draws.items()}  # compile (llvmpipe compiles on the first draw)
    times = {k: [] for k in draws}
    for _ in range(runs):
        for k, draw in draws.items():
            times[k].append(draw())
    prefix = glsl_name(spec.name)
    copies = {k: inlined_copies(f, f"{prefix}_raa") for k, f in frags.items()}
    ray = program([glslcheck.glsl_text(spec)], glslcheck.RAY_MAIN, "es", shape_defines(prefix))
    copies["ray"] = inlined_copies(ray, f"{prefix}_raa")
    return {k: statistics.median(v) for k, v in times.items()}, first, copies


def report(rows, keys, size, runs, renderer, load_before, seconds, argv) -> str:
    head = "| surface | " + " | ".join(f"{k}: copies of the tree, first draw (ms), median (ms)" for k in keys)
    head += " | " + " | ".join(f"{k} / ray" for k in keys if k != "ray") + " |"
    lines = [
        "# The page's program against the ray program",
        "",
        f"Written by `.venv/bin/python bench/glsl_page_cost.py{' ' + ' '.join(argv) if argv else ''}` on "
        f"{machine.describe()}, {time.strftime('%Y-%m-%d')}. Load average before: {load_before}, after: "
        f"{machine.load_average()}. Whole run {seconds / 60:.1f} min.",
        "",
        f"OpenGL 4.5 through EGL, renderer `{renderer}`: **llvmpipe runs the shader on the CPU; its frame times "
        "are indicative only** (and this machine's 2 cores were shared with other work). "
        f"{size[0]}×{size[1]} pixels, {runs} interleaved runs after a first draw that compiles. `page`: the "
        "page's program now; `old page`: the surface.js given to --compare; `ray`: the GLSL test harness's "
        "program (the shape's hit once per pixel). Copies of the tree: of the shape's affine form once every "
        "call is inlined.",
        "",
        head,
        "|---|" + "---|" * (len(keys) + len(keys) - 1),
    ]
    for name, med, first, copies in rows:
        cells = [f"{copies[k]}, {first[k]:.0f}, {med[k]:.1f}" for k in keys]
        ratios = [f"{med[k] / med['ray']:.2f}" for k in keys if k != "ray"]
        lines.append(f"| {name} | " + " | ".join(cells) + " | " + " | ".join(ratios) + " |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args, size = parse_args(argv)
    from implgen.measure.glslegl import Egl
    from implgen.measure.webgl import WebGL

    surfaces = {"page": surface_js().read_text(encoding="utf-8")}
    if args.compare:
        surfaces["old page"] = args.compare.read_text(encoding="utf-8")
    load_before, t0 = machine.load_average(), time.perf_counter()
    rows = []
    with WebGL() as browser, Egl() as gl:
        renderer = gl.info()[1]
        for n in (16, 20, 24):
            for nested in (False, True):
                spec = glslcases.chmutov(n, nested)
                med, first, copies = measure_case(gl, browser.driver, surfaces, spec, size, args.runs)
                rows.append((spec.name, med, first, copies))
                print(spec.name, {k: round(v, 1) for k, v in med.items()}, copies, flush=True)
    keys = [*surfaces, "ray"]
    text = report(rows, keys, size, args.runs, renderer, load_before, time.perf_counter() - t0, argv)
    machine.write_results(args.out, text)
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
