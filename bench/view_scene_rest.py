"""A scene file at rest in the viewer: the server's full frame against the GPU's picture with the pixels it flags
fixed by the server, in headless Chromium.

    nice .venv/bin/python bench/view_scene_rest.py [--size 320x240] [--rounds 3] [-o bench/results/view.md]

For each example scene (SCENES) one `implgen view SCENE.yaml --no-browser --port 0` is started and its page
opened at --size device pixels with "GPU preview" ticked (off by default on a software renderer). Each round
takes every scene in turn, and for each both ways, interleaved: *server*, the preview unticked, the page's
refined frame at rest (the server's ladder up to its 4-sample frame: `kind` full); *GPU + fixed*, the
preview ticked, the GPU's full frame at rest, its status pass, and the flagged pixels traced by the server in
double (view/fix.py) and put in (`data-fix-seq`). Each is timed in the page from a wheel event (a small zoom,
in and out in turn) to that picture: both include the page's 180 ms rest before it asks for the refined view.
Reported: medians over the rounds, their ratio, and how many pixels the server traced for the GPU's picture.

SwiftShader is a CPU emulation of a GPU, sharing the machine's cores with the server: the GPU's part of the
second figure is what a very slow GPU costs, so these figures are indicative only; on a real GPU that part is
milliseconds. The section is written between markers into the results file (--output).
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from implgen.measure.machine import describe as machine
from implgen.measure.machine import write_results
from implgen.measure.webgl import FLAGS

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("glassware", "csg_trio", "high_degree", "glass_sphere")
BEGIN, END = "<!-- bench/view_scene_rest.py: begin -->", "<!-- bench/view_scene_rest.py: end -->"
STATE = (
    "const v = document.getElementById('view').dataset;"
    "return {seq: +(v.seq ?? -1), kind: v.kind || '', shown: v.shown || '', path: v.path,"
    " fixSeq: +(v.fixSeq ?? -1), fixed: +(v.fixed ?? -1)};"
)
WATCH = (
    "const v = document.getElementById('view'); window.igRest = null;"
    "if (window.igWatch) window.igWatch.disconnect();"
    "window.igWatch = new MutationObserver(() => { const s = v.dataset;"
    "  if (window.igRest && window.igRest.t === null && ((arguments[0] && +(s.fixSeq ?? -1) > window.igRest.fix)"
    "      || (!arguments[0] && s.kind === 'full' && +s.seq > window.igRest.seq))) window.igRest.t = performance.now();"
    "});"
    "window.igWatch.observe(v, {attributes: true, attributeFilter: ['data-fix-seq', 'data-kind', 'data-seq']});"
)


def wait(d, what, timeout: float = 600.0):
    deadline = time.monotonic() + timeout
    while not (got := what(d)):
        if time.monotonic() > deadline:
            raise RuntimeError("the page did not get there")
        time.sleep(0.02)
    return got


def open_scene(d, url: str, size: tuple[int, int]) -> None:
    """The page at `size`, its refined frame shown, then the GPU preview ticked and its rest fixed."""
    d.get(url)
    wait(d, lambda d: d.execute_script(STATE)["kind"] != "")  # a first frame: the page has its hello
    d.execute_script(
        "const s = document.getElementById('stage'); s.style.flex = 'none';"
        "s.style.width = arguments[0] + 'px'; s.style.height = arguments[1] + 'px';",
        *size,
    )
    shape = "const c = document.getElementById('view'); return [c.width, c.height]"
    wait(d, lambda d: d.execute_script(shape) == list(size))
    wait(d, lambda d: d.execute_script(STATE)["kind"] == "full")
    set_gpu(d, True)


def set_gpu(d, on: bool) -> None:
    if d.execute_script("return document.getElementById('gpu').checked") != on:
        d.find_element("id", "gpu").click()
    if on:
        wait(d, lambda d: (s := d.execute_script(STATE))["path"] == "gpu" and s["shown"] == "fixed")
    else:
        wait(d, lambda d: d.execute_script(STATE)["path"] == "server")


def rest(d, gpu: bool, sign: int) -> tuple[float, int]:
    """Milliseconds from a wheel event to the rest's picture, and the pixels fixed (-1: the server's frame)."""
    set_gpu(d, gpu)
    s = d.execute_script(STATE)
    d.execute_script(WATCH, gpu)
    d.execute_script(
        "window.igRest = {t0: performance.now(), t: null, seq: arguments[0], fix: arguments[1]};"
        "document.getElementById('view').dispatchEvent(new WheelEvent('wheel', {deltaY: arguments[2]}));",
        s["seq"],
        s["fixSeq"],
        40 * sign,
    )
    wait(d, lambda d: d.execute_script("return window.igRest.t !== null"))
    ms = d.execute_script("return window.igRest.t - window.igRest.t0")
    return ms, d.execute_script(STATE)["fixed"] if gpu else -1


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="320x240", help="the picture, in device pixels (default 320x240)")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "view.md")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    load_before = os.getloadavg()[0]
    servers, urls = [], {}
    for name in SCENES:
        cmd = [sys.executable, "-m", "implgen.cli", "view", str(ROOT / "examples" / "scenes" / f"{name}.yaml")]
        servers.append(subprocess.Popen([*cmd, "--no-browser", "--port", "0"], stdout=subprocess.PIPE, text=True))
        urls[name] = "http://" + servers[-1].stdout.readline().split("http://", 1)[1].split()[0]
    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in (*FLAGS, "--force-device-scale-factor=1", "--window-size=1100,700"):
        opts.add_argument(arg)
    drivers = {}
    results = {name: {"server": [], "gpu": [], "fixed": []} for name in SCENES}
    try:
        for name in SCENES:  # a browser a scene: each page keeps its view and its compiled program
            drivers[name] = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
            drivers[name].set_script_timeout(600)
            open_scene(drivers[name], urls[name], size)
            print(f"{name}: open", file=sys.stderr, flush=True)
        renderer = drivers[SCENES[0]].execute_script("return implgenGpu.renderer().info()[1]")
        for r in range(args.rounds):
            for name in SCENES:
                sign = 1 if r % 2 == 0 else -1
                ms_server, _ = rest(drivers[name], False, sign)
                ms_gpu, fixed = rest(drivers[name], True, -sign)
                results[name]["server"].append(ms_server)
                results[name]["gpu"].append(ms_gpu)
                results[name]["fixed"].append(fixed)
                print(
                    f"round {r + 1}/{args.rounds} {name}: server {ms_server:.0f} ms, GPU + {fixed} fixed "
                    f"{ms_gpu:.0f} ms",
                    file=sys.stderr,
                    flush=True,
                )
    finally:
        for d in drivers.values():
            d.quit()
        for s in servers:
            s.terminate()
            s.wait(30)
    load_after = os.getloadavg()[0]
    section = report(args, size, results, renderer, load_before, load_after)
    print(section)
    old = args.output.read_text(encoding="utf-8") if args.output.exists() else ""
    if BEGIN in old and END in old:
        text = old[: old.index(BEGIN)] + section + old[old.index(END) + len(END) :]
    else:
        text = old.rstrip("\n") + "\n\n" + section + "\n"
    write_results(args.output, text)
    return 0


def report(args, size, results, renderer: str, load_before: float, load_after: float) -> str:
    w, h = size
    lines = [
        BEGIN,
        "## A scene at rest: the server's frame against the GPU's with its flagged pixels fixed (SwiftShader)",
        "",
        f"Written by `bench/view_scene_rest.py --size {args.size} --rounds {args.rounds}` on {machine()}; load "
        f"average (1 min) {load_before:.2f} before, {load_after:.2f} after. Headless Chromium, WebGL renderer "
        f"`{renderer}`: **SwiftShader is a CPU emulation of a GPU** sharing these cores with the server, so the "
        "GPU's part of the second column is what a very slow GPU costs: **indicative only**; on a real GPU it is "
        "milliseconds. No real GPU was available for this run.",
        "",
        f"The picture is {w}×{h}. *server*: a wheel event to the server's refined frame (its ladder up to 4 samples "
        "a pixel, the GPU preview off); *GPU + fixed*: a wheel event to the GPU's full frame with the pixels its "
        "GLSL flagged traced by the server in double (one sample at the pixel's centre, as `implgen render` at one "
        "sample) and put in. Both include the page's 180 ms rest. Medians of the rounds, interleaved.",
        "",
        "| scene | server (ms) | GPU + fixed (ms) | server / (GPU + fixed) | pixels fixed | of the picture |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for name, r in results.items():
        s, g, n = (statistics.median(r[k]) for k in ("server", "gpu", "fixed"))
        lines.append(f"| {name} | {s:.0f} | {g:.0f} | {s / g:.2f} | {n:.0f} | {100 * n / (w * h):.2f} % |")
    return "\n".join([*lines, "", END])


if __name__ == "__main__":
    sys.exit(main())
