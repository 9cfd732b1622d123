"""How the shared page (implgen share) redraws in headless Chromium: per example shape, the full frame's time, and
what the page's progressive redraw makes of it -- the coarse frame's scale and time, and the longest single
step while it finishes the frame in bands.

    .venv/bin/python bench/share_frames.py [--size 640x480] [--rounds 3] [-o bench/results/share.md]

Each example shape is shared to a page (implgen share, defaults), opened from file:// in headless Chromium
(WebGL2 through ANGLE on SwiftShader, a CPU emulation of a GPU: the times are not a GPU's, only how the page
behaves when its GPU is slow) and drawn at --size. The rounds are interleaved over the shapes; medians are
reported. Per round and shape: the page redraws from scratch (IgSurface.Progressive.invalidate), every draw it
makes is timed (coarse frame, bands), and then one full frame is drawn in a single call.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "examples" / "shapes"

from implgen.cli import main as implgen  # noqa: E402
from implgen.measure import machine  # noqa: E402
from implgen.measure.webgl import FLAGS, WebGL  # noqa: E402

WRAP = """
const r = implgenShare.renderer, p = implgenShare.progressive;
if (!r.timedDraw) {
  r.timedDraw = r.draw.bind(r);
  r.draw = (opts) => { const ms = r.timedDraw(opts); window.igSteps.push([opts && opts.scale || 1, ms]); return ms; };
}
window.igSteps = [];
window.igStart = performance.now();
p.onIdle = () => { window.igWall = performance.now() - window.igStart; };
window.igWall = null;
p.invalidate(false);
"""


def parse_args(argv):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", default="640x480", help="the canvas's drawing buffer (default 640x480)")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved rounds over the shapes (default 3)")
    ap.add_argument("-o", "--out", type=Path, default=ROOT / "bench" / "results" / "share.md")
    args = ap.parse_args(argv)
    return args, tuple(int(v) for v in args.size.lower().split("x"))


def wait(d, script: str, timeout: float = 900.0) -> None:
    deadline = time.monotonic() + timeout
    while not d.execute_script(script):
        err = d.execute_script("return window.implgenShare && window.implgenShare.error;")
        if err:
            raise RuntimeError(err)
        if time.monotonic() > deadline:
            raise RuntimeError("the page did not finish")
        time.sleep(0.02)


def one(d, page: Path, size) -> dict:
    d.get(page.as_uri())
    wait(d, "return !!window.implgenShare && (!!window.implgenShare.error || window.implgenShare.idle());")
    d.execute_script("implgenShare.fixSize(arguments[0], arguments[1]);", *size)
    wait(d, "return implgenShare.idle();")
    d.execute_script(WRAP)
    wait(d, "return window.igWall !== null;")
    steps, wall = d.execute_script("return [window.igSteps, window.igWall];")
    full = d.execute_script("return implgenShare.renderer.timedDraw({scale: 1});")
    coarse_scale, coarse_ms = steps[0]
    bands = [ms for scale, ms in steps[1:] if scale == 1]
    return {
        "full": full,
        "coarse_scale": coarse_scale,
        "coarse": coarse_ms,
        "bands": len(bands),
        "longest": max([coarse_ms, *bands]),
        "wall": wall,
    }


def report(rows: dict, size, renderer: str, rounds: int, seconds: float, argv) -> str:
    w, h = size
    lines = [
        "# The shared page's redraw in headless Chromium",
        "",
        f"Written by `.venv/bin/python bench/share_frames.py{' ' + ' '.join(argv) if argv else ''}` on "
        f"{machine.describe()}, {time.strftime('%Y-%m-%d')}. Load average after: {machine.load_average()}. "
        f"Whole run {seconds / 60:.1f} min.",
        "",
        f"Browser: headless Chromium ({' '.join(FLAGS)}), WebGL renderer `{renderer}`: **SwiftShader is a CPU "
        "emulation of a GPU**; these times are not a GPU's. They show how the page behaves on a slow GPU: it draws "
        "in steps and answers input between them.",
        "",
        f"Each example shape shared with the defaults (`implgen share SPEC -o page.html`) and drawn at {w}×{h}; "
        f"medians of {rounds} rounds interleaved over the shapes. *full frame*: one draw of every pixel. *coarse*: "
        "the page's first frame after a change, at the scale the last whole frame's cost per pixel allows within "
        "its 40 ms budget (1/s of the size each way). *bands*: how many draws finish the frame; *longest step*: "
        "the longest single draw of the redraw (the page answers input between draws). *to full frame*: from the "
        "change to the last band.",
        "",
        "| shape | full frame | coarse | coarse frame | bands | longest step | to full frame |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for name, runs in rows.items():

        def med(key, runs=runs):
            return statistics.median(r[key] for r in runs)

        lines.append(
            f"| {name} | {med('full'):.0f} ms | 1/{med('coarse_scale'):.0f} | {med('coarse'):.0f} ms | "
            f"{med('bands'):.0f} | {med('longest'):.0f} ms | {med('wall') / 1000:.2f} s |"
        )
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    args, size = parse_args(argv)
    t0 = time.perf_counter()
    specs = sorted(SHAPES.glob("*.yaml"))
    rows: dict[str, list[dict]] = {p.stem: [] for p in specs}
    with tempfile.TemporaryDirectory() as tmp, WebGL() as gl:
        _, renderer = gl.info()
        pages = {}
        for p in specs:
            pages[p.stem] = Path(tmp) / f"{p.stem}.html"
            assert implgen(["share", str(p), "-o", str(pages[p.stem]), "-q"]) == 0
        for k in range(args.rounds):
            for name, page in pages.items():
                r = one(gl.driver, page, size)
                rows[name].append(r)
                print(
                    f"round {k + 1} {name:<10} full {r['full']:8.0f} ms  coarse 1/{r['coarse_scale']} "
                    f"{r['coarse']:6.0f} ms  bands {r['bands']:4d}  longest {r['longest']:6.0f} ms",
                    flush=True,
                )
    text = report(rows, size, renderer, args.rounds, time.perf_counter() - t0, argv)
    machine.write_results(args.out, text)
    print(text)
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
