"""One page's session: its document, its compiled library, and the render loop where the newest request wins.

Messages arrive on the event loop; a `render` request replaces whatever request is waiting and cancels the
refined render that is running (rt_render_cancel: the C threads stop after their current row), so stale
frames are never queued. A coarse frame in flight is finished and sent (or cut by its time budget, pace.py):
throwing it away at each mouse move would leave a drag with no frames at all when a frame takes longer than
the gap between moves. Nothing slow runs on the event loop: parses and builds go to the `parse` pool, live
frames to the `render` pool, saves to the `save` pool (work.py), each C render under a Ticket with its time
budget. Each request is first drawn coarse (1 sample per pixel, sent as JPEG, its size chosen by pace.py so
that it takes about 30 ms) and, when it asks to be refined and nothing newer has come, refined pass by pass to
`implgen render`'s picture at 4 samples (ladder.py). A refined request for the view the last coarse frame showed
goes straight to the ladder, for the view being refined lets it go on, for the view last refined gets it again.

A slider moves a param value: the scene description is rebuilt around the already loaded library (microseconds;
params are run-time values of the generated code). A new equation is parsed once (protocol.py keeps the recent
ones) and generated and compiled once (build.py: only its own .c and the glue are compiled, the runtime's
objects are cached). When the page closes, its renders and its save are cancelled and `close` returns once they
have stopped: the server counts the page until then.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import math
import struct
import time
from collections.abc import Awaitable, Callable
from dataclasses import replace
from pathlib import Path

from implgen import validate
from implgen.errors import UserError
from implgen.scene.render import usable_cores
from implgen.spec.paramrange import param_ranges
from implgen.view import dump, fit, fix, frames, gpu, ladder, pick, protocol, sharepage
from implgen.view.builds import Builds
from implgen.view.document import Document
from implgen.view.meshsave import MeshSaver
from implgen.view.pace import CUT, Pace
from implgen.view.work import Ticket, Work

FULL_SPP = 4
MAX_RENDERS_PER_SECOND = 60  # per page: requests beyond this wait (and are overtaken by newer ones)
KIND_COARSE, KIND_FULL, KIND_SAVE, KIND_ONE = 0, 1, 2, 3  # KIND_ONE: full size at 1 sample, before KIND_FULL
KIND_MESH = 4  # Save mesh's STL (meshsave.py)
KIND_QUARTER, KIND_MORE = 5, 6  # the refinement's half-size picture; full size at 2 to FULL_SPP - 1 samples
LADDER_KINDS = {"quarter": KIND_QUARTER, "one": KIND_ONE, "more": KIND_MORE, "full": KIND_FULL}  # ladder.py's steps
HEADER = struct.Struct(">IBBxxHH")  # seq, kind, flags, width, height; the image bytes follow
SAMPLES = struct.Struct(">IBBHHH")  # HEADER with its spare bytes read: the samples a pixel of a KIND_MORE frame
FLAG_EMPTY = 1  # no pixel of the frame shows anything but the background: no real points in view

log = logging.getLogger("implgen.view")

Send = Callable[[dict | bytes], Awaitable[None]]


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
        self._live_full = False  # it is a refined frame (a newer request cancels it; a coarse one is finished)
        self._shown, self._shown_pixels = None, 0  # the view the last coarse frame showed, and its pixels
        self._ladder: list | None = None  # [view, seq] of the refinement running: its frames carry seq
        self._final: tuple | None = None  # (view, width, height, bytes, empty) of the last refined frame sent
        self.pace = Pace()  # the coarse frames' size
        self._seconds = 0.0  # the last render's wall time, encoding included
        self._save: Ticket | None = None  # the save's render in progress
        self._cost: float | None = None  # core seconds a sample of the last render of this shape
        self._last_start = 0.0
        self._task: asyncio.Task | None = None
        self._saving: asyncio.Task | None = None
        self._glsl: asyncio.Task | None = None
        self._scenes = gpu.LastScene()  # the glsl messages: a scene's program sent last
        self.frames = 0  # frames sent (for tests)
        self.builds = Builds(self.work, send)  # the scenes' libraries, a long build told to the page
        self.fixes = fix.Fixes(self.work, self.builds, send, self._failed)  # a GPU-drawn scene's rest (fix.py)
        self.meshes = MeshSaver(self.work, send, lambda stl: send(HEADER.pack(0, KIND_MESH, 0, 0, 0) + stl))
        self._shape_id = 0  # numbers the shapes sent to the page (hello, shape replies), for the GPU preview

    # ------------------------------------------------------------------ messages

    def hello(self) -> dict:
        """The state the page starts from."""
        limits = {"frame": protocol.MAX_FRAME, "save": protocol.MAX_SAVE, "save_spp": protocol.MAX_SAVE_SPP}
        limits["ranges"] = protocol.RANGES  # the share link reads its numbers within these (static/share.js)
        hello = {"type": "hello", **self.doc.state(), "limits": limits}
        return {**hello, "gpu": gpu.hello_part(), "shape_id": self._shape_id}

    def _shape_reply(self, **extra) -> dict:
        """The page's new shape: its name, equation, params and their values (and what `extra` adds)."""
        return {"type": "shape", **self.doc.shape_state(), "shape_id": self._shape_id, **extra}

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
            elif kind == "save_mesh":
                await self.meshes.start(self.doc, data)
            elif kind == "stop_mesh":
                self.meshes.stop()
            elif kind == "save_yaml":
                width, height = protocol.parse_size(data, "save_yaml")
                doc = replace(self.doc)
                ranges = protocol.parse_ranges(data.get("ranges"), doc.spec, doc.values)
                doc.spec = replace(doc.spec, ranges={**doc.spec.ranges, **ranges})  # for the file only
                text = await self.work.call(self.work.parse, dump.yaml_text, doc, width, height, FULL_SPP)
                await self.send({"type": "yaml", "mode": self._mode(), "text": text})
            elif kind in ("pick", "object"):
                await self._pick(data)
            elif kind == "clip":  # the page renders it next, as for any change of the view
                self.doc.set_clip(*protocol.parse_clip(data))
            elif kind == "export_page":
                doc = replace(self.doc)
                doc.ranges = protocol.parse_ranges(data.get("ranges"), doc.spec, doc.values)
                name, html, note = await self.work.derive_glsl(sharepage.page_text, doc)
                await self.send({"type": "page", "name": name, "text": html, **({"note": note} if note else {})})
            elif kind == "glsl":  # the GPU preview asks for the current shape's GLSL: derived (SymPy) in a task of
                if self._glsl is not None:  # its own, so the renders behind it are read meanwhile; a newer ask wins
                    self._glsl.cancel()
                doc, ask = replace(self.doc), None
                if doc.base is not None:  # a scene's program: at the page's values of the picked leaf
                    ask, doc.values = protocol.parse_ask(data, doc.spec)
                self._glsl = asyncio.get_running_loop().create_task(self._send_glsl(doc, self._shape_id, ask))
            elif kind == "fix":
                self.fixes.start(protocol.parse_fix(data, self.doc.spec), self.doc, self.threads)
            elif kind == "show_c":
                await self.send(
                    {"type": "c", "text": await self.work.call(self.work.parse, dump.c_text, self.doc.spec)}
                )
        except UserError as err:
            await self.send(protocol.error_for(err))

    async def _pick(self, data: dict) -> None:
        """A scene file: the leaf to edit from now on, the one at a pixel of the picture or by its index."""
        count = len(self.doc.objects())
        if count == 0:
            raise UserError(data["type"], "only a scene file has objects to pick")
        if data["type"] == "pick":
            x, y, width, height = protocol.parse_pick(data)
            sc = self.doc.scene(width, height, 1)
            index = await self.work.call(self.work.render, pick.pick_leaf, sc, await self.builds.library(sc), x, y)
            if index is None:
                raise UserError("pick", "nothing there: the ray through that pixel meets no object")
        else:
            index = validate.whole("object", "index", data.get("index"), 0, count - 1)
        self.doc.select(index)
        self._final = None
        await self.work.call(self.work.parse, param_ranges, self.doc.spec)  # the sliders' spans, off the loop
        self._cost = None
        self.pace.new_shape()
        self._shape_id += 1
        await self.send(self._shape_reply(fit=None, object=index, objects=self.doc.objects()))

    def _mode(self) -> str:
        return "spec" if self.doc.base is None else "scene"

    async def _shape(self, data: dict) -> None:
        trial = replace(self.doc)  # the page keeps showing the current shape until the new one is built
        picked = None
        if data.get("object") is not None:  # a scene's link: the equation is that object's
            count = len(self.doc.objects())
            if count == 0:
                raise UserError("shape", "object: only a scene file has objects to pick")
            picked = validate.whole("shape", "object", data["object"], 0, count - 1)
            trial.select(picked)
        spec = await self.work.call(self.work.parse, protocol.parse_shape, data, trial.spec)
        trial.set_spec(spec)
        await self.work.call(self.work.parse, param_ranges, spec)  # the sliders' spans (kept with the spec)
        await self.builds.library(trial.scene())
        fitted, unbounded = None, False
        box = spec.box(trial.values) if spec.params else spec.box()
        if data.get("fit") is True or box is None or not all(map(math.isfinite, box)):
            # where its real points are: the clip fitted to them (when the size is not the user's own), or that
            # it runs on without end (the page says so when there is no clip)
            probe = fit.probe_scene(spec, trial.values)
            far = await self.work.call(self.work.render, fit.reach, probe, await self.builds.library(probe))
            fitted = fit.clip_for(far) if data.get("fit") is True else None
            unbounded = far is not None and math.isinf(far)
        self.doc.spec, self.doc.values = trial.spec, trial.values
        self.doc.leaf, self.doc.edits = trial.leaf, trial.edits  # a scene's link picked the object first
        self._shown = self._final = None  # an accepted shape is drawn coarse first, even the same one again
        self._cost = None  # measured anew by the new shape's first render
        self.pace.new_shape()
        self._shape_id += 1
        picked_part = {} if picked is None else {"object": picked}
        await self.send(self._shape_reply(fit=fitted, unbounded=unbounded, objects=self.doc.objects(), **picked_part))

    # ------------------------------------------------------------------ rendering

    def request(self, req: protocol.RenderRequest) -> None:
        """The newest request wins: it replaces the waiting one and cancels the running refined render (a
        coarse one is finished: it is the drag's next frame). A refined request for the view being refined
        changes nothing: the refinement goes on, its frames numbered for the newer request."""
        if req.refine and self._ladder is not None and self._pending is None and self._ladder[0] == self._view(req):
            self._ladder[1] = req.seq
            return
        self._pending = req
        if self._live is not None and self._live_full:
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
        view = self._view(req)
        if req.gpu and not req.refine:
            return  # the page draws the live picture itself: the view is noted (and a refinement cancelled)
        if req.refine and self._final is not None and self._final[0] == view:
            await self._send_frame(req.seq, KIND_FULL, *self._final[1:])  # nothing changed: the same picture
            return
        while not (req.refine and (view == self._shown or req.gpu)):
            cw, ch = self.pace.size(req.width, req.height)
            smallest = self.pace.smallest(req.width, req.height, cw)
            data, ticket = await self._render(cw, ch, 1, frames.live_jpeg, full=False, cut=not smallest)
            if data is not None:
                self.pace.measured(cw * ch, self._seconds)
                self._shown, self._shown_pixels = view, cw * ch
                await self._send_frame(req.seq, KIND_COARSE, cw, ch, *data)
                break
            if ticket is None or not ticket.expired:
                return  # cancelled: the page closed
            done_seconds, rows = ticket.expired  # cut: the rows done say what a pixel costs
            if rows:
                self.pace.measured(rows * cw, done_seconds)
            else:
                self.pace.cut(cw * ch)
            if self._pending is not None:
                return  # the next request is drawn at the new size
            # else this view again, smaller: it is all the page will see until the next move
        if req.refine and self._pending is None:
            await self._refine(req, view)

    async def _refine(self, req: protocol.RenderRequest, view: tuple) -> None:
        """The refinement ladder (ladder.py) of the request's view, each picture sent as its pass ends."""
        small = not req.gpu and self._shown_pixels * 4 < req.width * req.height
        steps = ladder.plan(req.width, req.height, FULL_SPP, self.pace.seconds_per_pixel, small)
        sc = self.doc.scene(req.width, req.height, FULL_SPP)
        lib = await self.builds.library(sc)
        if self._pending is not None:  # overtaken while the scene was being built
            return
        ticket = self._ticket(req.width, req.height, FULL_SPP, "render", "render", self.work.limits.render_budget)
        ticket.begin_pass(1, 1.0)  # (a row of the first pass)
        ticket.check_rows(self._cost)
        self._ladder, self._live, self._live_full = [view, req.seq], ticket, True
        try:
            send = functools.partial(self._send_picture, view=view)
            done = await ladder.refine(self.work, ticket, sc, lib, steps, self.threads, send)
        finally:
            self._ladder, self._live, self._cost = None, None, ticket.cost or self._cost
        if not done and ticket.expired:
            raise ticket.over_budget()

    async def _send_picture(self, p: ladder.Picture, view: tuple) -> None:
        kind, flags = LADDER_KINDS[p.step.role], FLAG_EMPTY if p.empty else 0
        head = SAMPLES.pack(self._ladder[1], kind, flags, p.step.k1 if kind == KIND_MORE else 0, p.width, p.height)
        if kind == KIND_FULL:  # from now on a request for this view gets this picture again (request, _frames)
            self._final, self._ladder = (view, p.width, p.height, p.data, p.empty), None
        await self.send(head + p.data)
        self.frames += 1

    async def _send_frame(self, seq: int, kind: int, width: int, height: int, data: bytes, empty: bool) -> None:
        await self.send(HEADER.pack(seq, kind, FLAG_EMPTY if empty else 0, width, height) + data)
        self.frames += 1

    async def _render(
        self, width: int, height: int, spp: int, encode: Callable, full: bool, cut: bool = False
    ) -> tuple[tuple[bytes, bool] | None, Ticket | None]:
        """The document's current view, encoded, and its ticket; no bytes when a newer request cancelled it (a
        refined frame) or when it was `cut` after pace.CUT seconds (a coarse frame: ticket.expired says so).
        Over the render budget: a UserError saying what the surface costs."""
        sc = self.doc.scene(width, height, spp)
        lib = await self.builds.library(sc)
        if full and self._pending is not None:  # overtaken while the scene was being built
            return None, None
        budget = min(CUT, self.work.limits.render_budget) if cut else self.work.limits.render_budget
        ticket = self._ticket(width, height, spp, "render", "render", budget)
        ticket.check_rows(self._cost)
        self._live, self._live_full = ticket, full
        t0 = time.perf_counter()
        try:
            data = await self.work.trace(self.work.render, ticket, frames.trace, sc, lib, spp, self.threads, encode)
        finally:
            self._seconds = time.perf_counter() - t0  # the render and its encoding, as the page waits for them
            self._live = None
            self._cost = ticket.cost or self._cost
        if data is None and ticket.expired and not cut:
            raise ticket.over_budget()
        return data, ticket

    def _ticket(self, width: int, height: int, spp: int, what: str, source: str, budget: float) -> Ticket:
        """A C render's ticket, its messages naming what is rendered: the scene file, else the shape."""
        name = Path(self.doc.base.source).name if self.doc.base is not None else self.doc.spec.name
        return Ticket(budget, what, source, width, spp, self.threads, name=name, height=height)

    async def _save_png(self, width: int, height: int, spp: int) -> None:
        """The current view at any size: the same C render context and samples as render(), and the PNG encoder
        write_png uses (the same bytes as `implgen render` writes for this scene)."""
        try:
            sc = self.doc.scene(width, height, spp)
            lib = await self.builds.library(sc)
            ticket = self._ticket(width, height, spp, "save", "save_png", self.work.limits.save_budget)
            ticket.check_rows(self._cost)
            self._save = ticket
            data = await self.work.trace(
                self.work.save, ticket, frames.trace, sc, lib, spp, self.threads, frames.file_png
            )
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
        await self.send(HEADER.pack(0, KIND_SAVE, 0, width, height) + data[0])

    async def _failed(self, err: Exception, what: str) -> None:
        """Tell the page what failed; a bug (not bad input) also goes to the log with its traceback."""
        if not isinstance(err, UserError):
            log.error(what, exc_info=err)
        await self.send(protocol.error_for(err))

    async def _send_glsl(self, doc: Document, shape_id: int, ask: int | None = None) -> None:
        """The `glsl` message of `doc`'s shape, numbered as that shape was (never a newer shape's number); a
        scene's carries the page's `ask` back (gpu.LastScene: derived again only when its program would differ)."""
        try:
            msg = await self._scenes.message(doc, self.work.derive_glsl, ask)
            await self.send({**msg, "shape_id": shape_id})
        except UserError as err:
            await self.send(protocol.error_for(err))

    async def close(self) -> None:
        """The page has gone: cancel its renders and its save, and return once they have stopped."""
        self._pending = None
        for ticket in (self._live, self._save):
            if ticket is not None:
                ticket.cancel()
        running = (self._task, self._saving, self._glsl, *self.fixes.stop())
        tasks = [t for t in running if t is not None and not t.done()]
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)  # work.trace waits for the C threads to stop
        await self.meshes.close()

    def _view(self, req: protocol.RenderRequest) -> tuple:
        """What a request's picture depends on: equal views have equal pictures."""
        return (req.width, req.height, req.values, req.orbit, req.options, id(self.doc.spec))
