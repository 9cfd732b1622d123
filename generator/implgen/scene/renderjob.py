"""`RenderJob`: one C render context (rt_render, runtime_c/tracer_render.c) over a committed scene, owned by a
`with` block: created on entry, freed on exit whatever happened (an exception, a cancel, a run still going
on another thread: it is cancelled and waited for first; the C threads stop after their current row).

    with RenderJob(cs, width, height, spp, max_depth, threads, seed, rows=(y0, y1)) as job:
        img = job.run()           # blocks; None when cancelled
        job.seconds, job.stats()  # wall time of rt_render_run alone; rays by kind

`run` blocks in C with the GIL released (ctypes), so it may run on a worker thread (threading, or
asyncio.to_thread) while the caller polls `progress` or calls `cancel`; both are thread-safe and harmless
before the run starts (a cancel then stops it at once) or after the context is freed (they do nothing).
The output image is allocated on entry, so `run` times the C loop alone (what `implgen bench render`
reports). One run per job.

A job may instead be rendered in passes, as the viewer refines a resting view (view/ladder.py):

    with RenderJob(cs, width, height, 4, max_depth, threads) as job:
        job.run_pass(0, 1, PIXELS_EVEN)   # sample 0 of the pixels whose x and y are even: img[::2, ::2]
        job.run_pass(0, 1, PIXELS_ODD)    # sample 0 of the others: the whole picture at 1 sample
        img = job.run_pass(1, 4)          # samples 1 to 3 added: bit for bit run()'s image at 4 samples

Each pass adds the samples a whole render takes to running sums in double (kept by the job), in the same
order, so the last pass's image is the whole render's bit for bit; the image between passes is the mean of the
samples so far.
"""

from __future__ import annotations

import ctypes
import threading
import time
from typing import NamedTuple

import numpy as np

from implgen.scene.tracer import CScene

PIXELS_ALL, PIXELS_EVEN, PIXELS_ODD = 0, 1, 2  # the pixels a pass renders (RT_PIXELS_*): all, x and y even, the others
RAY_KINDS = ("primary", "shadow", "secondary")  # the first three stats slots (RT_RAYS_*)
CANCELLED = 1  # rt_render_run's result when cancelled; 0 is done, anything else a failure


class RenderStats(NamedTuple):
    rays: dict[str, float]  # rays traced by kind (RAY_KINDS)
    nonfinite: int  # samples that came out NaN/inf (rendered as 0); should always be 0


class RenderJob:
    """One rt_render context; see the module docstring. `rows`: only the band [y0, y1) of the image (a tile),
    exactly as those rows of the whole image; the image `run` returns has y1 - y0 rows."""

    def __init__(
        self,
        cs: CScene,
        width: int,
        height: int,
        spp: int,
        max_depth: int,
        threads: int,
        seed: int = 0,
        rows: tuple[int, int] | None = None,
    ):
        self.cs = cs
        self._args = (width, height, spp, max_depth, threads, seed)
        self._band = rows
        self.rows = (0, height) if rows is None else rows
        self.seconds = 0.0  # wall time of rt_render_run, once run
        self.certify_seconds = 0.0  # wall time of rt_render_certify, once run
        self.image: np.ndarray | None = None
        self._sums: np.ndarray | None = None  # the passes' running sums (run_pass)
        self._samples = {PIXELS_EVEN: 0, PIXELS_ODD: 0}  # samples a pixel the passes have added, by lattice
        self._ctx = None
        self._ran = False
        self._guard = threading.Lock()  # the context pointer: cancel/progress/stats vs free
        self._running = threading.Lock()  # held for the whole of rt_render_run: free waits for it

    def __enter__(self) -> RenderJob:
        lib = self.cs.lib
        ctx = lib.rt_render_new(self.cs.ptr, *self._args)
        if not ctx:
            raise RuntimeError("rt_render_new failed")
        self._ctx = ctx
        y0, y1 = self.rows
        if self._band is not None and lib.rt_render_set_rows(ctx, y0, y1) != 0:
            self._free()
            raise RuntimeError("rt_render_set_rows failed")
        self.image = np.zeros((y1 - y0, self._args[0], 3), dtype=np.float32)
        return self

    def __exit__(self, *exc) -> None:
        self.cancel()  # no-op for a run that ended; stops one still going on another thread
        with self._running:  # ... and waits for it: the C threads must not outlive the context
            self._free()

    def _free(self) -> None:
        with self._guard:
            ctx, self._ctx = self._ctx, None
        if ctx:
            self.cs.lib.rt_render_free(ctx)

    def run(self) -> np.ndarray | None:
        """Render (blocking): the float image, or None when cancelled. RuntimeError when the render failed
        (threads could not be started), or when called twice or outside the `with` block."""
        with self._running:
            with self._guard:
                ctx = self._ctx
                if self._ran or ctx is None:  # run once, and never after a pass
                    raise RuntimeError("a RenderJob runs once, inside its with block")
                self._ran = True
            code = self._run_c(ctx)
        return self._outcome(code)

    def _run_c(self, ctx) -> int:
        """rt_render_run into the image, timed (under _running)."""
        ptr = self.image.ctypes.data_as(ctypes.POINTER(ctypes.c_float))
        t0 = time.perf_counter()
        code = self.cs.lib.rt_render_run(ctx, ptr)
        self.seconds = time.perf_counter() - t0
        return code

    def _outcome(self, code: int) -> np.ndarray | None:
        if code == CANCELLED:
            return None
        if code != 0:
            raise RuntimeError(f"render failed (code {code})")
        return self.image

    def run_pass(self, k0: int, k1: int, pixels: int = PIXELS_ALL) -> np.ndarray | None:
        """Render samples [k0, k1) of `pixels` (blocking), added to the samples before k0 that earlier passes
        rendered: the image (the mean so far for those pixels), or None when cancelled. Passes go in order, each
        starting where the last one of its pixels ended; `run` is then not allowed. RuntimeError otherwise."""
        lattices = (PIXELS_EVEN, PIXELS_ODD) if pixels == PIXELS_ALL else (pixels,)
        with self._running:
            with self._guard:
                ctx = self._ctx
                whole = self._ran and self._sums is None  # run() has rendered this job
                if (
                    ctx is None
                    or whole
                    or any(self._samples.get(p) != k0 for p in lattices)
                    or not k0 < k1 <= self._args[2]
                ):
                    raise RuntimeError(f"pass [{k0}, {k1}) out of order, or outside the with block")
                self._ran = True
                if self._sums is None:
                    self._sums = np.zeros(self.image.shape, np.float64)
                if self.cs.lib.rt_render_set_pass(ctx, k0, k1, pixels, _doubles(self._sums)) != 0:
                    raise RuntimeError("rt_render_set_pass failed")
            code = self._run_c(ctx)
            if code == 0:
                for p in lattices:
                    self._samples[p] = k1
        return self._outcome(code)

    def certify(self) -> tuple[np.ndarray, np.ndarray]:
        """The certify pass over the rows run renders (runtime_c/certify.h): the code of each pixel's primary
        rays (uint8) and the object each code is about (int32, -1: none), timed into certify_seconds."""
        y0, y1 = self.rows
        width = self._args[0]
        codes = np.zeros((y1 - y0, width), dtype=np.uint8)
        objects = np.full((y1 - y0, width), -1, dtype=np.int32)
        with self._running:
            with self._guard:
                ctx = self._ctx
                if ctx is None:
                    raise RuntimeError("certify runs inside the with block")
            t0 = time.perf_counter()
            c_codes = codes.ctypes.data_as(ctypes.POINTER(ctypes.c_uint8))
            code = self.cs.lib.rt_render_certify(ctx, c_codes, objects.ctypes.data_as(ctypes.POINTER(ctypes.c_int)))
            self.certify_seconds = time.perf_counter() - t0
        if code != 0:
            raise RuntimeError(f"certify pass failed (code {code})")
        return codes, objects

    def cancel(self) -> None:
        """Ask the run to stop after its current rows (thread-safe; before the run: it will stop at once)."""
        with self._guard:
            if self._ctx:
                self.cs.lib.rt_render_cancel(self._ctx)

    def progress(self) -> int:
        """Rows finished so far (thread-safe)."""
        with self._guard:
            return self.cs.lib.rt_render_progress(self._ctx) if self._ctx else 0

    def stats(self) -> RenderStats:
        """Rays traced by kind and non-finite samples, so far (thread-safe)."""
        out = (ctypes.c_double * 4)()
        with self._guard:
            if self._ctx:
                self.cs.lib.rt_render_stats(self._ctx, out)
        return RenderStats(dict(zip(RAY_KINDS, out[:3])), int(out[3]))


def _doubles(a: np.ndarray):
    return a.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
