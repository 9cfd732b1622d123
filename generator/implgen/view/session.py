"""One page's session: its document, its compiled library, and the render loop where the newest request wins.

Messages arrive on the event loop; a `render` request replaces whatever request is waiting and cancels the
render that is running (rt_render_cancel: the C threads stop after their current row), so stale frames are
never queued. Nothing slow runs on the event loop: parses and builds go to the `parse` pool, live frames to the
`render` pool, saves to the `save` pool (work.py), each C render under a Ticket with its time budget. Each
request is first drawn coarse (a quarter of the size, 1 sample per pixel, sent as JPEG) and, when it asks to be
refined and nothing newer has come, at full size with 4 samples (sent as PNG).

A slider moves a param value: the scene description is rebuilt around the already loaded library (microseconds;
params are run-time values of the generated code). A new equation is parsed once (protocol.py keeps the recent
ones) and generated and compiled once (build.py: only its own .c and the glue are compiled, the runtime's
objects are cached). When the page closes, its renders and its save are cancelled and `close` returns once they
have stopped: the server counts the page until then.
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
from implgen.scene.render import usable_cores
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene
from implgen.view import dump, protocol
from implgen.view.document import Document
from implgen.view.work import Ticket, Work

COARSE_DIVISOR = 4
FULL_SPP = 4
MAX_RENDERS_PER_SECOND = 60  # per page: requests beyond this wait (and are overtaken by newer ones)
KIND_COARSE, KIND_FULL, KIND_SAVE = 0, 1, 2
HEADER = struct.Struct(">IBxxxHH")  # seq, kind, width, height; the image bytes follow
LIVE_JPEG_QUALITY = 88  # the coarse frame: small and soon replaced
LIVE_PNG_LEVEL = 1  # the full frame: speed over size (zlib level 1)
BAND = 256  # rows converted to 8 bits at a time: no float temporaries the size of a whole saved picture

log = logging.getLogger("implgen.view")

Send = Callable[[dict | bytes], Awaitable[None]]


def _live_jpeg(rgb8: np.ndarray) -> bytes:
    return encode_jpeg(rgb8, LIVE_JPEG_QUALITY)


def _live_png(rgb8: np.ndarray) -> bytes:
    return encode_png(rgb8, LIVE_PNG_LEVEL)


def _file_png(rgb8: np.ndarray) -> bytes:
    return encode_png(rgb8)  # the encoder and level write_png uses: the bytes `implgen render` writes


def _eight_bits(img: np.ndarray) -> np.ndarray:
    """to_uint8 band by band (the same values as on the whole picture, a fraction of its temporaries)."""
    out = np.empty(img.shape, np.uint8)
    for y in range(0, img.shape[0], BAND):
        out[y : y + BAND] = to_uint8(img[y : y + BAND])
    return out


def _trace(ticket: Ticket, loop, sc: Scene, lib: BuildResult, spp: int, threads: int, encode) -> bytes | None:
    """On a pool thread: one C render of `sc` under its ticket, encoded; None when cancelled (by the page, or by
    the budget: ticket.expired says which). The same context and samples as render() (renderjob.py)."""
    if ticket.cancelled:
        return None
    cs = CScene(sc, lib.for_scene(sc, fold=False))
    try:
        with RenderJob(cs, sc.width, sc.height, spp, sc.max_depth, threads) as job:
            ticket.attach(job, loop)
            try:
                img = job.run()
            finally:
                ticket.detach()
            rgb8 = None if img is None else _eight_bits(img)
            job.image = img = None  # the float picture is not kept while the bytes are encoded
    finally:
        cs.close()
    return None if rgb8 is None else encode(rgb8)


_default_work: Work | None = None


def default_work() -> Work:
    """The pools a Session uses when none are given (a session made directly, as in tests)."""
    global _default_work
    if _default_work is None:
        _default_work = Work()
    return _default_work


class Session:
    def __init__(self, doc: Document, send: Send, threads: int | None = None, work: Work | None = None):
        self.doc = doc
        self.send = send
        self.threads = threads or usable_cores()
        self.work = work or default_work()
        self._pending: protocol.RenderRequest | None = None
        self._wake = asyncio.Event()
        self._live: Ticket | None = None  # the live render in progress
        self._save: Ticket | None = None  # the save's render in progress
        self._cost: float | None = None  # core seconds a sample of the last render of this shape
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
                width, height, spp = protocol.parse_save(data)
                if self._saving is not None and not self._saving.done():
                    raise UserError("save_png", "a picture is already being saved")
                release = self.work.reserve_save(width * height)  # given back when the task is done
                # its own task: the page stays interactive while a large picture renders
                self._saving = asyncio.get_running_loop().create_task(self._save_png(width, height, spp))
                self._saving.add_done_callback(lambda _: release())
            elif kind == "save_yaml":
                text = await self.work.call(self.work.parse, yaml_text, replace(self.doc))
                await self.send({"type": "yaml", "mode": self._mode(), "text": text})
            elif kind == "show_c":
                await self.send({"type": "c", "text": await self.work.call(self.work.parse, c_text, self.doc.spec)})
        except UserError as err:
            await self.send(protocol.error_for(err))

    def _mode(self) -> str:
        return "spec" if self.doc.base is None else "scene"

    async def _shape(self, data: dict) -> None:
        spec = await self.work.call(self.work.parse, protocol.parse_shape, data, self.doc.spec)
        trial = replace(self.doc)  # the page keeps showing the current shape until the new one is built
        trial.set_spec(spec)
        await self._library(trial.scene())
        self.doc.spec, self.doc.values = trial.spec, trial.values
        self._cost = None  # measured anew by the new shape's first render
        await self.send(
            {
                "type": "shape",
                "equation": spec.equation,
                "params": spec.params,
                "values": self.doc.values,
                "degree": spec.degree,
            }
        )

    # ------------------------------------------------------------------ rendering

    async def _library(self, sc: Scene) -> BuildResult:
        """The scene's library: built (or found in the build cache) once per set of shapes on the parse pool,
        then reused by every page showing those shapes (each render maps the scene's leaves onto it on its own
        thread)."""
        specs = sc.specs()
        built = self.work.library(specs)
        if built is None:
            built = await self.work.call(self.work.parse, build_scene, sc)
            self.work.keep_library(specs, built)
        return built

    def request(self, req: protocol.RenderRequest) -> None:
        """The newest request wins: it replaces the waiting one and cancels the running render."""
        self._pending = req
        if self._live is not None:
            self._live.cancel()
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
        data = await self._render(cw, ch, 1, _live_jpeg)
        if data is None:
            return
        await self._send_frame(req.seq, KIND_COARSE, cw, ch, data)
        if req.refine and self._pending is None:
            data = await self._render(req.width, req.height, FULL_SPP, _live_png)
            if data is not None:
                await self._send_frame(req.seq, KIND_FULL, req.width, req.height, data)

    async def _send_frame(self, seq: int, kind: int, width: int, height: int, data: bytes) -> None:
        await self.send(HEADER.pack(seq, kind, width, height) + data)
        self.frames += 1

    async def _render(self, width: int, height: int, spp: int, encode: Callable) -> bytes | None:
        """The document's current view, encoded; None when a newer request cancelled it. Over its time budget:
        a UserError saying what the surface costs."""
        sc = self.doc.scene(width, height, spp)
        lib = await self._library(sc)
        if self._pending is not None:  # overtaken while the scene was being built
            return None
        ticket = Ticket(self.work.limits.render_budget, "render", "render", width, spp, self.threads)
        ticket.check_rows(self._cost)
        self._live = ticket
        try:
            data = await self.work.trace(self.work.render, ticket, _trace, sc, lib, spp, self.threads, encode)
        finally:
            self._live = None
            self._cost = ticket.cost or self._cost
        if data is None and ticket.expired:
            raise ticket.over_budget()
        return data

    async def _save_png(self, width: int, height: int, spp: int) -> None:
        """The current view at any size: the same C render context and samples as render(), and the PNG encoder
        write_png uses (the same bytes as `implgen render` writes for this scene)."""
        try:
            sc = self.doc.scene(width, height, spp)
            lib = await self._library(sc)
            ticket = Ticket(self.work.limits.save_budget, "save", "save_png", width, spp, self.threads)
            ticket.check_rows(self._cost)
            self._save = ticket
            data = await self.work.trace(self.work.save, ticket, _trace, sc, lib, spp, self.threads, _file_png)
            self._cost = ticket.cost or self._cost
            if data is None:
                if ticket.expired:
                    raise ticket.over_budget()
                return  # cancelled: the page closed
        except Exception as err:  # say so, keep serving
            await self._failed(err, "viewer save failed")
            return
        finally:
            self._save = None
        await self.send(HEADER.pack(0, KIND_SAVE, width, height) + data)

    async def _failed(self, err: Exception, what: str) -> None:
        """Tell the page what failed; a bug (not bad input) also goes to the log with its traceback."""
        if not isinstance(err, UserError):
            log.error(what, exc_info=err)
        await self.send(protocol.error_for(err))

    async def close(self) -> None:
        """The page has gone: cancel its renders and its save, and return once they have stopped."""
        self._pending = None
        for ticket in (self._live, self._save):
            if ticket is not None:
                ticket.cancel()
        tasks = [t for t in (self._task, self._saving) if t is not None and not t.done()]
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)  # work.trace waits for the C threads to stop


def yaml_text(doc: Document) -> str:
    """The document as a spec, or for a scene file the whole scene (on the parse pool: SymPy prints it)."""
    if doc.base is None:
        return dump.to_yaml(dump.spec_mapping(doc.spec, doc.values))
    return dump.to_yaml(dump.scene_mapping(doc.scene(spp=FULL_SPP)))


def c_text(spec) -> str:
    """What `implgen SPEC.yaml --lang c` writes for the shape (on the parse pool)."""
    from implgen.codegen.emit import generate

    files = generate(spec, langs=("c",))
    return "".join(f"/* ---- {name} ---- */\n{text}\n" for name, text in sorted(files.items()))
