"""bench/floor.py: the instrumented build records the rays a render traces, and only that build does; the report's
form (no timing is checked)."""

from __future__ import annotations

import argparse
import ctypes
from pathlib import Path

import floor
import numpy as np

from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene

ROOT = Path(__file__).resolve().parent.parent
TORUS = ROOT / "bench" / "scenes" / "torus.yaml"
SIZE = argparse.Namespace(width=24, height=18, spp=1)


def _render_stats(sc) -> dict[str, float]:
    cs = CScene(sc, build_scene(sc))
    try:
        with RenderJob(cs, SIZE.width, SIZE.height, SIZE.spp, sc.max_depth, 1) as job:
            job.run()
            return job.stats().rays
    finally:
        cs.close()


def test_the_recorded_queries_are_the_rays_the_render_counts() -> None:
    """One query per ray, of the kind the render's own ray counts give it."""
    sc = load_scene(TORUS)
    rec = floor.record(sc, SIZE)
    rays = _render_stats(sc)
    for k, kind in enumerate(floor.KINDS):
        assert np.count_nonzero(rec.qi[:, 0] == k) == rays[kind], kind
    assert rays["primary"] == SIZE.width * SIZE.height and rays["shadow"] > 0


def test_the_recorded_roots_lie_on_the_torus_inside_its_clipped_range() -> None:
    """Each box entry of the torus that found a root: the root is in the entry's range and, unless it came from a
    yes/no shadow solve (mode 2, which may leave it unrefined), the object-space point there is on the torus by its
    equation, written out here."""
    sc = load_scene(TORUS)
    rec = floor.record(sc, SIZE)
    counts = rec.si[:, 3]
    starts = np.cumsum(counts) - counts
    a, b = 1.0, 0.3  # the scene's params
    checked = 0
    for e in np.nonzero((rec.si[:, 2] != 3) & (counts > 0))[0]:  # 3: the plane's own path
        o, u, lo, hi = rec.sd[e, :3], rec.sd[e, 3:6], rec.sd[e, 6], rec.sd[e, 7]
        r = rec.roots[starts[e]]
        assert lo <= r <= hi
        if rec.si[e, 2] == 2:
            continue
        x, y, z = o + r * u
        q = x * x + y * y + z * z
        f = q * q - 2 * (a * a + b * b) * q + 4 * a * a * y * y + (a * a - b * b) ** 2
        assert abs(f) < 1e-9, (e, f)
        checked += 1
    assert checked > 20


def test_the_ordinary_build_has_no_recorder() -> None:
    """The hooks are compiled in only with -DRT_TRACE: the library every render uses has none of it."""
    sc = load_scene(TORUS)
    plain = ctypes.CDLL(str(build_scene(sc).library))
    traced = ctypes.CDLL(str(build_scene(sc, extra_flags=floor.TRACE_FLAGS).library))
    assert not hasattr(plain, "rt_trace_new") and hasattr(traced, "rt_trace_new")
    assert hasattr(plain, "rt_floor_time") and hasattr(plain, "rt_replay_time")


def test_the_report_has_a_row_per_scene_and_per_ray_kind(tmp_path: Path) -> None:
    out = tmp_path / "floor.md"
    scenes = [TORUS, ROOT / "examples" / "scenes" / "glass_sphere.yaml"]
    args = ["--width", "24", "--height", "18", "--runs", "1", "-o", str(out)]
    floor.main([*map(str, scenes), *args])
    text = out.read_text()
    assert text.startswith("# The render loop against its floor\n\nWritten by `bench/floor.py --width 24")
    rows = [line.split("|")[1:3] for line in text.splitlines() if line.startswith("| ")]
    names = [r[0].strip() for r in rows]
    assert names == [
        "scene",
        "torus",
        "glass_sphere",
        "scene",
        "torus",
        "torus",
        "glass_sphere",
        "glass_sphere",
        "glass_sphere",
    ]
    assert [r[1].strip() for r in rows[-5:]] == ["primary", "shadow", "primary", "shadow", "secondary"]
