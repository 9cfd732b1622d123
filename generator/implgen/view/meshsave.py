"""Save mesh: the shape the page shows, with its param values and its clip, as a closed binary STL made by the
mesh pipeline of `implgen mesh` (docs/mesh.md), for printing.

The picture cuts the surface open at the clip (as SURFER does) but a printed part must be a closed solid, so the
mesh is the solid f < 0 cut by the clip, the cut capped, as `implgen mesh --clip` makes it. With a scene file it
is the picked object alone, cut by its own clip (if the file gives it one) and placed by its transform.

Each mesh has bounds, checked before any work: cells in [MIN_CELLS, MAX_CELLS]; an upper estimate of its memory
(mesh/budget.py) reserved from the saves' memory (work.py); a time budget (Limits.mesh_budget, counted from when
the mesh pool starts it). The mesh is NumPy work in Python that would hold the server's GIL, so it runs in a
child process (mesh/job.py: a fresh interpreter, never a fork of the threaded server, in a session of its own so
that a Ctrl-C at the terminal is the server's alone). The child stops itself at its budget, saying in which
phase, and when the server goes (its stdin ends); a mesh pool thread waits for it and kills it at once on Stop,
when its page closes or at Ctrl-C, or GRACE seconds past its budget; the children left at exit are killed. A
kill is the child's whole process group, so the compilers of a build it started end with it, and what they left
half written in the build cache is removed once the child is reaped (cachedir.remove_temporaries). A page meshes
one shape at a time. The singular-point search of `implgen mesh` is skipped: its time and memory do
not depend on the cells (18 s and 443 MB on a degree-20 surface, bench/results/mesh_budget.md); nodes are
closed around.

The page hears, as `{"type": "mesh", "state": ..., "text": ...}`: `running` (with the file's name), then the
file as a binary frame (session.KIND_MESH) and `done`, or `failed` (one line; a bug in the child is
"internal error: Kind", its traceback in the server's log), or `stopped`.
"""

from __future__ import annotations

import asyncio
import atexit
import logging
import math
import os
import select
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Awaitable, Callable

import numpy as np

from implgen import cachedir
from implgen.errors import UserError, out_of_files, out_of_files_error
from implgen.mesh.budget import OverBudget, Stopped, estimate_bytes
from implgen.mesh.job import CHILD, SOURCE, MeshJob, read_message, write_message
from implgen.mesh.region import Clip, Sphere, box_clips
from implgen.view import protocol
from implgen.view.document import Document, Options
from implgen.view.work import Work

GRACE = 10.0  # seconds a mesh's process may run past its budget (its start, one uncut phase) before it is killed
POLL = 0.05  # seconds between looks at the stop

log = logging.getLogger("implgen.view")
Send = Callable[[dict | bytes], Awaitable[None]]
_children: set[subprocess.Popen] = set()  # the meshes' processes alive now (any mesh thread)
_children_lock = threading.Lock()


class ChildBug(Exception):
    """A bug in the mesh's process: its exception's kind (the page's line) and its traceback (the log)."""

    def __init__(self, kind: str, text: str):
        super().__init__(kind)
        self.kind, self.text = kind, text


def _clips(kind: str, size: float, center=(0.0, 0.0, 0.0)) -> list[Clip]:
    if kind == "sphere":
        return [Sphere(size, tuple(float(c) for c in center))]
    if kind == "box":
        return box_clips([c - size for c in center], [c + size for c in center])
    return []


def job_for(doc: Document, cells: int, values: dict[str, float], options: Options) -> MeshJob:
    """The page's shape (a scene: the picked object, its own clip and transform) at these values and clip."""
    if doc.base is None:
        clips, matrix = _clips(options.clip, options.clip_size), None
    else:
        leaf = doc.leaf
        clip = doc.leaf_clip()  # the file's, or the one the page gave it
        clips = _clips(clip.kind, clip.size, clip.center) if clip is not None else []
        matrix = np.asarray(leaf.matrix, dtype=np.float64) if leaf is not None else None
    box = doc.spec.box(dict(values))
    if not clips and (box is None or not all(math.isfinite(v) for v in box)):
        if doc.base is None:
            raise UserError(
                SOURCE, "the surface runs on without end: choose a sphere or box clip to mesh the solid in it"
            )
        raise UserError(SOURCE, f"{doc.spec.name} runs on without end and the scene gives it no clip: no solid to mesh")
    return MeshJob(doc.spec, dict(values), clips, matrix, cells)


def estimate(job: MeshJob) -> int:
    """Bytes the mesh may need at most (mesh/budget.py)."""
    return estimate_bytes(job.spec.box(job.values), job.spec.degree, job.clips, job.cells, SOURCE)


def run(job: MeshJob, seconds: float, stop: threading.Event, started: Callable[[], None]) -> tuple[bytes, str]:
    """On the mesh pool: the STL's bytes and a line saying what they hold, made in a child process (mesh/job.py).
    The budget starts now, the child's start counted in it; a stop set while this waited in the pool ends it
    before the child is started. The child stops itself at the budget (OverBudget, with its phase) and is killed
    at once on `stop`, or GRACE seconds past the budget when its work is not cut soon enough."""
    deadline = time.monotonic() + seconds  # CLOCK_MONOTONIC: the same clock in the child
    if stop.is_set():
        raise Stopped
    started()
    try:
        child, read_fd = _spawn()
    except OSError as err:  # out of descriptors: that, not "internal error: OSError"
        if out_of_files(err):
            raise out_of_files_error(SOURCE, err) from None
        raise
    with _children_lock:
        _children.add(child)
    receive = os.fdopen(read_fd, "rb")
    try:
        try:
            write_message(child.stdin.fileno(), (job, deadline, seconds))
        except OSError:  # it has ended already: its pipe says so below
            pass
        hard = deadline + GRACE
        ready = select.poll()  # not select(): a busy server's descriptors may pass FD_SETSIZE
        ready.register(read_fd, select.POLLIN)  # the reply's first bytes, or its end (POLLHUP)
        while not ready.poll(POLL * 1000):
            if stop.is_set():
                raise Stopped
            if time.monotonic() > hard:
                raise OverBudget(seconds, job.cells, "killed")
        try:
            kind, *what = read_message(receive)
        except EOFError:
            code = _exit_code(child, GRACE)
            raise UserError(SOURCE, f"the mesh's process ended with exit code {code}: try fewer cells") from None
    finally:
        _end(child)
        receive.close()
    if kind == "ok":
        return what[0], what[1]
    if kind == "user":
        raise UserError(what[0], what[1])
    raise ChildBug(what[0], what[1])


def _spawn() -> tuple[subprocess.Popen, int]:
    """The mesh's process, started in a session (and a process group) of its own, and the pipe it replies on."""
    read_fd, write_fd = os.pipe()
    try:
        child = subprocess.Popen(
            [sys.executable, *CHILD, str(write_fd)],
            stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL,
            pass_fds=(write_fd,),
            start_new_session=True,  # a Ctrl-C at the terminal is the server's: it kills this
        )
    except BaseException:
        os.close(read_fd)
        raise
    finally:
        os.close(write_fd)
    return child, read_fd


def _exit_code(child: subprocess.Popen, timeout: float) -> int | str:
    """The exit code of a child that has ended (negative: the signal that killed it), read without reaping it,
    so that its process group keeps its id until _end has killed what the child started."""
    end = time.monotonic() + timeout
    while True:
        try:
            info = os.waitid(os.P_PID, child.pid, os.WEXITED | os.WNOHANG | os.WNOWAIT)
        except ChildProcessError:  # reaped already
            return child.returncode if child.returncode is not None else "unknown"
        if info is not None:
            return -info.si_status if info.si_code in (os.CLD_KILLED, os.CLD_DUMPED) else info.si_status
        if time.monotonic() > end:
            return "none (it hung up)"
        time.sleep(POLL)


def _kill_group(child: subprocess.Popen) -> None:
    """SIGKILL to the child's process group: the child and the compilers it runs (a build's cc and cc1 would run
    on under PID 1, writing into the cache). Only while the child is not reaped: the group's id is its pid."""
    if child.returncode is None:
        try:
            os.killpg(child.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass


def _end(child: subprocess.Popen) -> None:
    """Kill the child and what it started if they still run, reap it, and remove what its builds left half
    written in the cache (their temporaries are named after the child's pid)."""
    _kill_group(child)
    try:
        child.stdin.close()
    except OSError:
        pass
    try:
        child.wait(GRACE)
    except subprocess.TimeoutExpired:  # a killed process not gone in GRACE s: the kernel's to finish
        pass
    else:
        cachedir.remove_temporaries(child.pid)
    with _children_lock:
        _children.discard(child)


@atexit.register
def _kill_children() -> None:
    """At exit (Ctrl-C: the mesh threads are daemons and may not get their turn), no mesh's process, nor a
    compiler it started, outlives the server."""
    with _children_lock:
        left = list(_children)
    for child in left:
        _kill_group(child)


class MeshSaver:
    """One page's Save mesh: at most one mesh at a time, stopped by Stop or when the page closes."""

    def __init__(self, work: Work, send: Send, send_file: Callable[[bytes], Awaitable[None]]):
        self.work, self.send, self.send_file = work, send, send_file
        self._task: asyncio.Task | None = None
        self._stop: threading.Event | None = None

    async def start(self, doc: Document, data: dict) -> None:
        """Check the request and the memory, then mesh in a task of its own (the page stays interactive); a
        refusal is a `failed` line."""
        try:
            if self._task is not None and not self._task.done():
                raise UserError(SOURCE, "a mesh is already being made: wait for it, or stop it")
            cells, values, options = protocol.parse_save_mesh(data, doc.spec)
            job = job_for(doc, cells, values, options)
            what = f"a mesh of {job.spec.name} at {cells} cells"
            release = self.work.reserve(estimate(job), SOURCE, what, ": try fewer cells")
        except UserError as err:
            await self._tell("failed", str(err))
            return
        self._stop = threading.Event()
        self._task = asyncio.get_running_loop().create_task(self._mesh(job, self._stop))
        self._task.add_done_callback(lambda _: release())

    def stop(self) -> None:
        if self._stop is not None:
            self._stop.set()

    async def _mesh(self, job: MeshJob, stop: threading.Event) -> None:
        loop = asyncio.get_running_loop()
        text = f"meshing {job.spec.name} at {job.cells} cells"

        def started() -> None:  # the mesh pool's thread: the mesh starts now (it may have waited behind another)
            asyncio.run_coroutine_threadsafe(self._tell("running", text, job), loop)

        await self._tell("running", f"{text}: waiting for the meshes before it", job)
        try:
            data, line = await self.work.stoppable(
                self.work.mesh, stop, run, job, self.work.limits.mesh_budget, stop, started
            )
        except Stopped:
            await self._tell("stopped", "meshing stopped")
            return
        except ChildBug as err:  # the page: its kind; the log: the child's traceback
            log.error("viewer mesh failed in its process:\n%s", err.text.rstrip())
            await self._tell("failed", f"internal error: {err.kind}")
            return
        except Exception as err:  # bad input or its budget: one line; a bug: logged too
            if not isinstance(err, UserError):
                log.error("viewer mesh failed", exc_info=err)
            await self._tell("failed", protocol.error_for(err)["message"])
            return
        await self.send_file(data)
        await self._tell("done", line)

    async def _tell(self, state: str, text: str, job: MeshJob | None = None) -> None:
        msg = {"type": "mesh", "state": state, "text": text}
        if job is not None:
            msg["name"] = job.name
        await self.send(msg)

    async def close(self) -> None:
        """The page has gone: stop its mesh and return once it has stopped."""
        if self._task is not None and not self._task.done():
            self._task.cancel()
            await asyncio.gather(self._task, return_exceptions=True)
