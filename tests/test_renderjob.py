"""scene/renderjob.py: the one Python owner of the C render context (rt_render). Its image is render()'s bit
for bit, its counts are the C loop's, and it is freed on exit whatever happens: a cancel from another thread,
an exception while the run is still going on a worker thread (cancelled and waited for, not freed under it)."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import pytest

from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.render import render
from implgen.scene.renderjob import PIXELS_ALL, PIXELS_EVEN, PIXELS_ODD, RenderJob
from implgen.scene.tracer import CScene

ROOT = Path(__file__).resolve().parent.parent
W, H = 37, 23


@pytest.fixture(scope="module")
def trio():
    sc = load_scene(ROOT / "examples" / "scenes" / "csg_trio.yaml")
    cs = CScene(sc, build_scene(sc))
    yield sc, cs
    cs.close()


@pytest.fixture(scope="module")
def slow():
    """A scene whose render at 1 thread takes long enough to be caught running (about 3.5 s at 480x360; the
    tests cancel it after a row or two)."""
    sc = load_scene(ROOT / "examples" / "scenes" / "glassware.yaml")
    cs = CScene(sc, build_scene(sc))
    yield sc, cs
    cs.close()


def test_the_image_and_counts_are_renders(trio) -> None:
    sc, cs = trio
    with RenderJob(cs, W, H, 2, 4, 3, seed=7) as job:
        img = job.run()
        assert img is not None and img.shape == (H, W, 3) and img.dtype == np.float32
        assert job.progress() == H and job.seconds > 0
        stats = job.stats()
    assert np.array_equal(img, render(sc, width=W, height=H, spp=2, max_depth=4, threads=1, seed=7))
    assert stats.rays["primary"] == W * H * 2 and stats.nonfinite == 0
    assert job.progress() == 0 and job.stats().rays["primary"] == 0  # freed: nothing left to ask


def test_a_band_of_rows(trio) -> None:
    sc, cs = trio
    whole = render(sc, width=W, height=H, spp=1, max_depth=4, threads=2)
    with RenderJob(cs, W, H, 1, 4, 2, rows=(5, 12)) as job:
        band = job.run()
        assert job.rows == (5, 12) and job.progress() == 7 and job.stats().rays["primary"] == W * 7
    assert np.array_equal(band, whole[5:12])
    with pytest.raises(RuntimeError, match="rt_render_set_rows"), RenderJob(cs, W, H, 1, 4, 2, rows=(5, 99)):
        pass


def test_cancelled_before_the_run_renders_nothing(trio) -> None:
    _, cs = trio
    with RenderJob(cs, W, H, 1, 4, 2) as job:
        job.cancel()
        assert job.run() is None
        assert np.array_equal(job.image, np.zeros_like(job.image)) and job.stats().rays["primary"] == 0


def test_one_run_per_job_and_only_inside_the_block(trio) -> None:
    _, cs = trio
    job = RenderJob(cs, W, H, 1, 4, 1)
    with job:
        job.run()
        with pytest.raises(RuntimeError, match="runs once"):
            job.run()
    with pytest.raises(RuntimeError, match="runs once"):
        RenderJob(cs, W, H, 1, 4, 1).run()
    job.cancel()  # after the block: does nothing


def test_passes_make_the_whole_render_bit_for_bit(trio) -> None:
    """The viewer's ladder: sample 0 of the pixels with even x and y (a half-size picture), of the others (the
    whole picture at 1 sample), then samples 1 to 3 added: render()'s 4-sample image, bit for bit."""
    sc, cs = trio
    whole = render(sc, width=W, height=H, spp=4, max_depth=4, threads=2, seed=5)
    with RenderJob(cs, W, H, 4, 4, 2, seed=5) as job:
        quarter = job.run_pass(0, 1, PIXELS_EVEN)[::2, ::2].copy()
        assert job.stats().rays["primary"] == ((W + 1) // 2) * ((H + 1) // 2)
        one = job.run_pass(0, 1, PIXELS_ODD).copy()
        two = job.run_pass(1, 2).copy()
        last = job.run_pass(2, 4)
        assert job.stats().rays["primary"] == W * H * 4  # no sample rendered twice
    assert np.array_equal(last, whole)
    assert np.array_equal(quarter, one[::2, ::2])
    with RenderJob(cs, W, H, 4, 4, 1, seed=5) as job:  # sample 0 of every pixel in one pass: the same picture
        assert np.array_equal(job.run_pass(0, 1), one)
        assert np.array_equal(job.run_pass(1, 2), two)  # the mean of samples 0 and 1
    assert 0 < np.abs(two - one).max() and 0 < np.abs(last - two).max()


def test_passes_go_in_order(trio) -> None:
    _, cs = trio
    with RenderJob(cs, W, H, 4, 4, 1) as job:
        for k0, k1, pixels in ((1, 2, PIXELS_ALL), (0, 5, PIXELS_ALL), (0, 0, PIXELS_ALL), (0, 1, 7)):
            with pytest.raises(RuntimeError, match="out of order"):
                job.run_pass(k0, k1, pixels)
        job.run_pass(0, 1, PIXELS_EVEN)
        with pytest.raises(RuntimeError, match="out of order"):
            job.run_pass(1, 2)  # the odd pixels have no sample 0 yet
        with pytest.raises(RuntimeError, match="runs once"):
            job.run()
    with RenderJob(cs, W, H, 4, 4, 1) as job:
        job.run()
        with pytest.raises(RuntimeError, match="out of order"):
            job.run_pass(0, 1)


def _wait_for_rows(job: RenderJob, rows: int = 1) -> None:
    deadline = time.monotonic() + 60
    while job.progress() < rows:
        assert time.monotonic() < deadline
        time.sleep(0.002)


def test_cancel_from_another_thread_stops_the_run(slow) -> None:
    sc, cs = slow
    width, height = 480, 360
    with RenderJob(cs, width, height, 4, sc.max_depth, 1) as job:
        result: dict = {}
        worker = threading.Thread(target=lambda: result.update(img=job.run()))
        worker.start()
        _wait_for_rows(job)
        job.cancel()
        worker.join()
        reached = job.progress()
    assert result["img"] is None and 1 <= reached < height
    assert job.image[:reached].max() > 0 and not job.image[reached:].any()  # rows never reached: black


def test_leaving_the_block_while_running_cancels_and_waits(slow) -> None:
    """An exception inside the block while the run goes on on a worker thread: the exit cancels the run and
    waits for the C threads before freeing the context (else they would write through freed memory)."""
    sc, cs = slow
    result: dict = {}
    worker = None
    with pytest.raises(KeyError), RenderJob(cs, 480, 360, 4, sc.max_depth, 1) as job:
        worker = threading.Thread(target=lambda: result.update(img=job.run()))
        worker.start()
        _wait_for_rows(job)
        raise KeyError("the caller failed")
    assert job.seconds > 0  # set when rt_render_run returned: before the exit freed the context
    worker.join()
    assert result["img"] is None and job.progress() == 0
