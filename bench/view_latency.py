"""Edit-to-picture latency and frame rate of `implgen view`, measured through the real server's WebSocket.

    .venv/bin/python bench/view_latency.py [--rounds N] [--orbit-frames N] [--neighbour-seconds S] [-o FILE]
    .venv/bin/python bench/view_latency.py --neighbours-only     # the last measure alone, printed, not written

Starts `implgen view --no-browser --port 0` in its own process with an empty build cache, connects as the page
does, and for every example shape of degree <= 8, interleaved round by round, measures:
  - new equation: from sending the edit to the first (coarse) picture; the equation is one the cache has never
    seen (a tiny constant added), so it is generated, compiled (its .c and the glue) and linked;
  - cached equation: the same edit sent again (generated code, objects and library all in the cache);
  - orbit: coarse frames per second while turning, each request sent when the previous frame has arrived;
  - refinement: from the coarse frame to the full 640 x 480, 4 samples per pixel frame of a resting view.
Then, with heavy neighbours (project issue 22): one page orbits while three other pages keep sending
`(x+y+z+a+b+1)^15` with a new constant each time (seconds of SymPy, then a build), and the orbiting page's
frames per second and its longest wait for a frame are measured.
Prints the medians and writes them, with the machine, to the results file.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from websockets.exceptions import ConnectionClosed
from websockets.sync.client import connect

from implgen.bench.machine import describe as machine
from implgen.bench.machine import write_results
from implgen.codegen.spec import load_spec
from implgen.view.dump import spec_mapping
from implgen.view.session import HEADER, KIND_COARSE, KIND_FULL, MAX_RENDERS_PER_SECOND

ROOT = Path(__file__).resolve().parents[1]
SHAPES = ROOT / "examples" / "shapes"
MAX_DEGREE = 8
WIDTH, HEIGHT = 640, 480


class Page:
    """The page's side of the protocol, with a clock."""

    def __init__(self, url: str):
        self.ws = connect(url, max_size=64 * 2**20)
        self.hello = json.loads(self.ws.recv())
        self.seq = 0
        self.orbit = dict(self.hello["orbit"])
        self.options = dict(self.hello["options"])
        self.values = dict(self.hello["values"])

    def send(self, msg: dict) -> None:
        self.ws.send(json.dumps(msg))

    def render(self, refine: bool) -> int:
        self.seq += 1
        self.send(
            {
                "type": "render",
                "seq": self.seq,
                "refine": refine,
                "width": WIDTH,
                "height": HEIGHT,
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
                s, k, _, _ = HEADER.unpack(msg[: HEADER.size])
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
    frames, longest = 0, 0.0
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        good.orbit["yaw"] = (good.orbit["yaw"] + 3.0) % 360.0
        t0 = time.perf_counter()
        good.frame(good.render(False), KIND_COARSE)
        longest = max(longest, time.perf_counter() - t0)
        frames += 1
    elapsed = time.perf_counter() - start
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
        "Coarse frames are 160×120 at 1 sample per pixel (JPEG), refined frames 640×480 at 4 (PNG); the studio "
        "light preset (two lights, so two shadow rays per hit), clipped to a ball (a CSG intersection). The "
        f"server starts at most {MAX_RENDERS_PER_SECOND} renders a second per page, which caps the orbit rate.",
        "",
    ]
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
    write_results(args.output, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
