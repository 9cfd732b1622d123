"""Edit-to-picture latency and frame rate of `implgen view`, measured through the real server's WebSocket.

    .venv/bin/python bench/view_latency.py [--rounds N] [--orbit-frames N] [--neighbour-seconds S] [-o FILE]
    .venv/bin/python bench/view_latency.py --neighbours-only     # the last measure alone, printed, not written
    nice .venv/bin/python bench/view_latency.py --drag-only [--compare /work/main]   # the drags alone
    nice .venv/bin/python bench/view_latency.py --glass [--compare /work/main]   # the glassware refinement alone

Starts `implgen view --no-browser --port 0` in its own process with an empty build cache, connects as the page
does, and for every example shape of degree <= 8, interleaved round by round, measures:
  - new equation: from sending the edit to the first (coarse) picture; the equation is one the cache has never
    seen (a tiny constant added), so it is generated, compiled (its .c and the glue) and linked;
  - cached equation: the same edit sent again (generated code, objects and library all in the cache);
  - orbit: coarse frames per second while turning, each request sent when the previous frame has arrived;
  - refinement: from the coarse frame to the full 640 x 480, 4 samples per pixel frame of a resting view.
Then drags: the page's mouse moves at 60 a second, whatever comes back, for
DRAG_SECONDS, on the glassware scene, a zoomed-in Chmutov 12, x^20 + y^20 + z^20 - 1 and Barth's sextic: the
coarse frames a second that arrive, the longest gap between two, and from the release (a refined request for
the last view) to the refined frame. With --compare TREE, the same drags against a server run from another
source tree (PYTHONPATH=TREE/generator: the code before the change), interleaved case by case and round by
round, so both see the same load.
With --glass (its own section of the results file): the glassware scene at 640 x 480 and 1280 x 800, a drag then
the release, interleaved size by size and round by round (and with --compare, tree by tree): from the release to
the half-size picture, the full size at 1 sample and at 4, how long the drag's last frame, when smaller than a
quarter of the picture, stays on the page (from its arrival to the first picture of a quarter or more), and the
server's CPU time from the release to the 4-sample picture.
Then, with heavy neighbours: one page orbits while three other pages keep sending
`(x+y+z+a+b+1)^15` with a new constant each time (seconds of SymPy, then a build), and the orbiting page's
frames per second and its longest wait for a frame are measured.
Prints the medians and writes them, with the machine, to the results file.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from implgen.measure.machine import describe as machine
from implgen.measure.machine import write_results, write_section
from implgen.spec.entry import load_spec
from implgen.view.dump import spec_mapping
from implgen.view.session import (
    HEADER,
    KIND_COARSE,
    KIND_FULL,
    KIND_MORE,
    KIND_ONE,
    KIND_QUARTER,
    MAX_RENDERS_PER_SECOND,
    SAMPLES,
)

ROOT = Path(__file__).resolve().parents[1]
SHAPES = ROOT / "examples" / "shapes"
MAX_DEGREE = 8
WIDTH, HEIGHT = 640, 480


class Page:
    """The page's side of the protocol, with a clock."""

    def __init__(self, url: str, width: int = WIDTH, height: int = HEIGHT):
        self.ws = connect(url, max_size=64 * 2**20)
        self.width, self.height = width, height
        self.hello = json.loads(self.ws.recv())
        self.seq = 0
        self.orbit = dict(self.hello["orbit"])
        self.options = dict(self.hello["options"])
        self.values = dict(self.hello["values"])

    def send(self, msg: dict) -> None:
        self.ws.send(json.dumps(msg))

    def orbit_for(self, seconds: float) -> tuple[int, float, float]:
        """Turn the camera 3 degrees a frame, each coarse frame awaited, for `seconds`: (frames, the longest
        wait for one, seconds elapsed)."""
        frames, longest = 0, 0.0
        start = time.perf_counter()
        while time.perf_counter() - start < seconds:
            self.orbit["yaw"] = (self.orbit["yaw"] + 3.0) % 360.0
            t0 = time.perf_counter()
            self.frame(self.render(False), KIND_COARSE)
            longest = max(longest, time.perf_counter() - t0)
            frames += 1
        return frames, longest, time.perf_counter() - start

    def render(self, refine: bool) -> int:
        self.seq += 1
        self.send(
            {
                "type": "render",
                "seq": self.seq,
                "refine": refine,
                "width": self.width,
                "height": self.height,
                "values": self.values,
                "orbit": self.orbit,
                "options": self.options,
            }
        )
        return self.seq

    def frame(self, seq: int, kind: int) -> float:
        """Wait for this frame; returns the time it arrived."""
        while True:
            msg = self.ws.recv()
            if isinstance(msg, bytes):
                s, k, _, _, _ = HEADER.unpack(msg[: HEADER.size])
                if s == seq and k == kind:
                    return time.perf_counter()
            else:
                data = json.loads(msg)
                if data["type"] == "error":
                    raise RuntimeError(data["message"])

    def reply(self) -> dict:
        while True:
            msg = self.ws.recv()
            if isinstance(msg, str):
                data = json.loads(msg)
                if data["type"] == "error":
                    raise RuntimeError(data["message"])
                if data["type"] != "status":  # a build's progress line comes before the reply
                    return data

    def edit(self, shape: dict) -> tuple[float, float]:
        """Send a new equation as the page does (the edit, then a refined render once it is accepted).
        Returns (seconds to the first picture, seconds from it to the refined one)."""
        t0 = time.perf_counter()
        self.send({"type": "shape", **shape})
        data = self.reply()
        self.values = dict(data["values"])
        seq = self.render(True)
        t1 = self.frame(seq, KIND_COARSE)
        t2 = self.frame(seq, KIND_FULL)
        return t1 - t0, t2 - t1


DRAG_SECONDS = 3.0
MOVE_GAP = 1 / 60  # seconds between the page's mouse moves while dragging
CHMUTOV12 = (
    "3 + 2048*(x^12 + y^12 + z^12) - 6144*(x^10 + y^10 + z^10) + 6912*(x^8 + y^8 + z^8) - 3584*(x^6 + y^6 + z^6)"
    " + 840*(x^4 + y^4 + z^4) - 72*(x^2 + y^2 + z^2)"
)  # T12(x) + T12(y) + T12(z), T12 the Chebyshev polynomial
BOX = {a: ["-1.05", "1.05"] for a in "xyz"}
# name, scene file (None: the starter page), the shape message (None: the file's), orbit changes, clip
DRAGS = (
    ("glassware scene", ROOT / "examples" / "scenes" / "glassware.yaml", None, {}, None),
    ("chmutov12, zoomed in", None, {"equation": CHMUTOV12, "bounds": BOX}, {"distance": 1.4}, "none"),
    ("x^20+y^20+z^20-1", None, {"equation": "x^20 + y^20 + z^20 - 1"}, {"distance": 5.0}, "sphere"),
    (
        "barth6",
        None,
        {
            "equation": "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - "
            "w^2)^2*w^2",
            "params": {"phi": 1.618033988749895, "w": 1.0},
        },
        {"distance": 9.6},
        "sphere",
    ),
)


def start_server(env: dict, file: Path | None) -> tuple[subprocess.Popen, str]:
    cmd = [sys.executable, "-m", "implgen.cli", "view", "--no-browser", "--port", "0"]
    server = subprocess.Popen(cmd + ([str(file)] if file else []), stdout=subprocess.PIPE, text=True, env=env)
    line = server.stdout.readline()
    return server, "ws://" + line.split("http://", 1)[1].split("/", 1)[0] + "/ws"


def drag_page(url: str, shape: dict | None, orbit: dict, clip: str | None) -> Page:
    page = Page(url)
    if shape is not None:
        page.send({"type": "shape", **shape})
        page.values = dict(page.reply()["values"])
    page.orbit.update(orbit)
    page.orbit["target"] = [0.0, 0.0, 0.0] if shape is not None else page.orbit["target"]
    if clip is not None:
        page.options["clip"], page.options["clip_size"] = clip, 3.0
    page.frame(page.render(True), KIND_FULL)  # built and drawn once before the drag
    return page


def moves(page: Page, seconds: float) -> tuple[list[float], list[tuple[int, int]]]:
    """Mouse moves every MOVE_GAP for `seconds`, sent whatever comes back: the start, the coarse frames' arrival
    times, the end; the coarse frames' sizes."""
    stop = threading.Event()

    def mover() -> None:
        while not stop.is_set():
            page.orbit["yaw"] = (page.orbit["yaw"] + 1.0) % 360.0
            page.render(False)
            time.sleep(MOVE_GAP)

    start = time.perf_counter()
    arrivals, sizes = [start], []
    sender = threading.Thread(target=mover, daemon=True)
    sender.start()
    while time.perf_counter() - start < seconds:
        try:
            msg = page.ws.recv(timeout=max(0.01, seconds - (time.perf_counter() - start)))
        except TimeoutError:
            break
        if isinstance(msg, bytes):
            _, k, _, w, h = HEADER.unpack(msg[: HEADER.size])
            if k == KIND_COARSE:
                arrivals.append(time.perf_counter())
                sizes.append((w, h))
    stop.set()
    sender.join()
    return arrivals + [time.perf_counter()], sizes


RELEASE_KINDS = {KIND_QUARTER: "quarter", KIND_ONE: "one", KIND_FULL: "full"}


def release(page: Page, guard: float = 120.0, pid: int | None = None) -> dict:
    """The release (a refined request for the last move's view): seconds from it to the first picture of each
    kind (RELEASE_KINDS; KIND_MORE as more2, more3), coarse frames of the drag still arriving ("coarse": the
    last one's arrival), the refinement's error line if it stopped, the server's CPU seconds to the end."""
    t0, cpu0 = time.perf_counter(), cpu_seconds(pid)
    seq = page.render(True)
    out: dict = {"error": None}
    while "full" not in out and time.perf_counter() - t0 < guard:
        try:
            msg = page.ws.recv(timeout=max(0.01, guard - (time.perf_counter() - t0)))
        except TimeoutError:
            break
        now = time.perf_counter() - t0
        if isinstance(msg, str):
            data = json.loads(msg)
            if data["type"] == "error":
                out["error"] = data["message"]
                break
            continue
        s, k, _, samples, w, h = SAMPLES.unpack(msg[: SAMPLES.size])
        if k == KIND_COARSE:
            out["coarse"] = now
        elif s == seq:
            out.setdefault(f"more{samples}" if k == KIND_MORE else RELEASE_KINDS.get(k, str(k)), now)
    out["cpu"] = cpu_seconds(pid) - cpu0
    return out


def cpu_seconds(pid: int | None) -> float:
    """User + system CPU seconds of process `pid` so far (0 without one)."""
    if pid is None:
        return 0.0
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def drag(page: Page, seconds: float = DRAG_SECONDS) -> dict[str, float]:
    """Mouse moves every MOVE_GAP for `seconds` (sent whatever comes back), then the release: coarse frames a
    second, the longest gap without a frame, the median coarse frame's width, release to refined frame."""
    arrivals, sizes = moves(page, seconds)
    end = arrivals[-1]
    after = release(page)
    if after["error"] is not None:
        raise RuntimeError(after["error"])
    gaps = [b - a for a, b in zip(arrivals, arrivals[1:])]
    return {
        "fps": (len(arrivals) - 2) / (end - arrivals[0]),
        "gap": max(gaps),
        "width": statistics.median(w for w, _ in sizes) if sizes else 0.0,
        "sharp": after.get("one", after["full"]),
        "release": after["full"],
    }


def drags(rounds: int, compare: Path | None) -> tuple[dict, dict | None]:
    """Every drag case, interleaved round by round (and with the compared tree's server, case by case)."""
    trees = {"new": None} | ({"old": compare} if compare else {})
    out: dict[str, dict[str, dict[str, list[float]]]] = {t: {c[0]: {} for c in DRAGS} for t in trees}
    with tempfile.TemporaryDirectory(prefix="implgen-bench-drag-") as cache:
        servers, pages = [], {}
        try:
            for tree, path in trees.items():
                env = dict(os.environ, IMPLGEN_CACHE=str(Path(cache) / tree))
                if path is not None:
                    env["PYTHONPATH"] = str(path / "generator")
                for name, file, shape, orbit, clip in DRAGS:
                    server, url = start_server(env, file)
                    servers.append(server)
                    pages[tree, name] = drag_page(url, shape, orbit, clip)
            for r in range(rounds):
                for name, *_ in DRAGS:
                    for tree in trees:
                        for k, v in drag(pages[tree, name]).items():
                            out[tree][name].setdefault(k, []).append(v)
                        print(f"drag round {r + 1}/{rounds} {name} {tree}", file=sys.stderr, flush=True)
        finally:
            for server in servers:
                server.terminate()
                server.wait(30)
    med = {t: {n: {k: statistics.median(v) for k, v in d.items()} for n, d in o.items()} for t, o in out.items()}
    return med["new"], med.get("old")


def drag_lines(new: dict, old: dict | None, rounds: int, compare: Path | None = None) -> list[str]:
    head = (
        "| drag | coarse frames/s | longest gap (s) | coarse width (px) | release → full size, 1 spp (s) | "
        "release → 4 spp (s) |"
    )
    lines = [
        f"Drags: mouse moves every {MOVE_GAP * 1e3:.0f} ms for {DRAG_SECONDS:g} s, sent whatever "
        f"comes back, 640×480 canvas, then the release; medians of {rounds} rounds. Targets: ≥ 15 coarse "
        "frames/s, refined ≤ 0.4 s after the release for degree ≤ 8. When its 4-sample frame is expected to take "
        "longer than 0.4 s, the server refines it pass by pass (the full size at 1 sample first).",
        "",
        head
        if old is None
        else head + " before: frames/s | before: longest gap (s) | before: width (px) | before: 1 spp (s) | "
        "before: 4 spp (s) |",
        "|---|---|---|---|---|---|" + ("---|---|---|---|---|" if old else ""),
    ]
    for name, m in new.items():
        row = f"| {name} | {m['fps']:.1f} | {m['gap']:.3f} | {m['width']:.0f} | {m['sharp']:.3f} | {m['release']:.3f} |"
        if old is not None:
            o = old[name]
            row += f" {o['fps']:.1f} | {o['gap']:.3f} | {o['width']:.0f} | {o['sharp']:.3f} | {o['release']:.3f} |"
        lines.append(row)
    if old is not None and compare is not None:
        lines += [
            "",
            f"Before: the same drags against the server of `{compare}`, interleaved case by case and round by round.",
        ]
    return lines + [""]


GLASSWARE = ROOT / "examples" / "scenes" / "glassware.yaml"
GLASS_SIZES = ((640, 480), (1280, 800))
GLASS_DRAG = 1.5  # seconds of mouse moves before each release
GLASS_GUARD = 120.0  # seconds: a hang guard for one refinement
GLASS_BEGIN, GLASS_END = "<!-- bench/view_latency.py --glass: begin -->", "<!-- bench/view_latency.py --glass: end -->"


def glass_round(page: Page, pid: int) -> dict:
    """One drag of the glassware page, then the release: what `release` says, and how long the drag's last
    frame stayed on the page when it was smaller than a quarter of the picture ("small")."""
    arrivals, sizes = moves(page, GLASS_DRAG)
    last_w, last_h = sizes[-1] if sizes else (0, 0)
    last = arrivals[-2] - arrivals[-1]  # the last coarse frame's arrival, from the release (<= 0)
    out = release(page, GLASS_GUARD, pid)
    last = out.get("coarse", last)  # a frame of the drag may still come after the release
    big = [out[k] for k in ("quarter", "one", "full") if k in out]
    small = 4 * last_w * last_h < page.width * page.height
    out["small"] = (min(big) - last if big else None) if small else 0.0  # None: no picture came (the budget)
    out["shown"] = last_w
    return out


def glass(rounds: int, compare: Path | None) -> dict:
    """The glassware refinement at each size, interleaved round by round (and tree by tree): per tree and size,
    each measure's list over the rounds (a missing picture is None)."""
    trees = {"new": None} | ({"old": compare} if compare else {})
    out: dict = {(t, size): {} for t in trees for size in GLASS_SIZES}
    with tempfile.TemporaryDirectory(prefix="implgen-bench-glass-") as cache:
        servers, pages = [], {}
        try:
            for tree, path in trees.items():
                env = dict(os.environ, IMPLGEN_CACHE=str(Path(cache) / tree))
                if path is not None:
                    env["PYTHONPATH"] = str(path / "generator")
                for size in GLASS_SIZES:
                    server, url = start_server(env, GLASSWARE)
                    servers.append(server)
                    page = Page(url, *size)
                    release(page, GLASS_GUARD * 4)  # built and refined once before the drags
                    pages[tree, size] = (page, server.pid)
            for r in range(rounds):
                for size in GLASS_SIZES:
                    for tree in trees:
                        got = glass_round(*pages[tree, size])
                        for k in ("quarter", "one", "full", "small", "shown", "cpu", "error"):
                            out[tree, size].setdefault(k, []).append(got.get(k))
                        print(f"glass round {r + 1}/{rounds} {size} {tree}: {got}", file=sys.stderr, flush=True)
        finally:
            for server in servers:
                server.terminate()
                server.wait(30)
    return out


QUIET_ONE = 0.73  # s: glassware's 1-sample picture at 640×480 after the release, quiet 2-core AMD EPYC (docs/viewer.md)
GLASS_PER_PIXEL = 2.4e-6  # s: a pixel at one sample, as the live frames measure it on that machine (the ladder's plan)


def glass_work(rounds: int) -> dict:
    """In this process, this tree's runtime: the core seconds (process CPU time: every thread) and the rays traced
    from the start of a refinement to each of its pictures, encoding included, the way before (a 1-sample render
    at the pixel centres, then a 4-sample render from nothing) and the ladder, interleaved round by round. Load
    inflates CPU time less than wall time, and both ways alike; the rays do not depend on it."""
    from implgen.scene.build import build_scene
    from implgen.scene.tracer import CScene
    from implgen.view.command import document_factory

    doc = document_factory(GLASSWARE)()
    out: dict = {}
    for _ in range(rounds):
        for w, h in GLASS_SIZES:
            sc = doc.scene(w, h, 4)
            cs = CScene(sc, build_scene(sc))
            for way in ("before", "ladder"):
                got = out.setdefault((w, h, way), {})
                for stage, (cpu, rays) in (_before if way == "before" else _ladder)(cs, sc, w, h):
                    got.setdefault(stage, []).append(cpu)
                    got.setdefault("rays " + stage, []).append(rays)
            cs.close()
    return out


def _before(cs, sc, w: int, h: int) -> list[tuple[str, tuple[float, float]]]:
    """The refinement before the ladder: a 1-sample render, then a 4-sample one; (stage, (CPU, rays)) of each."""
    from implgen.scene.renderjob import RenderJob
    from implgen.view import frames

    t0, rays, out = time.process_time(), 0.0, []
    for stage, spp in (("one", 1), ("full", 4)):
        with RenderJob(cs, w, h, spp, sc.max_depth, 2) as job:
            frames.live_png(frames.eight_bits(job.run()))
            rays += sum(job.stats().rays.values())
        out.append((stage, (time.process_time() - t0, rays)))
    return out


def _ladder(cs, sc, w: int, h: int) -> list[tuple[str, tuple[float, float]]]:
    """The ladder, a pass a sample: (stage, (CPU, rays)) of each picture."""
    from implgen.scene.renderjob import PIXELS_EVEN, RenderJob
    from implgen.view import frames, ladder

    t0, out = time.process_time(), []
    with RenderJob(cs, w, h, 4, sc.max_depth, 2) as job:
        for step in ladder.plan(w, h, 4, max(GLASS_PER_PIXEL, 1.0 / (w * h)), True):
            img = job.run_pass(step.k0, step.k1, step.pixels)
            frames.live_png(frames.eight_bits(img[::2, ::2] if step.pixels == PIXELS_EVEN else img))
            stage = step.role + (str(step.k1) if step.role == "more" else "")
            out.append((stage, (time.process_time() - t0, sum(job.stats().rays.values()))))
    return out


def work_lines(work: dict) -> list[str]:
    lines = [
        "Work, independent of the load: the core seconds and the rays (all kinds, millions) from the start of the "
        "refinement to each picture, encoding included, rendered in the benchmark's own process with this tree's "
        "runtime on 2 threads, the way before (a 1-sample render, then a 4-sample render from nothing) and the "
        f"ladder, interleaved. *Quiet estimate*: {QUIET_ONE} s (the 1-sample picture at 640×480 on a quiet 2-core "
        "machine, before) times the picture's rays over those of the 1-sample render before at 640×480.",
        "",
        "| size | way | → half size (core s) | → 1 spp | → 2 spp | → 3 spp | → 4 spp | rays to half size, 1 spp, "
        "4 spp (M) | quiet estimate: half size, 1 spp, 4 spp (s) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    unit = statistics.median(work[640, 480, "before"]["rays one"])  # the rays of QUIET_ONE
    for w, h in GLASS_SIZES:
        for way in ("before", "ladder"):
            m = work[w, h, way]
            cells = [_median(m[k]) if k in m else "–" for k in ("quarter", "one", "more2", "more3", "full")]
            rays = [statistics.median(m[f"rays {k}"]) if f"rays {k}" in m else None for k in ("quarter", "one", "full")]
            cells.append(", ".join("–" if r is None else f"{r / 1e6:.2f}" for r in rays))
            cells.append(", ".join("–" if r is None else f"{QUIET_ONE * r / unit:.2f}" for r in rays))
            lines.append(f"| {w}×{h} | {way} | " + " | ".join(cells) + " |")
    return lines + [""]


def _median(values: list, digits: int = 3) -> str:
    got = [v for v in values if v is not None]
    text = f"{statistics.median(got):.{digits}f}" if got else "never"
    return text + (f" ({len(values) - len(got)} of {len(values)} never)" if got and len(got) < len(values) else "")


def glass_lines(out: dict, rounds: int, compare: Path | None, load: tuple[float, float]) -> list[str]:
    lines = [
        GLASS_BEGIN,
        "## The glassware scene after a drag: the refinement ladder",
        "",
        f"Written by `bench/view_latency.py --glass --rounds {rounds}"
        + (f" --compare {compare}`" if compare else "`")
        + f" on {machine()}; load average (1 min) {load[0]:.2f} before, {load[1]:.2f} after. The server "
        "(`implgen view examples/scenes/glassware.yaml`, its own process, 2 render threads) and this client share "
        f"the machine. Each round: mouse moves every {MOVE_GAP * 1e3:.0f} ms for {GLASS_DRAG:g} s, then the release "
        "(a refined request for the last move's view); sizes and trees interleaved round by round. Medians of "
        f"{rounds} rounds. *Small frame*: how long the drag's last frame, when smaller than a quarter of the "
        "picture, stays on the page (from its arrival to the first picture of a quarter or more). *CPU*: the "
        "server's CPU time from the release to the 4-sample picture, or to the stop (on a quiet 2-core machine "
        "the wall time is about half of it). *never*: the render budget (20 s) stopped it first. Targets on a "
        "quiet 2-core machine: 1 sample ≤ 0.3 s, 4 samples ≤ 1.2 s, small frame ≤ 0.3 s.",
        "",
        "| size | server | last drag frame (px wide) | release → half size (s) | small frame shown (s) | "
        "release → 1 spp (s) | release → 4 spp (s) | CPU to 4 spp (core s) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for (tree, (w, h)), m in out.items():
        name = "this tree" if tree == "new" else f"`{compare}`"
        cells = [_median(m["shown"], 0)] + [_median(m[k]) for k in ("quarter", "small", "one", "full", "cpu")]
        lines.append(f"| {w}×{h} | {name} | " + " | ".join(cells) + " |")
    lines.append("")
    for (tree, (w, h)), m in out.items():  # one message of each kind, its figures as the last round had them
        said = {re.sub(r"[0-9.]+ ms", "N ms", e): e for e in m["error"] if e}
        if said:
            name = "this tree" if tree == "new" else f"`{compare}`"
            stopped = sum(map(bool, m["error"]))
            lines.append(f"- {w}×{h}, {name}: stopped by the budget in {stopped} of {rounds} rounds, saying")
            lines += [f"  `{e}`" for e in said.values()]
    return lines + ["", GLASS_END]


def write_glass(path: Path, lines: list[str]) -> None:
    """The glass section into the results file, in place of the last one (or at its end)."""
    write_section(path, GLASS_BEGIN, GLASS_END, "\n".join(lines))


NEIGHBOUR_EQUATION = "(x+y+z+a+b+1)^15"
NEIGHBOURS = 3


def neighbours(url: str, seconds: float) -> dict[str, float]:
    """Orbit frames/s and the longest frame wait of one page while NEIGHBOURS pages send heavy new equations."""
    stop = threading.Event()
    sent = [0]

    def neighbour(k: int) -> None:
        page = Page(url)
        n = 0
        try:
            while not stop.is_set():
                n += 1
                equation = f"{NEIGHBOUR_EQUATION} + {n}/{1000 + k}"  # never seen before: parsed and built
                page.send({"type": "shape", "equation": equation, "params": {"a": 1, "b": 1}})
                sent[0] += 1
                try:
                    page.reply()
                except RuntimeError:
                    pass  # refused: send the next one
        except ConnectionClosed:
            return  # the server stopped
        page.ws.close()

    good = Page(url)
    good.frame(good.render(False), KIND_COARSE)  # its shape is built before the neighbours start
    threads = [threading.Thread(target=neighbour, args=(k,), daemon=True) for k in range(NEIGHBOURS)]
    for t in threads:
        t.start()
    time.sleep(1.0)  # their first equations are being parsed
    frames, longest, elapsed = good.orbit_for(seconds)
    stop.set()
    good.ws.close()
    return {"fps": frames / elapsed, "longest": longest, "equations": sent[0], "seconds": elapsed}


def frame_for(spec, page: Page) -> None:
    """Point the page's camera at the shape (its box, else the clip ball) as the viewer does for a spec file."""
    from implgen.view.document import Document

    doc = Document.for_spec(spec)
    page.orbit = {
        "yaw": 30.0,
        "pitch": 25.0,
        "distance": doc.orbit.distance,
        "target": list(doc.orbit.target),
        "fov": 40.0,
    }
    if spec.box() is None or not all(abs(v) < 1e300 for v in spec.box()):
        page.orbit["distance"] = 3.0 / 0.342 * 1.1  # the clip ball of radius 3 fills the view
        page.options["clip_size"] = 3.0
    else:
        page.options["clip_size"] = doc.options.clip_size


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--orbit-frames", type=int, default=60, dest="orbit_frames")
    ap.add_argument("--neighbour-seconds", type=float, default=20.0, dest="neighbour_seconds")
    ap.add_argument("--neighbours-only", action="store_true", dest="neighbours_only")
    ap.add_argument("--drag-only", action="store_true", dest="drag_only", help="the drags alone, printed")
    ap.add_argument("--drag-rounds", type=int, default=5, dest="drag_rounds")
    ap.add_argument("--compare", type=Path, help="a source tree whose server the drags are compared with")
    ap.add_argument("--glass", action="store_true", help="the glassware refinement alone, into its own section")
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "view.md")
    args = ap.parse_args()
    if args.neighbours_only:
        with tempfile.TemporaryDirectory(prefix="implgen-bench-view-") as cache:
            cmd = [sys.executable, "-m", "implgen.cli", "view", "--no-browser", "--port", "0"]
            server = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=dict(os.environ, IMPLGEN_CACHE=cache))
            try:
                line = server.stdout.readline()
                url = "ws://" + line.split("http://", 1)[1].split("/", 1)[0] + "/ws"
                print(neighbours(url, args.neighbour_seconds))
            finally:
                server.kill()
                server.wait(30)
        return 0
    if args.glass:
        before = os.getloadavg()[0]
        out = glass(args.rounds, args.compare)
        work = glass_work(args.rounds)
        lines = glass_lines(out, args.rounds, args.compare, (before, os.getloadavg()[0]))
        lines[-1:-1] = work_lines(work)
        print("\n".join(lines))
        write_glass(args.output, lines)
        return 0
    if args.drag_only:
        load = os.getloadavg()[0]
        new, old = drags(args.drag_rounds, args.compare)
        print("\n".join(drag_lines(new, old, args.drag_rounds, args.compare)))
        print(f"load average (1 min) {load:.2f} before, {os.getloadavg()[0]:.2f} after; {machine()}")
        return 0
    drag_load = os.getloadavg()[0]
    drag_new, drag_old = drags(args.drag_rounds, args.compare)
    drag_load_after = os.getloadavg()[0]
    specs = [s for s in (load_spec(p) for p in sorted(SHAPES.glob("*.yaml"))) if s.degree <= MAX_DEGREE]
    nonce = time.time_ns() % 10**9
    load_before = os.getloadavg()[0]
    results: dict[str, dict[str, list[float]]] = {s.name: {} for s in specs}

    def add(name: str, key: str, value: float) -> None:
        results[name].setdefault(key, []).append(value)

    with tempfile.TemporaryDirectory(prefix="implgen-bench-view-") as cache:
        env = dict(os.environ, IMPLGEN_CACHE=cache)
        cmd = [sys.executable, "-m", "implgen.cli", "view", "--no-browser", "--port", "0"]
        server = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env)
        try:
            line = server.stdout.readline()
            url = "ws://" + line.split("http://", 1)[1].split("/", 1)[0] + "/ws"
            t0 = time.perf_counter()
            page = Page(url)
            seq = page.render(True)
            cold = page.frame(seq, KIND_COARSE) - t0  # the runtime's objects are compiled here, once
            page.frame(seq, KIND_FULL)
            for r in range(args.rounds):
                for spec in specs:
                    mapping = spec_mapping(spec)
                    shape = {
                        "equation": f"{mapping['equation']} + {r + 1}/{nonce}000000000000",  # never seen before
                        "params": mapping.get("params") or {},
                        "bounds": mapping.get("bounds"),
                    }
                    frame_for(spec, page)
                    first, refine = page.edit(shape)
                    add(spec.name, "new", first)
                    add(spec.name, "refine", refine)
                    first, _ = page.edit(shape)
                    add(spec.name, "cached", first)
                    start = time.perf_counter()
                    for _ in range(args.orbit_frames):
                        page.orbit["yaw"] = (page.orbit["yaw"] + 3.0) % 360.0
                        page.frame(page.render(False), KIND_COARSE)
                    add(spec.name, "fps", args.orbit_frames / (time.perf_counter() - start))
                    print(f"round {r + 1}/{args.rounds} {spec.name}", file=sys.stderr, flush=True)
            busy = neighbours(url, args.neighbour_seconds) if args.neighbour_seconds > 0 else None
        finally:
            server.terminate()
            server.wait(30)

    load_after = os.getloadavg()[0]
    med = {n: {k: statistics.median(v) for k, v in d.items()} for n, d in results.items()}
    degree = {s.name: s.degree for s in specs}
    lines = [
        "# `implgen view`: edit-to-picture latency and frame rate",
        "",
        f"Written by `bench/view_latency.py --rounds {args.rounds} --orbit-frames {args.orbit_frames}` on "
        f"{machine()}. The server (`implgen view`, its own process, an empty build cache) and this client ran on "
        "the same machine; everything goes through the WebSocket as the page's messages do. Medians over the "
        "rounds, shapes interleaved within each round. Load average (1 min) before the run "
        f"{load_before:.2f}, after {load_after:.2f}: above about 1 the machine was shared and the times are longer.",
        "",
        f"Cold start (the runtime compiled into cached objects, once per cache): first picture after {cold:.2f} s.",
        "",
        "| shape | degree | new equation → first picture (s) | cached → first picture (s) | "
        "orbit, coarse frames/s | full 640×480, 4 spp refinement (s) |",
        "|---|---|---|---|---|---|",
    ]
    for name, m in sorted(med.items(), key=lambda kv: (degree[kv[0]], kv[0])):
        lines.append(
            f"| {name} | {degree[name]} | {m['new']:.3f} | {m['cached']:.3f} | {m['fps']:.1f} | {m['refine']:.3f} |"
        )
    worst = {k: (max if k != "fps" else min)(m[k] for m in med.values()) for k in ("new", "cached", "fps", "refine")}
    lines += [
        "",
        f"Worst shape: new equation {worst['new']:.3f} s (target ≤ 1.0), cached {worst['cached']:.3f} s "
        f"(target ≤ 0.15), orbit {worst['fps']:.1f} frames/s (target ≥ 20), refinement {worst['refine']:.3f} s "
        "(target ≤ 0.4).",
        "",
        "Coarse frames are at 1 sample per pixel (JPEG), sized by the server for about 30 ms each (view/pace.py: "
        "at most 320×240 here), refined frames 640×480 at 4 (PNG); the studio light preset (two lights, so two "
        "shadow rays per hit), the surface clipped to a ball (cut open). The server starts at most "
        f"{MAX_RENDERS_PER_SECOND} renders a second per page, which caps the orbit rate.",
        "",
    ]
    lines += drag_lines(drag_new, drag_old, args.drag_rounds, args.compare)
    lines += [f"Load average (1 min) before the drags {drag_load:.2f}, after {drag_load_after:.2f}.", ""]
    if busy is not None:
        lines += [
            f"With heavy neighbours: {NEIGHBOURS} other pages kept sending `{NEIGHBOUR_EQUATION} + n/k` (a new "
            f"equation each time: seconds of SymPy on the parse pool, then a build; {busy['equations']} sent) "
            f"while the torus page orbited for {busy['seconds']:.0f} s: {busy['fps']:.1f} coarse frames/s, the "
            f"longest wait for a frame {busy['longest']:.3f} s.",
            "",
        ]
    text = "\n".join(lines)
    print(text)
    old = args.output.read_text(encoding="utf-8") if args.output.exists() else ""
    for begin, end in (
        ("<!-- bench/view_gpu.py: begin -->", "<!-- bench/view_gpu.py: end -->"),
        ("<!-- bench/view_scene_rest.py: begin -->", "<!-- bench/view_scene_rest.py: end -->"),
        (GLASS_BEGIN, GLASS_END),
    ):
        if begin in old and end in old:  # the sections of bench/view_gpu.py, view_scene_rest.py and --glass stay
            text = text.rstrip("\n") + "\n\n" + old[old.index(begin) : old.index(end) + len(end)] + "\n"
    write_results(args.output, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
