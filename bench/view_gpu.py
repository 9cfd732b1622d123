"""The viewer's GPU preview during a scripted drag, in headless Chromium: frames a second, their size and cost.

    nice .venv/bin/python bench/view_gpu.py [--size 640x480] [--rounds 2] [--seconds 3] [-o bench/results/view.md]

Starts `implgen view --no-browser --port 0` (its own process), opens the page in headless Chromium with WebGL2
through ANGLE on SwiftShader (implgen.measure.webgl.FLAGS), gives the picture --size device pixels, ticks "GPU
preview" (off by default on a software renderer) and, for each case, opens its view through the page's share
link (equation, camera, clip), waits for the shape's GLSL and the server's refined frame, then drags the mouse
across the picture for --seconds (a move every 1/60 s, through Selenium's pointer actions). Every draw the page
makes meanwhile (IgSurface.Progressive: coarse frames sized to its 40 ms budget while the view moves) is timed
in the page. Reported per case, medians over the rounds (interleaved): GPU frames a second during the drag,
the coarse scale they were drawn at (1/s of the canvas each way), the median draw, the server frames received
during the drag (0: the page drew them all), and one full-size frame drawn at once after the drag.

SwiftShader is a CPU emulation of a GPU, sharing the machine's cores with the server: these figures say how
the page behaves on a very slow GPU, not what a GPU does. The section is written between markers into the
results file (--output), so bench/view_latency.py's tables stay.
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

from view_latency import CHMUTOV12  # the drags of view_latency.py: the same shapes

from implgen.measure.machine import describe as machine
from implgen.measure.machine import write_section
from implgen.measure.webgl import FLAGS

ROOT = Path(__file__).resolve().parents[1]
BEGIN, END = "<!-- bench/view_gpu.py: begin -->", "<!-- bench/view_gpu.py: end -->"
BARTH6 = "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - w^2)^2*w^2"
TORUS = "(x^2 + y^2 + z^2)^2 - 2*(a^2 + b^2)*(x^2 + y^2 + z^2) + 4*a^2*y^2 + (a^2 - b^2)^2"
# name, equation, params text, slider values, orbit (yaw, pitch, distance), clip (kind, size)
CASES = (
    ("torus", TORUS, "a = 1, b = 0.35", {"a": 1.0, "b": 0.35}, (30, 25, 4.6), ("sphere", 1.6)),
    ("chmutov12, zoomed in", CHMUTOV12, "", {}, (30, 25, 1.4), ("box", 1.05)),
    ("x^20+y^20+z^20-1", "x^20 + y^20 + z^20 - 1", "", {}, (30, 25, 5.0), ("sphere", 1.5)),
    (
        "barth6",
        BARTH6,
        "phi = 1.618033988749895, w = 1",
        {"phi": 1.618033988749895, "w": 1.0},
        (30, 25, 9.6),
        ("sphere", 3.0),
    ),
)
STATE = (
    "const v = document.getElementById('view'), g = document.getElementById('gpu-view');"
    "return {seq: +(v.dataset.seq ?? -1), kind: v.dataset.kind || '', frames: +(v.dataset.frames || 0),"
    " path: v.dataset.path, eq: document.getElementById('equation').value};"
)
WRAP = """
const r = implgenGpu.renderer();
if (!r.timedDraw) {
  r.timedDraw = r.draw.bind(r);
  r.draw = (o) => {
    const ms = r.timedDraw(o);
    window.igDraws.push([(o && o.scale) || 1, ms, performance.now()]);
    return ms;
  };
}
window.igDraws = [];
"""


def wait(d, what, timeout: float = 600.0):
    deadline = time.monotonic() + timeout
    while not (got := what(d)):
        if time.monotonic() > deadline:
            raise RuntimeError("the page did not get there")
        time.sleep(0.05)
    return got


def open_case(d, url: str, size: tuple[int, int], case) -> None:
    name, equation, params, values, (yaw, pitch, distance), (clip, clip_size) = case
    d.get(url)
    wait(d, lambda d: d.execute_script(STATE)["kind"] == "full")
    d.execute_script(
        "const s = document.getElementById('stage'); s.style.flex = 'none';"
        "s.style.width = arguments[0] + 'px'; s.style.height = arguments[1] + 'px';",
        *size,
    )
    if not d.execute_script("return document.getElementById('gpu').checked"):
        d.find_element("id", "gpu").click()
    seq = d.execute_script(STATE)["seq"]
    d.execute_script(
        "const o = window.implgenState();"
        "location.hash = implgenLink.encode({equation: arguments[0], name: 'surface', params: arguments[1],"
        " values: arguments[2], orbit: {yaw: arguments[3], pitch: arguments[4], distance: arguments[5],"
        " target: [0, 0, 0], fov: 40},"
        " options: Object.assign(o.options, {clip: arguments[6], clip_size: arguments[7]})});",
        equation,
        params,
        values,
        yaw,
        pitch,
        distance,
        clip,
        clip_size,
    )
    wait(d, lambda d: (s := d.execute_script(STATE))["seq"] > seq and s["kind"] == "full" and s["path"] == "gpu")
    assert d.execute_script("return document.getElementById('equation').value") == equation, name


def drag(d, seconds: float) -> dict:
    from selenium.webdriver.common.action_chains import ActionChains

    d.execute_script(WRAP)
    before = d.execute_script(STATE)["frames"]
    canvas = d.find_element("id", "view")
    moves = int(seconds * 60)
    chain = ActionChains(d, duration=0).move_to_element(canvas).move_by_offset(-moves // 2, 0).click_and_hold()
    t0 = d.execute_script("return performance.now()")
    for _ in range(moves):
        chain = chain.move_by_offset(1, 0).pause(1 / 60)
    chain.perform()
    t1 = d.execute_script("return performance.now()")
    draws = d.execute_script("return window.igDraws")
    server = d.execute_script(STATE)["frames"] - before
    ActionChains(d).release().perform()
    wait(d, lambda d: d.execute_script(STATE)["kind"] == "full")
    full = d.execute_script("return implgenGpu.renderer().timedDraw({})")
    during = [(s, ms) for s, ms, t in draws if t0 <= t <= t1]
    return {
        "fps": len(during) / ((t1 - t0) / 1000),
        "scale": statistics.median(s for s, _ in during) if during else float("nan"),
        "draw": statistics.median(ms for _, ms in during) if during else float("nan"),
        "server": server,
        "full": full,
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="640x480", help="the picture, in device pixels (default 640x480)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "view.md")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.lower().split("x"))
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    results: dict[str, list[dict]] = {c[0]: [] for c in CASES}
    load_before = os.getloadavg()[0]
    cmd = [sys.executable, "-m", "implgen.cli", "view", "--no-browser", "--port", "0"]
    server = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True)
    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in (*FLAGS, "--force-device-scale-factor=1", "--window-size=1100,700"):
        opts.add_argument(arg)
    d = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    d.set_script_timeout(600)
    try:
        url = "http://" + server.stdout.readline().split("http://", 1)[1].split()[0]
        for r in range(args.rounds):
            for case in CASES:
                open_case(d, url, size, case)
                results[case[0]].append(drag(d, args.seconds))
                print(f"round {r + 1}/{args.rounds} {case[0]}: {results[case[0]][-1]}", file=sys.stderr, flush=True)
        renderer = d.execute_script("return implgenGpu.renderer().info()[1]")
    finally:
        d.quit()
        server.terminate()
        server.wait(30)
    load_after = os.getloadavg()[0]
    med = {n: {k: statistics.median(x[k] for x in v) for k in v[0]} for n, v in results.items()}
    lines = [
        BEGIN,
        "## The GPU preview during a drag (SwiftShader, not a GPU)",
        "",
        f"Written by `bench/view_gpu.py --size {args.size} --rounds {args.rounds} --seconds {args.seconds:g}` on "
        f"{machine()}; load average (1 min) {load_before:.2f} before, {load_after:.2f} after. Headless Chromium, "
        f"WebGL renderer `{renderer}`: **SwiftShader is a CPU emulation of a GPU**, sharing these cores with the "
        "server; the figures show how the page behaves on a very slow GPU, not what a GPU does. On a software "
        "renderer the page leaves the GPU preview off unless ticked (the server's coarse frames above are faster).",
        "",
        f"The page's picture is {size[0]}×{size[1]}; the mouse moves every 1/60 s for {args.seconds:g} s. *GPU "
        "frames/s*: the page's draws during the drag (coarse, at the scale its 40 ms budget allows); *scale*: 1/s "
        "of the canvas each way; *draw*: the median draw; *server frames*: frames the server sent during the drag "
        "(0: the page drew every live frame itself); *full frame*: one full-size GPU frame (the studio lights, "
        f"two shadow rays a hit). Medians of {args.rounds} rounds.",
        "",
        "| drag | GPU frames/s | scale | draw (ms) | server frames | full frame (ms) |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for name, m in med.items():
        lines.append(
            f"| {name} | {m['fps']:.1f} | 1/{m['scale']:g} | {m['draw']:.0f} | {m['server']:g} | {m['full']:.0f} |"
        )
    lines += ["", END]
    section = "\n".join(lines)
    print(section)
    write_section(args.output, BEGIN, END, section)
    return 0


if __name__ == "__main__":
    sys.exit(main())
