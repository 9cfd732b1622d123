"""The pixels float could not decide, in double: at rest, a page whose GPU draws a scene (gpu.js) keeps its own
picture and asks for the pixels its GLSL flagged "not sure"; each is traced here by the C tracer, one sample at
the pixel's centre, exactly as `implgen render` at one sample draws that pixel (tracer_render.c render_row: the
same camera ray, rt_trace_ray, the colour as a float, then imagefile.to_uint8), and sent as its RGB bytes.

The rays go through scene/camera.py's camera_rays (the tracer's basis) and are shared out over `threads`
threads (rt_trace_ray only reads the committed scene). The work stops at `stop` (a newer view) or past
`seconds` (the render budget), and then returns None. `Fixes` runs a page's fix messages, each in a task of its
own, the parts of one rest one after the other, a newer rest's stopping an older one's.
"""

from __future__ import annotations

import asyncio
import struct
import threading
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from implgen.errors import UserError
from implgen.imagefile import to_uint8
from implgen.scene.build import BuildResult
from implgen.scene.camera import camera_rays
from implgen.scene.model import Scene
from implgen.scene.tracer import CScene
from implgen.view.builds import Builds
from implgen.view.document import Document
from implgen.view.protocol import MAX_FIX_PARTS, MAX_FIX_PIXELS, FixRequest
from implgen.view.work import Work

MAX_PIXELS, MAX_PARTS = MAX_FIX_PIXELS, MAX_FIX_PARTS  # a fix message's pixels; the messages of one rest
KIND_FIX = 7  # the reply's kind: its header is session.SAMPLES's (seq, kind, flags, part, width, height)
HEAD = struct.Struct(">IBBHHH")
CHECK = 64  # pixels traced between looks at the stop and the clock


def _trace_share(cs: CScene, eye, dirs: np.ndarray, depth: int, out: np.ndarray, give_up) -> bool:
    """Trace dirs into out (float32 RGB); False when given up."""
    for i, d in enumerate(dirs):
        if i % CHECK == 0 and give_up():
            return False
        c = cs.trace(eye, d, depth)
        out[i] = c if np.isfinite(c).all() else 0.0  # the tracer drops a non-finite sample: black at 1 sample
    return True


def fix_pixels(
    sc: Scene,
    lib: BuildResult,
    pixels: list[int],
    threads: int = 1,
    stop: threading.Event | None = None,
    seconds: float | None = None,
) -> bytes | None:
    """The RGB bytes (3 a pixel, in the order given) of pixels y * width + x of sc's picture at one sample, or None
    when stopped or past `seconds` (on a pool thread)."""
    index = np.asarray(pixels, dtype=np.int64)
    x, y = index % sc.width, index // sc.width
    eye, dirs = camera_rays(sc.camera, sc.width, sc.height, x + 0.5, y + 0.5)  # the pixels' centres
    out = np.zeros((len(index), 3), np.float32)
    deadline = None if seconds is None else time.monotonic() + seconds

    def give_up() -> bool:
        return (stop is not None and stop.is_set()) or (deadline is not None and time.monotonic() > deadline)

    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        n = max(1, min(threads, len(index) // CHECK + 1))
        cuts = np.linspace(0, len(index), n + 1).astype(int)  # contiguous shares: out[a:b] is a view of out
        with ThreadPoolExecutor(n) as pool:
            jobs = [
                pool.submit(_trace_share, cs, eye, dirs[a:b], sc.max_depth, out[a:b], give_up)
                for a, b in zip(cuts[:-1], cuts[1:])
            ]
            done = [job.result() for job in jobs]
    finally:
        cs.close()
    if not all(done):
        return None
    return to_uint8(out).tobytes()


class Fixes:
    """A page's fix messages: `start` one (its pixels traced on the render pool, their bytes sent after a HEAD of
    KIND_FIX); `stop` all, returning their tasks to wait for."""

    def __init__(self, work: Work, builds: Builds, send: Callable, failed: Callable) -> None:
        self.work, self.builds, self.send, self.failed = work, builds, send, failed
        self._by_seq: dict[int, tuple[asyncio.Task, threading.Event]] = {}
        self._newest, self._parts = -1, set()  # the newest rest's seq and the parts it has asked

    def start(self, req: FixRequest, doc: Document, threads: int) -> None:
        """Trace the request's pixels after the parts of its rest asked before; an older rest's are stopped, and a
        request older than the newest rest's is dropped. A part asked twice is refused (so a rest holds at most
        MAX_PARTS tasks)."""
        seq = req.view.seq
        if seq < self._newest:
            return
        if seq > self._newest:
            self._newest, self._parts = seq, set()
        if req.part in self._parts:
            raise UserError("fix", f"part {req.part} of this view was asked already")
        self._parts.add(req.part)
        for old in [s for s in self._by_seq if s < seq]:  # an older rest's fix: stopped
            task, stop = self._by_seq.pop(old)
            stop.set()
            task.cancel()
        before, stop = self._by_seq.get(seq, (None, threading.Event()))
        v = req.view
        view = replace(doc, values=v.values, orbit=v.orbit, options=v.options)
        task = asyncio.get_running_loop().create_task(self._run(req, view, threads, stop, before))
        self._by_seq[seq] = (task, stop)

    async def _run(
        self, req: FixRequest, doc: Document, threads: int, stop: threading.Event, before: asyncio.Task | None
    ) -> None:
        if before is not None:  # the rest's parts one after the other
            await asyncio.gather(before, return_exceptions=True)
        v = req.view
        try:
            sc = doc.scene(v.width, v.height, 1)
            lib = await self.builds.library(sc)
            budget = self.work.limits.render_budget
            data = await self.work.call(self.work.render, fix_pixels, sc, lib, req.pixels, threads, stop, budget)
            if data is None:
                if not stop.is_set():
                    raise UserError("fix", f"the flagged pixels took more than the {budget:g} s render budget")
                return
            await self.send(HEAD.pack(v.seq, KIND_FIX, 0, req.part, v.width, v.height) + data)
        except Exception as err:  # (not a cancel) said to the page
            await self.failed(err, "viewer fix failed")

    def stop(self) -> list[asyncio.Task]:
        out = []
        for task, stop in self._by_seq.values():
            stop.set()
            task.cancel()
            out.append(task)
        self._by_seq = {}
        return out
