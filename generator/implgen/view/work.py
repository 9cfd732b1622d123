"""The viewer's work and its limits: one bounded pool of threads for each kind of work, a time budget for every
C render, one memory bound for all saves.

    parse   SymPy (a new equation, a scene file, the generated C or YAML) and builds (the compiler): one
            thread, so heavy equations queue up there and never stop the event loop; the libraries built are
            kept for every page that shows the same shapes
    render  the pages' live frames, each encoded on the same thread: a few at once
    save    Save PNG: one at a time; the memory of every save asked for (a mesh's too), running or waiting, is
            reserved when it is asked for and refused beyond the bound
    mesh    Save mesh: one at a time, each thread waiting for its mesh's own process; a pool of its own, so a
            Save PNG never waits behind a mesh
    glsl    the GPU preview's GLSL and Export page (SymPy): one at a time, beside the parse pool, so a new
            equation never waits behind a GLSL derivation; each under the GLSL budget (`derive_glsl`)

A C render (a live frame or a save) runs under a `Ticket`: the page cancels it when a newer request comes or when
it closes, and a timer on the event loop cancels it when its time budget is spent (rt_render_cancel: the C threads
stop after their current row); the render then raises a UserError saying what the surface costs. A cancel takes
effect between rows only, so a render whose single row would outlast its budget (the cost a sample measured by
the page's previous render, times the row's samples) is refused before it starts. The threads are daemons and
`Work.shutdown` cancels every render, so Ctrl-C never waits for one: a parse or a build still running ends with
the process.

A GLSL derivation (gpu.py, sharepage.py) runs under `derive_glsl`: its Chebyshev step
(codegen/backends/glsl/chebform.py, the one part whose time the spec limits do not bound) checks the GLSL budget
and a stop between its small steps, and past them the shader evaluates f's tree as written, which the page is
told. A cancelled caller (a newer request, the
page closed) sets the stop.

A mesh (meshsave.py) is not a C render: it runs `stoppable`, its own time budget and stop checked by the mesh
pipeline between slices of its work (implgen.mesh.budget); a cancelled caller, or `shutdown`, sets the stop.

`Limits` holds every number; `implgen view` reads them from IMPLGEN_VIEW_* environment variables
(docs/viewer.md#limits), which the tests set small.
"""

from __future__ import annotations

import asyncio
import os
import queue
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping
from concurrent.futures import Executor, Future
from dataclasses import dataclass, fields
from typing import Any

from implgen import validate
from implgen.errors import UserError

MB = 2**20
LIBRARIES = 16  # built scene libraries kept for the pages (by the identity of their shapes' specs)
# What one saved pixel holds at the peak of a save: the float image (12 bytes) and its 8-bit copy (3), then the
# copy Pillow encodes from (3) and the PNG bytes (up to about 3, twice while they are copied out); the 8-bit
# image is made band by band (session.py), so there are no float temporaries of the whole picture. Measured
# 16.6 bytes a pixel on a 4096 x 4096 save of a torus (whose PNG is small); 39 before banding.
SAVE_BYTES_PER_PIXEL = 24


@dataclass(frozen=True)
class Limits:
    max_pages: int = 8  # pages connected at once, each counted until its last piece of work has ended
    render_budget: float = 20.0  # seconds of one live frame's C render
    save_budget: float = 300.0  # seconds of one save's C render
    mesh_budget: float = 120.0  # seconds of one Save mesh
    glsl_budget: float = 10.0  # seconds of a GLSL derivation (GPU preview, Export page): then f's tree as written
    save_memory: float = 2048.0  # MB reserved by all saves, running or waiting
    idle: float = 600.0  # seconds a page may send nothing before it is closed
    ping: float = 20.0  # seconds between WebSocket pings, and for the answer: a vanished peer is closed
    request: float = 10.0  # seconds a connection has to send a whole request (connections.py)
    max_connections: int = 256  # connections at once, fewer when the file-descriptor limit says so (connections.py)
    parse_threads: int = 1  # SymPy holds the GIL: a second thread parses no faster and slows the event loop
    render_threads: int = 4
    save_threads: int = 1
    mesh_threads: int = 1
    glsl_threads: int = 1

    @staticmethod
    def from_env(env: Mapping[str, str] = os.environ) -> Limits:
        """The limits with any IMPLGEN_VIEW_<NAME> variable over the default (a bad value: one-line UserError)."""
        given: dict[str, Any] = {}
        for f in fields(Limits):
            name = f"IMPLGEN_VIEW_{f.name.upper()}"
            if name in env:
                whole = isinstance(f.default, int)
                value = validate.number(name, "", env[name], 1 if whole else 0.01, 1e6, text_ok=True)
                if whole and value != int(value):
                    raise UserError(name, f"expected a whole number, not {env[name]!r}")
                given[f.name] = int(value) if whole else value
        return Limits(**given)


class Pool(Executor):
    """A fixed set of daemon threads taking work in order (concurrent.futures' pool joins its threads at exit:
    a render would hold Ctrl-C up)."""

    def __init__(self, name: str, threads: int):
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self._closed = False
        for i in range(threads):
            threading.Thread(target=self._work, name=f"implgen-view-{name}-{i}", daemon=True).start()
        self.threads = threads

    def submit(self, fn: Callable, /, *args, **kwargs) -> Future:
        if self._closed:
            raise RuntimeError("the pool is shut down")
        fut: Future = Future()
        self._queue.put((fut, fn, args, kwargs))
        return fut

    def _work(self) -> None:
        while True:
            item = self._queue.get()
            if item is None:
                return
            fut, fn, args, kwargs = item
            if not fut.set_running_or_notify_cancel():
                continue
            try:
                fut.set_result(fn(*args, **kwargs))
            except BaseException as err:  # the awaiting coroutine raises it
                fut.set_exception(err)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Stop taking work; what waits is cancelled. Never waits for the running work (daemon threads)."""
        self._closed = True
        while True:
            try:
                item = self._queue.get_nowait()
            except queue.Empty:
                break
            if item is not None:
                item[0].cancel()
        for _ in range(self.threads):
            self._queue.put(None)


class Ticket:
    """The handle of one C render of `width` pixels a row at `spp` samples on `threads` threads, from before it
    starts to after it ends: cancel it (a newer request, the page closed) or let its budget run out, from the event
    loop, whatever the worker thread is doing. `what` and `source` name it in messages ("save", "save_png"), `name`
    what is rendered (the scene file, or the shape). A render in passes (view/ladder.py) runs each under
    `begin_pass`, each with the whole budget; `total` is then its samples a pixel, `shown` those sent so far."""

    def __init__(self, budget: float, what: str, source: str, width: int, spp: int, threads: int, name="", height=0):
        self.budget, self.what, self.source = budget, what, source
        self.width, self.spp, self.threads = width, spp, threads
        self.name, self.height, self.total = name or "the scene", height, spp
        self.share = 1.0  # the share of the pixels the run (a pass) renders
        self.passes = False  # the render is made in passes (begin_pass)
        self.shown = 0  # samples a pixel of the last whole picture a pass sent (view/ladder.py)
        self._lock = threading.Lock()
        self._job = None  # the RenderJob while it exists
        self._cancelled = False
        self._started = 0.0
        self.expired: tuple[float, int] | None = None  # (seconds, rows done) when the budget stopped it
        self.cost: float | None = None  # core seconds a sample, measured once the run has ended
        self._timer: asyncio.TimerHandle | None = None

    @property
    def cancelled(self) -> bool:
        return self._cancelled

    def cancel(self) -> None:
        with self._lock:
            self._cancelled = True
            if self._job is not None:
                self._job.cancel()

    def begin_pass(self, samples: int, share: float) -> None:
        """Worker thread, before `attach`: the next run is a pass of `samples` samples over `share` of the pixels."""
        self.spp, self.share, self.passes = samples, share, True

    def attach(self, job, loop: asyncio.AbstractEventLoop) -> None:
        """Worker thread: the RenderJob is about to run; cancelled already, it stops at once; the budget starts."""
        with self._lock:
            self._job = job
            self._started = time.monotonic()
            if self._cancelled:
                job.cancel()
        loop.call_soon_threadsafe(self._arm)

    def detach(self) -> None:
        """Worker thread: the run has ended (the job is freed next); what a sample cost is kept."""
        with self._lock:
            job, self._job = self._job, None
        rows = job.progress() if job is not None else 0
        if rows:
            self.cost = job.seconds * self.threads / (rows * self.width * self.share * self.spp)

    def _arm(self) -> None:
        """Event loop: the budget's timer for the run going on (a pass's replaces the last pass's)."""
        with self._lock:
            self.disarm()
            if self._job is not None:
                left = self.budget - (time.monotonic() - self._started)
                self._timer = asyncio.get_running_loop().call_later(max(0.0, left), self._expire)

    def _expire(self) -> None:
        with self._lock:
            spent = time.monotonic() - self._started
            late = spent < self.budget  # an earlier pass's timer, come after this pass began: not this one's
            if self._job is not None and not self._cancelled and not late:
                self.expired = (spent, self._job.progress())
                self._job.cancel()
        if late:
            self._arm()

    def disarm(self) -> None:
        """Event loop, once the render has ended."""
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None

    def _cost_text(self, per_pixel: str, samples: int) -> str:
        return f"{self.name} costs {per_pixel} a pixel{f' at {samples} samples' if samples > 1 else ''}"

    def over_budget(self) -> UserError:
        """The message for a render its budget stopped: what it renders and what that costs (core time a pixel,
        at one sample for a render in passes), and what to do."""
        seconds, rows = self.expired or (self.budget, 0)
        samples = 1 if self.passes else self.spp
        pixels = self.width * self.share * self.spp / samples  # pixels at `samples` a pixel a row
        if rows:
            cost = f"{seconds * self.threads / (rows * pixels) * 1e3:.2g} ms"
        else:  # no row finished: each thread spent the time on less than one row
            cost = f"more than {seconds / pixels * 1e3:.2g} ms"
        size, budget = f"{self.width} × {self.height}", f"{self.budget:g} s"
        if self.what == "save":
            stopped = f"the {size} save stopped after {budget}: try fewer samples or fewer pixels"
        elif self.shown:
            stopped = (
                f"its {size} picture stopped at {self.shown} of {self.total} samples a pixel (a pass ran past the "
                f"{budget} budget): a smaller window gets all {self.total} in time"
            )
        else:
            stopped = (
                f"its {size} picture stopped after {budget}: try a smaller window, or a larger budget "
                "(IMPLGEN_VIEW_RENDER_BUDGET)"
            )
        return UserError(self.source, f"{self._cost_text(cost, samples)}: {stopped}")

    def check_rows(self, cost: float | None) -> None:
        """Refuse, before it starts, a render one row of which would outlast the budget at `cost` core seconds a
        sample (None: not known yet): a cancel takes effect only between rows."""
        if cost is None:
            return
        row = cost * self.width * self.spp  # one thread renders a whole row
        if row > self.budget:
            costs = self._cost_text(f"{cost * self.spp * 1e3:.2g} ms", self.spp)
            raise UserError(
                self.source,
                f"{costs}: a row of {self.width} pixels would take about {row:.3g} s, more than the "
                f"{self.budget:g} s budget of a {self.what}: fewer pixels a row or fewer samples",
            )


class Work:
    """The pools, the save memory and the C renders running now (for shutdown), shared by all pages."""

    def __init__(self, limits: Limits | None = None):
        self.limits = limits or Limits()
        self.parse = Pool("parse", self.limits.parse_threads)
        self.render = Pool("render", self.limits.render_threads)
        self.save = Pool("save", self.limits.save_threads)
        self.mesh = Pool("mesh", self.limits.mesh_threads)
        self.glsl = Pool("glsl", self.limits.glsl_threads)
        self._lock = threading.Lock()
        self._tickets: set[Ticket] = set()
        self._stops: set[threading.Event] = set()  # the meshes running or waiting (stoppable)
        self._save_bytes = 0
        self._libraries: OrderedDict[tuple, tuple[Any, list]] = OrderedDict()  # loop only
        self._waiting: set[asyncio.Future] = set()  # `call`s waiting for a parse or a build (loop only)
        self.closed = False

    def library(self, specs: list) -> Any:
        """The library built for these specs (the same objects) by any page, or None (the event loop only)."""
        key = tuple(map(id, specs))
        hit = self._libraries.get(key)
        if hit is None:
            return None
        self._libraries.move_to_end(key)
        return hit[0]

    def keep_library(self, specs: list, built: Any) -> None:
        self._libraries[tuple(map(id, specs))] = (built, list(specs))  # the specs kept alive with their ids
        while len(self._libraries) > LIBRARIES:
            self._libraries.popitem(last=False)

    async def call(self, pool: Pool, fn: Callable, *args) -> Any:
        """fn(*args) on one of the pool's threads; the event loop waits for it without blocking."""
        if self.closed:
            raise asyncio.CancelledError
        fut = asyncio.wrap_future(pool.submit(fn, *args))
        self._waiting.add(fut)
        try:
            return await fut
        finally:
            self._waiting.discard(fut)

    async def trace(self, pool: Pool, ticket: Ticket, fn: Callable, *args) -> Any:
        """fn(ticket, loop, *args) on the pool: a C render under `ticket`. A cancelled caller cancels the ticket
        and waits for the render to stop (after its current row): its page is counted until then."""
        with self._lock:
            if self.closed:
                raise asyncio.CancelledError
            self._tickets.add(ticket)
        try:
            return await self._shielded(pool.submit(fn, ticket, asyncio.get_running_loop(), *args), ticket.cancel)
        finally:
            ticket.disarm()
            with self._lock:
                self._tickets.discard(ticket)

    async def stoppable(self, pool: Pool, stop: threading.Event, fn: Callable, *args) -> Any:
        """fn(*args) on the pool, fn looking at `stop` as it goes (a mesh): a cancelled caller sets it, takes fn out
        of the pool's queue if it has not started, or waits for it to end (its page is counted until then);
        shutdown sets it too."""
        with self._lock:
            if self.closed:
                raise asyncio.CancelledError
            self._stops.add(stop)
        try:
            return await self._shielded(pool.submit(fn, *args), stop.set)
        finally:
            with self._lock:
                self._stops.discard(stop)

    async def derive_glsl(self, fn: Callable, *args) -> Any:
        """fn(*args, budget, stop) on the glsl pool: a GLSL derivation, `budget` the GLSL budget in seconds (from
        when the pool starts it), `stop` set when the caller is cancelled (`stoppable`)."""
        stop = threading.Event()
        return await self.stoppable(self.glsl, stop, fn, *args, self.limits.glsl_budget, stop)

    async def _shielded(self, work: Future, on_cancel: Callable[[], None]) -> Any:
        """The pool's result for `work`, which a cancel of the caller does not cut short: the caller's cancel calls
        `on_cancel` (fn stops soon), cancels `work` if it still waits in the queue (the pool skips it), else waits
        for it to end -- unless the server is shutting down."""
        fut = asyncio.wrap_future(work)
        fut.add_done_callback(lambda f: f.cancelled() or f.exception())  # heard even when no one waits (Ctrl-C)
        try:
            return await asyncio.shield(fut)
        except asyncio.CancelledError:
            on_cancel()
            work.cancel()  # only a queued item: a running one cannot be cancelled
            if not self.closed:
                await asyncio.wait([fut])
            raise

    def reserve_save(self, pixels: int) -> Callable[[], None]:
        """Reserve a picture's memory, or refuse it in one line; returns the release (call it once, any thread)."""
        return self.reserve(pixels * SAVE_BYTES_PER_PIXEL, "save_png", f"a picture of {pixels} pixels")

    def reserve(self, need: int, source: str, what: str, hint: str = "") -> Callable[[], None]:
        """Reserve `need` bytes of the saves' memory for `what`, or refuse it in one line naming `source` (and
        ending with `hint`); returns the release (call it once, any thread)."""
        bound = self.limits.save_memory * MB
        if need > bound:
            raise UserError(
                source,
                f"{what} needs about {need / MB:.0f} MB; saves may use at most {self.limits.save_memory:g} MB "
                f"together{hint}",
            )
        with self._lock:
            if self._save_bytes + need > bound:
                raise UserError(
                    source,
                    f"the saves in progress use {self._save_bytes / MB:.0f} MB of the {self.limits.save_memory:g} MB "
                    f"allowed and this one needs {need / MB:.0f} MB: try again when they are done",
                )
            self._save_bytes += need
        released = []

        def release() -> None:
            with self._lock:
                if not released:
                    released.append(1)
                    self._save_bytes -= need

        return release

    def shutdown(self) -> None:
        """Cancel every C render, stop waiting for parses and builds (they cannot be stopped: they end with the
        process), and stop the pools, without waiting (Ctrl-C; on the event loop while it runs)."""
        with self._lock:
            self.closed = True
            tickets = list(self._tickets)
            stops = list(self._stops)
        for t in tickets:
            t.cancel()
        for stop in stops:
            stop.set()
        for fut in list(self._waiting):
            try:
                fut.cancel()
            except RuntimeError:  # its loop has ended
                pass
        for pool in (self.parse, self.render, self.save, self.mesh, self.glsl):
            pool.shutdown(wait=False, cancel_futures=True)
