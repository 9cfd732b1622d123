"""Each scene's render loop against its floor: what the same rays cost at the least, with the same compiled code.

    .venv/bin/python bench/floor.py [SCENE.yaml ...] [--width 400 --height 300] [--runs 5] [-o bench/results/floor.md]

The floor of a render is, for every ray that enters a shape's box, the ray polynomial's coefficients (the shape's
generated `_coeffs` at the point the solve expands around) and one Newton step at each root the solve kept: the
arithmetic no intersector of that shape can avoid. To know those rays, each scene is rendered once (one thread)
with an instrumented build of its library (-DRT_TRACE: runtime_c/tracer_floor.c records every scene query and
every leaf solve whose ray enters the leaf's box, with the ray's kind); the ordinary build, whose render loop has
no recording in it, then times, interleaved round by round:

  render  the render loop (rt_render_run, one thread, as `implgen bench render` runs it);
  floor   the coefficients and Newton steps of the recorded box entries, all and per ray kind;
  query   the recorded scene queries replayed through rt_scene_closest, per ray kind: the hit finding of that
          kind, without the shading (normals, error bounds, colours) that the render loop adds.

Reported: render/floor per scene, query/floor per ray kind (primary, shadow, secondary: reflected and refracted),
and how many rays of each kind entered a box. Every figure is CPU time (the render's process, the floor's and the
queries' thread), so that another process's share of a busy machine is not counted; medians of --runs rounds; the
machine and its load are named.
Default scenes: bench/scenes/*.yaml and examples/scenes/*.yaml at 400x300 (a smaller picture than `implgen bench
render`'s 800x600 keeps the records, about 100 bytes a box entry, small), 1 sample per pixel.
"""

from __future__ import annotations

import argparse
import ctypes
import statistics
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from implgen.measure.machine import describe, load_average, write_results
from implgen.measure.render import _measure
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.model import Scene
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene

ROOT = Path(__file__).resolve().parents[1]
KINDS = ("primary", "shadow", "secondary")
TRACE_FLAGS = ("-DRT_TRACE",)
_vp, _l, _i, _d = ctypes.c_void_p, ctypes.c_long, ctypes.c_int, ctypes.c_double


def _ptr(a: np.ndarray, ctype) -> ctypes._Pointer:
    return a.ctypes.data_as(ctypes.POINTER(ctype))


@dataclass
class Records:
    """What the instrumented render recorded: queries (qi: kind, mode, skip; qd: o, d, tmin, tmax) and box entries
    (si: kind, leaf, mode, root count; sd: o, u, lo, hi), with the entries' roots one after the other."""

    qi: np.ndarray
    qd: np.ndarray
    si: np.ndarray
    sd: np.ndarray
    roots: np.ndarray

    def of_kind(self, k: int) -> Records:
        """The records of one ray kind, contiguous (timing a kind does not walk through the others' records)."""
        q, s = self.qi[:, 0] == k, self.si[:, 0] == k
        counts = self.si[:, 3]
        starts = np.cumsum(counts) - counts
        take = np.concatenate([np.arange(a, a + n) for a, n in zip(starts[s], counts[s])] or [np.zeros(0, int)])
        roots = self.roots[take] if len(take) else np.zeros(1)
        return Records(self.qi[q].copy(), self.qd[q].copy(), self.si[s].copy(), self.sd[s].copy(), roots)


def _bind_trace(lib: ctypes.CDLL) -> None:
    for name, res, args in (
        ("rt_trace_new", _vp, []),
        ("rt_trace_free", None, [_vp]),
        ("rt_trace_attach", None, [_vp, _vp]),
        ("rt_trace_sizes", None, [_vp, ctypes.POINTER(_l)]),
        ("rt_trace_copy", None, [_vp] + [ctypes.POINTER(t) for t in (_i, _d, _i, _d, _d)]),
    ):
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args


def _bind_floor(lib: ctypes.CDLL) -> None:
    pi, pd = ctypes.POINTER(_i), ctypes.POINTER(_d)
    lib.rt_floor_time.restype = _d
    lib.rt_floor_time.argtypes = [_vp, _l, pi, pd, pd, _i, pd]
    lib.rt_replay_time.restype = _d
    lib.rt_replay_time.argtypes = [_vp, _l, pi, pd, _i, ctypes.POINTER(_l)]


def record(sc: Scene, size: argparse.Namespace) -> Records:
    """The rays of one render of sc, recorded by the instrumented build (one thread: the log is not shared)."""
    cs = CScene(sc, build_scene(sc, extra_flags=TRACE_FLAGS))
    lib = cs.lib
    _bind_trace(lib)
    log = lib.rt_trace_new()
    if not log:
        raise MemoryError("rt_trace_new failed")
    try:
        lib.rt_trace_attach(cs.ptr, log)
        with RenderJob(cs, size.width, size.height, size.spp, sc.max_depth, 1) as job:
            if job.run() is None:
                raise RuntimeError("the recording render failed")
        n = (_l * 3)()
        lib.rt_trace_sizes(log, n)
        rec = Records(
            np.zeros((n[0], 3), np.intc),
            np.zeros((n[0], 8)),
            np.zeros((n[1], 4), np.intc),
            np.zeros((n[1], 8)),
            np.zeros(max(1, n[2])),
        )
        lib.rt_trace_copy(log, *(_ptr(a, t) for a, t in zip(vars(rec).values(), (_i, _d, _i, _d, _d))))
        return rec
    finally:
        lib.rt_trace_attach(cs.ptr, None)
        lib.rt_trace_free(log)
        cs.close()


def _floor(cs: CScene, rec: Records) -> float:
    sink = _d()
    args = (_ptr(rec.si, _i), _ptr(rec.sd, _d), _ptr(rec.roots, _d))
    return cs.lib.rt_floor_time(cs.ptr, len(rec.si), *args, -1, ctypes.byref(sink))


def _replay(cs: CScene, rec: Records) -> float:
    found = _l()
    return cs.lib.rt_replay_time(cs.ptr, len(rec.qi), _ptr(rec.qi, _i), _ptr(rec.qd, _d), -1, ctypes.byref(found))


def measure(sc: Scene, rec: Records, size: argparse.Namespace, runs: int) -> dict[str, float]:
    """Medians over `runs` interleaved rounds: render, floor (all and per kind), query per kind, in CPU seconds."""
    cs = CScene(sc, build_scene(sc))
    _bind_floor(cs.lib)
    times: dict[str, list[float]] = {}
    kinds = [rec.of_kind(k) for k in range(len(KINDS))]
    try:
        _measure(cs, sc, size, 1)  # warm
        for _ in range(max(1, runs)):
            got = {"render": _measure(cs, sc, size, 1)[1], "floor": _floor(cs, rec)}
            for name, sub in zip(KINDS, kinds):
                got[f"floor {name}"] = _floor(cs, sub)
                got[f"query {name}"] = _replay(cs, sub)
            for key, v in got.items():
                times.setdefault(key, []).append(v)
    finally:
        cs.close()
    return {k: statistics.median(v) for k, v in times.items()}


def _ratio(a: float, b: float) -> str:
    return f"{a / b:.1f}" if b > 0 else "-"


def scene_rows(name: str, rec: Records, t: dict[str, float]) -> tuple[str, list[str]]:
    """The scene's line of the summary and its lines of the per-kind table."""
    entries = len(rec.si)
    summary = (
        f"| {name} | {t['render'] * 1e3:.1f} | {t['floor'] * 1e3:.2f} | {_ratio(t['render'], t['floor'])} | "
        f"{len(rec.qi)} | {entries} |"
    )
    rows = []
    for k, kind in enumerate(KINDS):
        queries = int(np.count_nonzero(rec.qi[:, 0] == k))
        if not queries:
            continue
        mine = rec.si[:, 0] == k
        q, f = t[f"query {kind}"], t[f"floor {kind}"]
        rows.append(
            f"| {name} | {kind} | {queries} | {int(np.count_nonzero(mine))} | {int(rec.si[mine, 3].sum())} | "
            f"{q * 1e3:.2f} | {f * 1e3:.3f} | {_ratio(q, f)} |"
        )
    return summary, rows


def report(args: argparse.Namespace, results: list[tuple[str, Records, dict[str, float]]], before: str) -> str:
    summaries, kinds = [], []
    for name, rec, t in results:
        s, rows = scene_rows(name, rec, t)
        summaries.append(s)
        kinds.extend(rows)
    return "\n".join(
        [
            "# The render loop against its floor",
            "",
            f"Written by `bench/floor.py --width {args.width} --height {args.height} --spp {args.spp} --runs "
            f"{args.runs}` on {describe()}. Load average before: {before}; after: {load_average()}. CPU time, medians "
            f"of {args.runs} interleaved rounds, one thread. Floor: for every ray that enters a shape's box, the ray "
            "polynomial's coefficients and one Newton step per root kept (bench/floor.py explains).",
            "",
            "| scene | render ms | floor ms | render/floor | queries | box entries |",
            "|---|---:|---:|---:|---:|---:|",
            *summaries,
            "",
            "Per ray kind: the recorded queries of that kind replayed through rt_scene_closest (hit finding only, no "
            "shading) against the floor of that kind's box entries.",
            "",
            "| scene | kind | queries | box entries | roots | query ms | floor ms | query/floor |",
            "|---|---|---:|---:|---:|---:|---:|---:|",
            *kinds,
        ]
    )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--width", type=int, default=400)
    ap.add_argument("--height", type=int, default=300)
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "floor.md")
    args = ap.parse_args(argv)
    paths = args.scenes or sorted((ROOT / "bench" / "scenes").glob("*.yaml")) + sorted(
        (ROOT / "examples" / "scenes").glob("*.yaml")
    )
    before = load_average()
    results = []
    for path in paths:
        sc = load_scene(path)
        rec = record(sc, args)
        t = measure(sc, rec, args, args.runs)
        results.append((path.stem, rec, t))
        print(f"{path.stem}: render {t['render'] * 1e3:.1f} ms, floor {t['floor'] * 1e3:.2f} ms", flush=True)
    text = report(args, results, before) + "\n"
    print(text)
    write_results(args.output, text)
    print(f"wrote {args.output}")


if __name__ == "__main__":
    main()
