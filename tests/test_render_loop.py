"""The threaded render loop (runtime_c/tracer_render.c) through its C API: every row is written whatever the
thread count, the ray counts do not depend on it, and a cancelled render leaves black the rows it never
reached (the output is not cleared before the threads start, so stale contents must not survive)."""

from __future__ import annotations

import ctypes
import os
from pathlib import Path

import numpy as np
import pytest

from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.tracer import CScene

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "examples" / "scenes" / "csg_trio.yaml"
W, H = 37, 23


@pytest.fixture(scope="module")
def scene() -> CScene:
    sc = load_scene(SCENE)
    return CScene(sc, build_scene(sc))


def run(
    cs: CScene, threads: int, spp: int = 2, cancel_first: bool = False, rows: tuple[int, int] = (0, H)
) -> tuple[int, np.ndarray, list, int]:
    ctx = cs.lib.rt_render_new(cs.ptr, W, H, spp, 4, threads, 7)
    assert ctx
    try:
        assert cs.lib.rt_render_set_rows(ctx, *rows) == 0
        out = np.full((rows[1] - rows[0], W, 3), np.nan, dtype=np.float32)  # stale: every pixel must be written
        if cancel_first:
            cs.lib.rt_render_cancel(ctx)
        code = cs.lib.rt_render_run(ctx, out.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))
        stats = (ctypes.c_double * 4)()
        cs.lib.rt_render_stats(ctx, stats)
        return code, out, list(stats), cs.lib.rt_render_progress(ctx)
    finally:
        cs.lib.rt_render_free(ctx)


def test_every_row_is_written_and_counts_do_not_depend_on_threads(scene: CScene) -> None:
    code, one, stats1, done1 = run(scene, 1)
    assert code == 0 and done1 == H and np.isfinite(one).all() and one.max() > 0
    assert stats1[0] == W * H * 2 and stats1[3] == 0  # primary rays: every sample of every pixel
    for threads in (2, 3, 8, 64):  # more threads than rows too
        code, img, stats, done = run(scene, threads)
        assert code == 0 and done == H
        assert np.array_equal(img, one)  # bit for bit: each pixel's samples depend on the pixel only
        assert stats == stats1


def test_a_cancelled_render_leaves_unreached_rows_black(scene: CScene) -> None:
    code, img, stats, done = run(scene, 2, cancel_first=True)
    assert code == 1 and done == 0
    assert np.array_equal(img, np.zeros_like(img)) and stats[0] == 0


def test_a_band_of_rows_is_those_rows_of_the_whole_image(scene: CScene) -> None:
    _, whole, _, _ = run(scene, 1)
    for threads in (1, 2, 5):
        code, band, _, done = run(scene, threads, rows=(5, 12))
        assert code == 0 and done == 7 and np.array_equal(band, whole[5:12])
    code, band, _, done = run(scene, 2, cancel_first=True, rows=(5, 12))
    assert code == 1 and done == 0 and np.array_equal(band, np.zeros_like(band))


@pytest.mark.skipif(not hasattr(os, "sched_getaffinity") or len(os.sched_getaffinity(0)) < 2, reason="one core")
def test_keeping_threads_on_their_cores_never_pins_the_caller(scene: CScene) -> None:
    """The render threads go one per allowed core; the thread that called the render keeps its own cores.
    (A worker done before it was pinned had no kernel thread left, and pinning it pinned the caller instead:
    every later render then ran all its threads on one core, half as fast.)"""
    allowed = os.sched_getaffinity(0)
    for _ in range(200):  # tiny renders: workers often finish before the last one is even started
        code = run(scene, len(allowed), spp=1, rows=(0, 2))[0]
        assert code == 0
        assert os.sched_getaffinity(0) == allowed
