"""One page's session: its document, its compiled library, and the render loop where the newest request wins.

Messages arrive on the event loop; a `render` request replaces whatever request is waiting and cancels the
render that is running (rt_render_cancel: the C threads stop after their current row), so stale frames are
never queued. Renders run in the C tracer on a worker thread (ctypes releases the GIL) and the event loop
stays free. Each request is first drawn coarse (a quarter of the size, 1 sample per pixel, sent as JPEG) and,
when it asks to be refined and nothing newer has come, at full size with 4 samples (sent as PNG).

A slider moves a param value: the scene description is rebuilt around the already loaded library (microseconds;
params are run-time values of the generated code). A new equation is generated and compiled once (build.py:
only its own .c and the glue are compiled, the runtime's objects are cached).
"""

from __future__ import annotations

import asyncio
import logging
import struct
import time
from collections.abc import Awaitable, Callable
from dataclasses import replace

import numpy as np

from implgen.errors import UserError
from implgen.imagefile import encode_jpeg, encode_png, to_uint8
from implgen.scene.build import BuildResult, build_scene
from implgen.scene.model import Scene
from implgen.scene.render import render, usable_cores
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene
from implgen.view import dump, protocol
from implgen.view.document import Document

COARSE_DIVISOR = 4
FULL_SPP = 4
MAX_RENDERS_PER_SECOND = 60  # per page: requests beyond this wait (and are overtaken by newer ones)
KIND_COARSE, KIND_FULL, KIND_SAVE = 0, 1, 2
HEADER = struct.Struct(">IBxxxHH")  # seq, kind, width, height; the image bytes follow
LIVE_JPEG_QUALITY = 88  # the coarse frame: small and soon replaced
LIVE_PNG_LEVEL = 1  # the full frame: speed over size (zlib level 1)

log = logging.getLogger("implgen.view")

Send = Callable[[dict | bytes], Awaitable[None]]


def _live_jpeg(img: np.ndarray) -> bytes:
    return encode_jpeg(to_uint8(img), LIVE_JPEG_QUALITY)


def _live_png(img: np.ndarray) -> bytes:
    return encode_png(to_uint8(img), LIVE_PNG_LEVEL)


class Session:
    def __init__(self, doc: Document, send: Send, threads: int | None = None):
        self.doc = doc
        self.send = send
        self.threads = threads or usable_cores()
        self._libs: dict[tuple, object] = {}  # spec ids of a scene's shapes -> built library path
        self._pending: protocol.RenderRequest | None = None
        self._wake = asyncio.Event()
        self._running: RenderJob | None = None  # the render in progress
        self._last_start = 0.0
        self._task: asyncio.Task | None = None
        self._saving: asyncio.Task | None = None
        self.frames = 0  # frames sent (for tests)

    # ------------------------------------------------------------------ messages

    def hello(self) -> dict:
        """The state the page starts from."""
        d = self.doc
        o = d.options
        return {
            "type": "hello",
            "equation": d.spec.equation,
            "params": d.spec.params,
            "values": d.values,
            "degree": d.spec.degree,
            "mode": "spec" if d.base is None else "scene",
            "orbit": {
                "yaw": d.orbit.yaw,
                "pitch": d.orbit.pitch,
                "distance": d.orbit.distance,
                "target": list(d.orbit.target),
                "fov": d.orbit.fov,
            },
            "options": {
                "clip": o.clip,
                "clip_size": o.clip_size,
                "color": list(o.color),
                "inside": list(o.inside),
                "lights": o.lights,
                "background": list(o.background),
            },
            "limits": {"frame": protocol.MAX_FRAME, "save": protocol.MAX_SAVE, "save_spp": protocol.MAX_SAVE_SPP},
        }

    async def handle(self, text: str | bytes) -> None:
        """One message from the page. Bad input is answered with an error message; nothing raises."""
        try:
            data = protocol.decode(text)
            kind = data["type"]
            if kind == "shape":
                await self._shape(data)
            elif kind == "render":
                self.request(protocol.parse_render(data, self.doc.spec))
            elif kind == "save_png":
                size = protocol.parse_save(data)
                if self._saving is not None and not self._saving.done():
                    raise UserError("save_png", "a picture is already being saved")
                # its own task: the page stays interactive while a large picture renders
                self._saving = asyncio.get_running_loop().create_task(self._save_png(*size))
            elif kind == "save_yaml":
                await self.send({"type": "yaml", "mode": self._mode(), "text": self.yaml_text()})
            elif kind == "show_c":
                await self.send({"type": "c", "text": self.c_text()})
        except UserError as err:
            await self.send(protocol.error_for(err))

    def _mode(self) -> str:
        return "spec" if self.doc.base is None else "scene"

    async def _shape(self, data: dict) -> None:
        spec = protocol.parse_shape(data, self.doc.spec)
        trial = replace(self.doc)  # the page keeps showing the current shape until the new one is built
        trial.set_spec(spec)
        await asyncio.to_thread(self._library, trial.scene())  # generate + compile off the event loop
        self.doc.spec, self.doc.values = trial.spec, trial.values
        await self.send(
            {
                "type": "shape",
                "equation": spec.equation,
                "params": spec.params,
                "values": self.doc.values,
                "degree": spec.degree,
            }
        )

    def yaml_text(self) -> str:
        if self.doc.base is None:
            return dump.to_yaml(dump.spec_mapping(self.doc.spec, self.doc.values))
        return dump.to_yaml(dump.scene_mapping(self.doc.scene(spp=FULL_SPP)))

    def c_text(self) -> str:
        from implgen.codegen.emit import generate

        files = generate(self.doc.spec, langs=("c",))
        return "".join(f"/* ---- {name} ---- */\n{text}\n" for name, text in sorted(files.items()))

    # ------------------------------------------------------------------ rendering

    def _library(self, sc: Scene) -> BuildResult:
        """The scene's library: built (or found in the build cache) once per set of shapes, then reused."""
        key = tuple(id(spec) for spec in sc.specs())
        if key not in self._libs:
            self._libs = {key: (build_scene(sc), sc.specs())}  # keep the specs alive with their ids
        return self._libs[key][0].for_scene(sc, fold=False)

    def request(self, req: protocol.RenderRequest) -> None:
        """The newest request wins: it replaces the waiting one and cancels the running render."""
        self._pending = req
        if self._running is not None:
            self._running.cancel()
        self._wake.set()
        if self._task is None or self._task.done():
            self._task = asyncio.get_running_loop().create_task(self._loop())

    async def _loop(self) -> None:
        while True:
            await self._wake.wait()
            self._wake.clear()
            req, self._pending = self._pending, None
            if req is None:
                continue
            wait = self._last_start + 1.0 / MAX_RENDERS_PER_SECOND - time.monotonic()
            if wait > 0:
                await asyncio.sleep(wait)
                if self._pending is not None:  # overtaken while waiting
                    self._wake.set()
                    continue
            self._last_start = time.monotonic()
            self.doc.values, self.doc.orbit, self.doc.options = req.values, req.orbit, req.options
            try:
                await self._frames(req)
            except Exception as err:  # (not a cancel: that is a BaseException) say so, serve the next request
                await self._failed(err, "viewer render failed")

    async def _frames(self, req: protocol.RenderRequest) -> None:
        cw, ch = max(1, req.width // COARSE_DIVISOR), max(1, req.height // COARSE_DIVISOR)
        img = await self._render(cw, ch, 1)
        if img is None:
            return
        await self._send_frame(req.seq, KIND_COARSE, img, _live_jpeg)
        if req.refine and self._pending is None:
            img = await self._render(req.width, req.height, FULL_SPP)
            if img is not None:
                await self._send_frame(req.seq, KIND_FULL, img, _live_png)

    async def _send_frame(self, seq: int, kind: int, img: np.ndarray, encode: Callable[[np.ndarray], bytes]) -> None:
        data = await asyncio.to_thread(encode, img)
        await self.send(HEADER.pack(seq, kind, img.shape[1], img.shape[0]) + data)
        self.frames += 1

    async def _render(self, width: int, height: int, spp: int) -> np.ndarray | None:
        """Render the document's current view; None when a newer request cancelled it."""
        sc = self.doc.scene(width, height, spp)
        built = await asyncio.to_thread(self._library, sc)
        cs = CScene(sc, built)
        try:
            with RenderJob(cs, width, height, spp, sc.max_depth, self.threads) as job:
                self._running = job
                try:
                    if self._pending is not None:  # overtaken while the scene was being built
                        job.cancel()
                    run = asyncio.ensure_future(asyncio.to_thread(job.run))
                    try:
                        return await asyncio.shield(run)
                    except asyncio.CancelledError:  # the page went away: stop the C threads, wait for them
                        job.cancel()
                        await run
                        raise
                finally:
                    self._running = None
        finally:
            cs.close()

    async def _save_png(self, width: int, height: int, spp: int) -> None:
        """The current view at any size through the normal path: render(), and the PNG encoder write_png uses
        (the same bytes as `implgen render` writes for this scene)."""
        sc = self.doc.scene(width, height, spp)

        def work() -> bytes:
            return encode_png(to_uint8(render(sc, threads=self.threads)))

        try:
            data = await asyncio.to_thread(work)
        except Exception as err:  # say so, keep serving
            await self._failed(err, "viewer save failed")
            return
        await self.send(HEADER.pack(0, KIND_SAVE, width, height) + data)

    async def _failed(self, err: Exception, what: str) -> None:
        """Tell the page what failed; a bug (not bad input) also goes to the log with its traceback."""
        if not isinstance(err, UserError):
            log.error(what, exc_info=err)
        await self.send(protocol.error_for(err))

    async def close(self) -> None:
        self._pending = None
        if self._saving is not None and not self._saving.done():
            await asyncio.wait([self._saving])  # render() cannot be cancelled from here; it ends on its own
        if self._running is not None:
            self._running.cancel()
        if self._task is not None:
            self._task.cancel()
            try:
                await self._task
            except asyncio.CancelledError:
                pass
