"""Many frames, or the tiles of one still: rendered here or on Dask, written in order, resumable.

`render_frames` renders the frames of an animation that are not complete yet (a rerun skips them) in chunks of
frames in a row, one task per chunk (chunks.py: its size set as the chunks are handed out), and writes each
frame as soon as it and every frame before it are done (writer.py). With tiles, each frame is K bands of rows,
one task each, stacked when all are back: each pixel's samples depend only on the pixel and the seed
(runtime_c/tracer_render.c), so the result is bit for bit the image rendered in one piece. A still is an
animation of one frame.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from implgen.animation import cluster
from implgen.animation.chunks import ChunkResult, Pace, Part, lanes, local_results, render_chunk
from implgen.animation.frameout import FrameOutput, Made
from implgen.animation.frames import FrameOptions, Frames
from implgen.animation.writer import OrderedWriter
from implgen.errors import UserError
from implgen.imagefile import decode_png
from implgen.scene.render import usable_cores


def _say(text: str) -> None:
    print(f"implgen: {text}", file=sys.stderr, flush=True)


@dataclass
class Runner:
    """Where tasks run: `client` None is this process. `label` names the option that chose the cluster in
    messages; `say` is told what the run waits for (no workers yet). `chunk`: frames per task, fixed (None:
    chosen as the run goes, chunks.Pace)."""

    client: Any = None
    retries: int = 3
    task: Callable[..., ChunkResult] = render_chunk  # the unit of work; tests wrap it to inject faults
    label: str = "--cluster"
    say: Callable[[str], None] = _say
    chunk: int | None = None
    lanes: int = 1  # frames side by side in this process (set for each run: chunks.lanes)
    _threads: tuple[float, int] = field(default=(0.0, 1), init=False, repr=False)  # (when looked, threads then)

    def workers(self) -> int:
        """Workers the cluster has now (1 for this process)."""
        if self.client is None:
            return 1
        return len(self.client.nthreads())

    def threads(self) -> int:
        """Worker threads the scheduler has, looked up again at most every cluster.POLL seconds (here: the
        frames that render side by side)."""
        if self.client is None:
            return self.lanes
        when, n = self._threads
        if time.monotonic() - when >= cluster.POLL:
            n = cluster.slots(self.client)
            self._threads = (time.monotonic(), n)
        return n

    def results(self, jobs: Iterator[tuple[Any, tuple]], name: str) -> Iterator[tuple[Any, ChunkResult]]:
        if self.client is None:
            return local_results(self.task, jobs, self.lanes)
        return cluster.ordered(self.client, self.task, jobs, retries=self.retries, name=name, say=self.say)


@dataclass
class BatchReport:
    written: list[int]
    skipped: list[int]
    seconds: float
    bytes_moved: int  # PNG bytes that came back from Dask tasks (none in this process)
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
    """Render the frames of `todo` whose output is missing, in chunks of frames or as `tiles` bands of rows
    each, write them in order, then finish the output (encode a video or GIF from all frames of `todo`)."""
    t0 = time.perf_counter()
    out.check_fps(frames.fps, frames.source)
    made = Made(frames.digest(), opts.width, opts.height, opts.spp, opts.max_depth, opts.seed, fold)
    claim = out.claim(made, todo)  # frames made by other settings are removed here, or the run refused
    skipped = [f for f in todo if out.done(f, made)]
    done = set(skipped)
    missing = [f for f in todo if f not in done]
    out.prepare()
    written: list[int] = []
    moved = 0
    if missing:
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=len(missing), unit="frame", desc=out.target.name, leave=True)

        def wrote(frames_in_place: list[int]) -> None:
            for f in frames_in_place:
                written.append(f)
                if bar is not None:
                    bar.update(1)
                if on_written is not None:
                    on_written(f)

        try:
            moved = _render_and_write(frames, missing, opts, out, runner, tiles, fold, wrote)
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


def _render_and_write(
    frames: Frames,
    missing: list[int],
    opts: FrameOptions,
    out: FrameOutput,
    runner: Runner,
    tiles: int,
    fold: bool,
    wrote: Callable[[list[int]], None],
) -> int:
    """The tasks' frames through the writer, in order; the PNG bytes that came back from Dask."""
    rows = [None] if tiles == 1 else bands(opts.height, tiles)
    if runner.client is None:
        runner.lanes, opts = lanes(opts, usable_cores())
    pace = Pace(fixed=runner.chunk)
    writer = OrderedWriter(out)
    results = runner.results(_jobs(frames, missing, rows, opts, runner, fold, pace), name="frame")
    moved = 0
    try:
        for f, image, nbytes in _assembled(results, len(rows), pace):
            moved += nbytes
            wrote(writer.put(f, image))
        wrote(writer.close())
    except cluster.SchedulerLost:
        wrote(writer.close())  # the frames that came back are whole: they are kept
        raise
    finally:
        results.close()
        writer.abandon()
    return moved


def _jobs(
    frames: Frames, missing: list[int], rows: list, opts: FrameOptions, runner: Runner, fold: bool, pace: Pace
) -> Iterator[tuple[Part, tuple]]:
    """(part, task arguments) for each chunk of missing frames, or each band of each missing frame, made as
    they are needed (a chunk's size is chosen then). Tasks on Dask return PNG bytes (what crosses the wire),
    tasks here 8-bit pixels (the writer's threads encode them)."""
    encode = runner.client is not None
    if len(rows) > 1:
        for f in missing:
            scene = frames.scene(f)
            for k, band in enumerate(rows):
                yield Part((f,), k), ((scene,), opts, band, fold, encode)
        return
    i = 0
    while i < len(missing):
        group = missing[i : i + pace.size(len(missing) - i, runner.threads())]
        i += len(group)
        yield Part(tuple(group)), (tuple(frames.scene(f) for f in group), opts, None, fold, encode)


def _assembled(
    results: Iterator[tuple[Part, ChunkResult]], nbands: int, pace: Pace
) -> Iterator[tuple[int, bytes | np.ndarray, int]]:
    """(frame, PNG or pixels, PNG bytes moved) from the tasks' results in order: each frame of a chunk, or a
    frame's bands stacked. Each pixel's samples depend only on the pixel, so the stacked bands are the
    one-piece image bit for bit."""
    parts: list[np.ndarray] = []
    nbytes = 0
    for part, res in results:
        pace.record(len(part.frames), res.seconds)
        moved = [len(im) if isinstance(im, bytes) else 0 for im in res.images]
        if nbands == 1:
            yield from zip(part.frames, res.images, moved)
            continue
        image = res.images[0]
        parts.append(decode_png(image) if isinstance(image, bytes) else image)
        nbytes += moved[0]
        if part.band == nbands - 1:
            yield part.frames[0], np.concatenate(parts, axis=0), nbytes
            parts, nbytes = [], 0


def bands(height: int, k: int) -> list[tuple[int, int]]:
    """K bands of rows [y0, y1) covering the image, sizes differing by at most one row (K <= height)."""
    edges = [i * height // k for i in range(k + 1)]
    return [(edges[i], edges[i + 1]) for i in range(k)]
