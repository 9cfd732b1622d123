"""Many frames, or the tiles of one still: rendered here or on Dask, written in order, resumable.

`render_frames` renders the frames of an animation that are not complete yet (a rerun skips them), one task
per frame, and writes each as soon as it and every frame before it are done. `render_tiles` splits one image
into K bands of rows, one task each, and assembles them: each pixel's samples depend only on the pixel and
the seed (runtime_c/tracer_render.c), so the result is bit for bit the image rendered in one piece.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from implgen.scene import cluster
from implgen.scene.build import build_scene
from implgen.scene.frameout import FrameOutput
from implgen.scene.frames import FrameOptions, Frames, decode_png, encode_png, rebind, render_frame_png

WINDOW_PER_WORKER = 3  # tasks in flight per worker: enough to hide the round trip, little memory


@dataclass
class Runner:
    """Where tasks run: `client` None is this process."""

    client: Any = None
    retries: int = 3
    task: Callable[..., bytes] = render_frame_png  # the unit of work; tests wrap it to inject faults

    def workers(self) -> int:
        """Workers the cluster has now (1 for this process)."""
        if self.client is None:
            return 1
        return len(self.client.scheduler_info(n_workers=-1).get("workers", {})) or 1

    def window(self) -> int:
        return 1 if self.client is None else WINDOW_PER_WORKER * self.workers()

    def results(self, jobs: Iterator[tuple[int, tuple]], name: str) -> Iterator[tuple[int, bytes]]:
        if self.client is None:
            return cluster.serial(self.task, jobs)
        return cluster.ordered(self.client, self.task, jobs, window=self.window(), retries=self.retries, name=name)


@dataclass
class BatchReport:
    written: list[int]
    skipped: list[int]
    seconds: float
    bytes_moved: int  # PNG bytes that came back from the tasks


def render_frames(
    frames: Frames,
    todo: range,
    opts: FrameOptions,
    out: FrameOutput,
    runner: Runner,
    *,
    fold: bool = False,
    progress: bool = False,
    keep_frames: bool = False,
    on_written: Callable[[int], None] | None = None,
) -> BatchReport:
    """Render the frames of `todo` whose output is missing, write them in order, then finish the output
    (encode a video or GIF from all frames of `todo`)."""
    t0 = time.perf_counter()
    skipped = [f for f in todo if out.done(f)]
    missing = [f for f in todo if not out.done(f)]
    out.prepare()
    written: list[int] = []
    moved = 0
    if missing:
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=len(missing), unit="frame", desc=out.target.name, leave=True)
        try:
            for f, png in runner.results(_frame_jobs(frames, missing, opts, runner, fold), name="frame"):
                out.write(f, png)
                written.append(f)
                moved += len(png)
                if bar is not None:
                    bar.update(1)
                if on_written is not None:
                    on_written(f)
        finally:
            if bar is not None:
                bar.close()
    out.finish(list(todo), frames.fps, keep_frames=keep_frames)
    return BatchReport(written=written, skipped=skipped, seconds=time.perf_counter() - t0, bytes_moved=moved)


def _frame_jobs(
    frames: Frames, missing: list[int], opts: FrameOptions, runner: Runner, fold: bool
) -> Iterator[tuple[int, tuple]]:
    """(frame, task arguments) for each missing frame, made as they are needed. In this process the library
    is built once and shared by every frame; a Dask worker builds it through its own cache."""
    built = build_scene(frames.first, fold=fold) if runner.client is None else None
    for f in missing:
        scene = frames.scene(f)
        if built is None:
            yield f, (scene, opts)
        else:
            yield f, (scene, opts, None, rebind(built, scene, fold))


def bands(height: int, k: int) -> list[tuple[int, int]]:
    """K bands of rows [y0, y1) covering the image, sizes differing by at most one row."""
    edges = [i * height // k for i in range(k + 1)]
    return [(edges[i], edges[i + 1]) for i in range(k) if edges[i] < edges[i + 1]]


def render_tiles(frames: Frames, frame: int, opts: FrameOptions, k: int, runner: Runner) -> tuple[bytes, int]:
    """One image rendered as K bands of rows and assembled: (PNG bytes, PNG bytes moved by the tasks)."""
    scene = frames.scene(frame)
    built = build_scene(scene) if runner.client is None else None
    jobs = ((i, (scene, opts, rows, built)) for i, rows in enumerate(bands(opts.height, k)))
    parts: list[np.ndarray] = []
    moved = 0
    for _, png in runner.results(jobs, name="tile"):
        parts.append(decode_png(png))
        moved += len(png)
    image = np.concatenate(parts, axis=0)
    assert image.shape == (opts.height, opts.width, 3)
    return encode_png(image), moved
