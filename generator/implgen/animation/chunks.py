"""Chunks of frames: the unit of work of an animation, in this process or on a Dask worker.

A task renders a chunk, several frames in a row (or, with tiles, one band of rows of one frame), as render
farms do, so that what each task costs besides its pixels (the scheduler's round trip, the scene sent, a
result sent back) is paid once per chunk rather than once per frame. Each process builds a scene library once
and keeps it for the frames of every chunk it is given afterwards (`renderer_for`): one library load and
seal check per worker and library, not one per frame. `Pace` chooses the size of each chunk as the chunks are
handed out, from what is left, the worker threads there are now and the render time measured so far.

`local_results` runs chunks in this process on render threads, a chunk ahead of the caller, which writes
the frames meanwhile; Ctrl-C stops the frames in progress (`Stop`). Small frames render side by side, each
on fewer tracer threads (`lanes`): a frame of a few thousand samples cut among many threads spends more
on starting them and on its last row than on its pixels.
"""

from __future__ import annotations

import dataclasses
import math
import threading
import time
from collections import OrderedDict, deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

import numpy as np

from implgen.imagefile import encode_png, to_uint8
from implgen.scene.build import build_scene
from implgen.scene.model import Scene
from implgen.scene.render import usable_cores
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene, load_bound

TARGET_SECONDS = 0.25  # a chunk's render time: a task's fixed cost (a few ms on Dask) is then about 2 %
SHARES = 2  # a chunk takes at most 1/(SHARES x worker threads) of the frames left: the last round is balanced
MAX_CHUNK = 256  # frames
KEEP_RENDERERS = 4  # scene libraries a process keeps loaded for the chunks to come
PER_LANE = 3  # chunks submitted ahead per render thread here, as cluster.PER_THREAD per worker thread
SAMPLES_PER_THREAD = 20_000  # a tracer thread's least share of a frame here: smaller frames go side by side


@dataclass(frozen=True)
class Part:
    """What one task renders: the frames `frames` whole, or band `band` of the rows of its one frame."""

    frames: tuple[int, ...]
    band: int | None = None

    def __str__(self) -> str:  # in task keys and messages
        first, last = self.frames[0], self.frames[-1]
        if self.band is not None:
            return f"{first}-{self.band}"
        return str(first) if first == last else f"{first}..{last}"


@dataclass
class ChunkResult:
    images: list  # per frame: PNG bytes (encoded on the worker) or 8-bit RGB arrays (rendered here)
    seconds: float  # rendering and encoding alone, not the scene library's build or load


@dataclass
class Pace:
    """The size of each chunk. `fixed`: always that many frames. Otherwise one frame a chunk until a render
    time is known, then about TARGET_SECONDS of frames, at most 1/(SHARES x threads) of what is left."""

    target: float = TARGET_SECONDS
    fixed: int | None = None
    per_frame: float | None = None  # seconds, a running mean over the chunks done

    def size(self, left: int, threads: int) -> int:
        if self.fixed is not None:
            return max(1, min(self.fixed, left))
        if self.per_frame is None:
            return 1
        share = math.ceil(left / (SHARES * max(1, threads)))
        want = int(self.target / max(self.per_frame, 1e-6))
        return max(1, min(want, share, MAX_CHUNK, left))

    def record(self, frames: int, seconds: float) -> None:
        per = seconds / max(1, frames)
        self.per_frame = per if self.per_frame is None else 0.5 * (self.per_frame + per)


class Stopped(Exception):
    """The chunk was stopped (Ctrl-C in this process): its frames are not done."""


class Stop:
    """Stops the chunks rendering in this process: before their next frame, and the frames in progress (their
    render contexts cancelled: the C threads end after their current row)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._jobs: set[RenderJob] = set()
        self.stopped = False

    def stop(self) -> None:
        with self._lock:
            self.stopped = True
            for job in self._jobs:
                job.cancel()

    def running(self, job: RenderJob, now: bool) -> None:
        """A job starts (`now`) or ends rendering; one that starts after stop() is cancelled at once."""
        with self._lock:
            if now:
                self._jobs.add(job)
                if self.stopped:
                    job.cancel()
            else:
                self._jobs.discard(job)


class FrameRenderer:
    """One scene library, built (through the build cache), loaded and bound once, for every frame of every
    scene made of the same shapes."""

    def __init__(self, scene: Scene, fold: bool):
        self.fold = fold
        self.built = build_scene(scene, fold=fold)
        self.lib = load_bound(self.built)

    def image(self, scene: Scene, opts: Any, rows: tuple[int, int] | None, stop: Stop | None) -> np.ndarray:
        """One frame (or the band of rows [y0, y1) of it) as 8-bit RGB: the pixels render() gives."""
        cs = CScene(scene, self.built.for_scene(scene, self.fold), lib=self.lib)
        try:
            threads = opts.threads or usable_cores()
            args = (opts.width, opts.height, opts.spp, opts.max_depth, threads, opts.seed)
            with RenderJob(cs, *args, rows=rows) as job:
                if stop is not None:
                    stop.running(job, True)
                try:
                    img = job.run()
                finally:
                    if stop is not None:
                        stop.running(job, False)
        finally:
            cs.close()
        if img is None:
            raise Stopped()
        return to_uint8(img)


_renderers: OrderedDict[tuple, FrameRenderer] = OrderedDict()
_renderers_lock = threading.Lock()


def renderer_key(scene: Scene, fold: bool) -> tuple:
    """What a scene's library depends on: each leaf's generated code, and its param values when folded."""
    return (fold, tuple((leaf.spec.spec_key, tuple(leaf.params.values()) if fold else ()) for leaf in scene.leaves()))


def renderer_for(scene: Scene, fold: bool) -> FrameRenderer:
    """This process's renderer for the scene's shapes: built on first use, then kept (the KEEP_RENDERERS
    most recently used)."""
    key = renderer_key(scene, fold)
    with _renderers_lock:
        r = _renderers.get(key)
        if r is None:
            r = _renderers[key] = FrameRenderer(scene, fold)
            while len(_renderers) > KEEP_RENDERERS:
                _renderers.popitem(last=False)
        _renderers.move_to_end(key)
        return r


def forget_renderers() -> None:
    """Drop every kept renderer (tests: count the builds of one run)."""
    with _renderers_lock:
        _renderers.clear()


def render_chunk(
    scenes: tuple[Scene, ...],
    opts: Any,
    rows: tuple[int, int] | None = None,
    fold: bool = False,
    encode: bool = True,
    stop: Stop | None = None,
) -> ChunkResult:
    """The task: each scene (a frame) rendered with the options `opts` (frames.FrameOptions), whole or its
    band of rows, as PNG bytes (`encode`) or 8-bit arrays. Every pixel is the one render() gives alone."""
    renderer = renderer_for(scenes[0], fold)
    t0 = time.perf_counter()
    images = []
    for sc in scenes:
        if stop is not None and stop.stopped:
            raise Stopped()
        img = renderer.image(sc, opts, rows, stop)
        images.append(encode_png(img) if encode else img)
    return ChunkResult(images, time.perf_counter() - t0)


def lanes(opts: Any, cores: int) -> tuple[int, Any]:
    """How frames render in this process: (frames side by side, the options with each frame's tracer threads).
    Threads set by the caller are kept, one frame at a time; otherwise a frame gets every core unless that
    leaves a thread fewer than SAMPLES_PER_THREAD samples, and the cores left over render other frames."""
    if opts.threads is not None:
        return 1, opts
    per_frame = max(1, min(cores, opts.width * opts.height * opts.spp // SAMPLES_PER_THREAD))
    return max(1, cores // per_frame), dataclasses.replace(opts, threads=per_frame)


def local_results(
    fn: Callable[..., Any], jobs: Iterable[tuple[Any, tuple]], lanes: int = 1
) -> Iterator[tuple[Any, Any]]:
    """cluster.ordered's contract in this process: fn(*args, stop=...) for each (index, args) of `jobs` on
    `lanes` render threads, PER_LANE jobs a thread submitted ahead of the caller (so that a thread whose
    chunk ended before the oldest one finds another waiting), results yielded in order. When the caller stops
    early (Ctrl-C, an error), the frames in progress are cancelled and the threads waited for."""
    depth = PER_LANE * lanes
    stop = Stop()
    pool = ThreadPoolExecutor(lanes, thread_name_prefix="implgen-render")
    pending: deque = deque()
    todo = iter(jobs)
    try:
        while True:
            while len(pending) < depth:
                job = next(todo, None)
                if job is None:
                    break
                pending.append((job[0], pool.submit(fn, *job[1], stop=stop)))
            if not pending:
                return
            index, fut = pending.popleft()
            yield index, fut.result()
    finally:
        stop.stop()
        for _, fut in pending:
            fut.cancel()
        pool.shutdown(wait=True)
