"""`implgen view`'s Save mesh beside a page that orbits: does a mesh on the save pool (NumPy work in Python, which
holds the GIL part of the time) take frames from the other pages?

    nice .venv/bin/python bench/view_mesh.py [--rounds 5] [--seconds 6] [-o bench/results/view_mesh.md]

Starts `implgen view --no-browser --port 0` in its own process (the starter torus). One page orbits, each render
request sent when the previous coarse frame has arrived, for --seconds; in the `meshing` rounds a second page
meshes Chmutov's octic at MESH_CELLS cells again and again meanwhile; in the `apart` rounds the same meshes are
made by `implgen mesh` in a process of its own (the same work on the CPU, no share of the server's GIL); `quiet`
rounds have neither. Rounds interleave (quiet, meshing, apart, quiet, ...). Per round: the orbiting page's
coarse frames a second and its longest wait for a frame; the medians over rounds; the meshes finished and
their median time.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from view_latency import Page, start_server  # the page's side of the protocol, the server (view_latency.py)
from websockets.exceptions import ConnectionClosed

from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results
from implgen.view.session import KIND_COARSE

ROOT = Path(__file__).resolve().parents[1]
MESH_CELLS = 128
OCTIC = ROOT / "examples" / "shapes" / "chmutov8.yaml"


def mesher(url: str, stop: threading.Event, times: list[float], ready: threading.Event) -> None:
    """A page that sends the octic, then saves its mesh again and again until `stop`."""
    import yaml

    spec = yaml.safe_load(OCTIC.read_text())
    page = Page(url)
    page.send({"type": "shape", "equation": spec["equation"], "bounds": spec["bounds"], "params": {}})
    page.reply()
    ready.set()
    try:
        while not stop.is_set():
            t0 = time.perf_counter()
            page.send({"type": "save_mesh", "cells": MESH_CELLS, "values": {}, "options": page.options})
            while True:
                msg = page.ws.recv()
                if isinstance(msg, str) and json.loads(msg).get("state") in ("done", "failed", "stopped"):
                    state = json.loads(msg)
                    if state["state"] != "done":
                        raise RuntimeError(state["text"])
                    times.append(time.perf_counter() - t0)
                    break
    except ConnectionClosed:
        return
    finally:
        page.ws.close()


def apart(stop: threading.Event, times: list[float], ready: threading.Event, folder: Path) -> None:
    """The same meshes by `implgen mesh` in its own process, again and again until `stop`."""
    cmd = [sys.executable, "-m", "implgen.cli", "mesh", str(OCTIC), "--cells", str(MESH_CELLS), "--no-singular"]
    ready.set()
    while not stop.is_set():
        t0 = time.perf_counter()
        subprocess.run([*cmd, "-o", str(folder / "octic.stl")], check=True, capture_output=True)
        times.append(time.perf_counter() - t0)


def orbit(url: str, seconds: float, kind: str, folder: Path) -> dict[str, float]:
    good = Page(url)
    good.frame(good.render(False), KIND_COARSE)  # built before the measure
    stop, ready, times = threading.Event(), threading.Event(), []
    other = None
    if kind != "quiet":
        work = mesher if kind == "meshing" else apart
        args = (url, stop, times, ready) if kind == "meshing" else (stop, times, ready, folder)
        other = threading.Thread(target=work, args=args, daemon=True)
        other.start()
        ready.wait(120)
        time.sleep(0.5)  # its first mesh under way
    frames, longest, elapsed = good.orbit_for(seconds)
    stop.set()
    if other is not None:
        other.join(120)
    good.ws.close()
    return {"fps": frames / elapsed, "longest": longest, "meshes": len(times), "mesh_seconds": times}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=6.0)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "view_mesh.md")
    args = ap.parse_args()
    load_before = load_average()
    server, url = start_server(dict(os.environ), None)
    runs: dict[str, list[dict]] = {"quiet": [], "meshing": [], "apart": []}
    folder = Path(tempfile.mkdtemp(prefix="implgen-bench-view-mesh-"))
    try:
        orbit(url, 1.0, "quiet", folder)  # the starter built
        for r in range(args.rounds):
            for kind in runs:
                got = orbit(url, args.seconds, kind, folder)
                runs[kind].append(got)
                print(f"round {r + 1} {kind}: {got['fps']:.1f} frames/s, longest wait {got['longest']:.3f} s, "
                      f"{got['meshes']} meshes", flush=True)  # fmt: skip
    finally:
        server.kill()
        server.wait(30)
        shutil.rmtree(folder, ignore_errors=True)
    rows = []
    for kind, got in runs.items():
        fps = statistics.median(g["fps"] for g in got)
        longest = statistics.median(g["longest"] for g in got)
        worst = max(g["longest"] for g in got)
        times = [t for g in got for t in g["mesh_seconds"]]
        mesh = f"{len(times)}, median {statistics.median(times):.2f} s" if times else "none"
        rows.append(f"| {kind} | {fps:.1f} | {longest:.3f} | {worst:.3f} | {mesh} |")
    quiet = statistics.median(g["fps"] for g in runs["quiet"])
    ratios = {k: statistics.median(g["fps"] for g in runs[k]) / quiet for k in ("meshing", "apart")}
    text = "\n".join(
        [
            "# `implgen view`: a page's frames while another page saves a mesh",
            "",
            f"Machine: {machine()}; load average {load_before} before the run, {load_average()} after.",
            f"Written by `bench/view_mesh.py --rounds {args.rounds} --seconds {args.seconds:g}`: one page orbits the "
            f"starter torus (coarse frames, each request sent when the previous frame has arrived) while, in the "
            f"`meshing` rounds, a second page saves Chmutov's octic at {MESH_CELLS} cells again and again, and in the "
            "`apart` rounds `implgen mesh --no-singular` makes the same mesh again and again in its own process; "
            "rounds interleaved.",
            "",
            "| rounds | coarse frames/s (median) | longest wait for a frame (median) | longest wait (worst round) "
            "| meshes finished |",
            "|---|---|---|---|---|",
            *rows,
            "",
            f"Frames a second over quiet: {ratios['meshing']:.2f} while the server meshes, {ratios['apart']:.2f} while "
            "a process of its own makes the same meshes.",
            "",
        ]
    )
    print(text)
    write_results(args.output, text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
