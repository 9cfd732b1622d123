"""Many frames, or the tiles of one still: rendered here or on Dask, written in order, resumable.

`render_frames` renders the frames of an animation that are not complete yet (a rerun skips them), one task
per frame, and writes each as soon as it and every frame before it are done. With tiles, each frame is K
bands of rows, one task each, stacked when all are back: each pixel's samples depend only on the pixel and
the seed (runtime_c/tracer_render.c), so the result is bit for bit the image rendered in one piece. A still
is an animation of one frame.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from implgen.animation import cluster
from implgen.animation.frameout import FrameOutput, Made
from implgen.animation.frames import FrameOptions, Frames, render_frame_png
from implgen.errors import UserError
from implgen.imagefile import decode_png, encode_png
from implgen.scene.build import build_scene


def _say(text: str) -> None:
    print(f"implgen: {text}", file=sys.stderr, flush=True)


@dataclass
class Runner:
    """Where tasks run: `client` None is this process. `label` names the option that chose the cluster in
    messages; `say` is told what the run waits for (no workers yet)."""

    client: Any = None
    retries: int = 3
    task: Callable[..., bytes] = render_frame_png  # the unit of work; tests wrap it to inject faults
    label: str = "--cluster"
    say: Callable[[str], None] = _say

    def workers(self) -> int:
        """Workers the cluster has now (1 for this process)."""
        if self.client is None:
            return 1
        return len(self.client.nthreads())

    def results(self, jobs: Iterator[tuple[Any, tuple]], name: str) -> Iterator[tuple[Any, bytes]]:
        if self.client is None:
            return cluster.serial(self.task, jobs)
        return cluster.ordered(self.client, self.task, jobs, retries=self.retries, name=name, say=self.say)


@dataclass
class BatchReport:
    written: list[int]
    skipped: list[int]
    seconds: float
    bytes_moved: int  # PNG bytes that came back from the tasks
    replaced: list[int] = field(default_factory=list)  # frames there, made otherwise: rendered again
    replaced_why: str = ""


def render_frames(
    frames: Frames,
    todo: range,
    opts: FrameOptions,
    out: FrameOutput,
    runner: Runner,
    *,
    tiles: int = 1,
    fold: bool = False,
    progress: bool = False,
    keep_frames: bool = False,
    on_written: Callable[[int], None] | None = None,
) -> BatchReport:
    """Render the frames of `todo` whose output is missing, each as one task or as `tiles` bands of rows,
    write them in order, then finish the output (encode a video or GIF from all frames of `todo`)."""
    t0 = time.perf_counter()
    out.check_fps(frames.fps, frames.source)
    made = Made(frames.digest(), opts.width, opts.height, opts.spp, opts.max_depth, opts.seed, fold)
    claim = out.claim(made, todo)  # frames made by other settings are removed here, or the run refused
    skipped = [f for f in todo if out.done(f, made)]
    missing = [f for f in todo if f not in skipped]
    out.prepare()
    written: list[int] = []
    moved = 0
    if missing:
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=len(missing), unit="frame", desc=out.target.name, leave=True)
        try:
            rows = [None] if tiles == 1 else bands(opts.height, tiles)
            results = runner.results(_jobs(frames, missing, rows, opts, runner, fold), name="frame")
            for f, png, nbytes in _assembled(results, len(rows)):
                try:
                    out.write(f, png)
                except OSError as err:  # a full disk, a folder removed meanwhile: one line, frames so far kept
                    raise UserError(f"-o {out.target}", f"cannot write frame {f}: {err.strerror or err}") from None
                written.append(f)
                moved += nbytes
                if bar is not None:
                    bar.update(1)
                if on_written is not None:
                    on_written(f)
        except cluster.SchedulerLost:
            n = len(written) + len(skipped)
            where = getattr(runner.client.scheduler, "address", "")
            raise UserError(
                runner.label,
                f"lost the Dask scheduler{' at ' + where if where else ''} with {n} frames written (kept: "
                "the same command again renders the rest)",
            ) from None
        finally:
            if bar is not None:
                bar.close()
    out.finish(list(todo), frames.fps, keep_frames=keep_frames)
    seconds = time.perf_counter() - t0
    return BatchReport(written, skipped, seconds, moved, replaced=claim.replaced, replaced_why=claim.why)


def _jobs(
    frames: Frames, missing: list[int], rows: list, opts: FrameOptions, runner: Runner, fold: bool
) -> Iterator[tuple[tuple[int, int], tuple]]:
    """((frame, band), task arguments) for each band of each missing frame, made as they are needed. In this
    process the library is built once and shared by every frame; a Dask worker builds it through its cache."""
    built = build_scene(frames.first, fold=fold) if runner.client is None else None
    for f in missing:
        scene = frames.scene(f)
        frame_built = None if built is None else built.for_scene(scene, fold)
        for k, band in enumerate(rows):
            yield (f, k), (scene, opts, band, frame_built)


def _assembled(results: Iterator[tuple[tuple[int, int], bytes]], nbands: int) -> Iterator[tuple[int, bytes, int]]:
    """(frame, PNG, bytes moved) from the tasks' results in order: one PNG per frame, or its bands stacked.
    Each pixel's samples depend only on the pixel, so the stacked bands are the one-piece image bit for bit."""
    parts: list[np.ndarray] = []
    nbytes = 0
    for (f, k), png in results:
        if nbands == 1:
            yield f, png, len(png)
            continue
        parts.append(decode_png(png))
        nbytes += len(png)
        if k == nbands - 1:
            yield f, encode_png(np.concatenate(parts, axis=0)), nbytes
            parts, nbytes = [], 0


def bands(height: int, k: int) -> list[tuple[int, int]]:
    """K bands of rows [y0, y1) covering the image, sizes differing by at most one row (K <= height)."""
    edges = [i * height // k for i in range(k + 1)]
    return [(edges[i], edges[i + 1]) for i in range(k)]
