"""Save mesh: the shape the page shows, with its param values and its clip, as a closed binary STL made by the
mesh pipeline of `implgen mesh` (docs/mesh.md), for printing.

The picture cuts the surface open at the clip (as SURFER does) but a printed part must be a closed solid, so the
mesh is the solid f < 0 cut by the clip, the cut capped, as `implgen mesh --clip` makes it. With a scene file it
is the picked object alone, cut by its own clip (if the file gives it one) and placed by its transform.

Each mesh has bounds, checked before any work: cells in [MIN_CELLS, MAX_CELLS]; an upper estimate of its memory
(mesh/budget.py) reserved from the saves' memory (work.py); a time budget (Limits.mesh_budget, counted from when
the save pool starts it). The mesh is NumPy work in Python, so it runs in a child process (spawned, never forked
from the threaded server): in the server's own process it held the GIL long enough to cost the other pages
half their frames (bench/view_mesh.py). The child stops itself at its budget, saying in which phase; a save pool
thread waits for it and kills it at once on Stop, when its page closes or at Ctrl-C, or GRACE seconds past its
budget. A page meshes one shape at a time. The singular-point search of `implgen mesh` is skipped: its time and memory
do not depend on the cells (tens of seconds and hundreds of MB on a degree-20 surface); nodes are closed around.

The page hears, as `{"type": "mesh", "state": ..., "text": ...}`: `running` (with the file's name), then the
file as a binary frame (session.KIND_MESH) and `done`, or `failed` (one line), or `stopped`.
"""

from __future__ import annotations

import asyncio
import logging
import math
import multiprocessing
import threading
import time
from collections.abc import Awaitable, Callable
from dataclasses import dataclass

import numpy as np

from implgen.codegen.spec import Spec
from implgen.errors import UserError
from implgen.mesh.budget import OverBudget, Stopped, estimate_bytes
from implgen.mesh.pipeline import closed_and_euler, mesh_spec
from implgen.mesh.region import Clip, Sphere, box_clips
from implgen.mesh.write import mesh_bytes, place, vertex_normals
from implgen.view import protocol
from implgen.view.document import Document, Options
from implgen.view.work import Work

SOURCE = "save_mesh"
GRACE = 10.0  # seconds a mesh's process may run past its budget (its start, one uncut phase) before it is killed
POLL = 0.05  # seconds between looks at the stop

log = logging.getLogger("implgen.view")
Send = Callable[[dict | bytes], Awaitable[None]]


@dataclass
class MeshJob:
    """What to mesh, from validated values only."""

    spec: Spec
    values: dict[str, float]
    clips: list[Clip]
    matrix: np.ndarray | None  # object -> world (a scene's object), or None
    cells: int

    @property
    def name(self) -> str:
        return f"{self.spec.name}.stl"  # a spec name is an identifier (checked by the spec parser)


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
        clip = leaf.clip if leaf is not None else None
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
    """On the save pool: the STL's bytes and a line saying what they hold, made in a child process (`make`). The
    budget starts now; the child stops itself at it (OverBudget, with its phase) and is killed at once on `stop`,
    or GRACE seconds past the budget when its work is not cut soon enough."""
    started()
    ctx = multiprocessing.get_context("spawn")  # a fresh interpreter: never a fork of the threaded server
    receive, send = ctx.Pipe(duplex=False)
    child = ctx.Process(target=_child, args=(job, seconds, send), name="implgen-view-mesh", daemon=True)
    hard = time.monotonic() + seconds + GRACE
    child.start()
    send.close()
    try:
        while not receive.poll(POLL):
            if stop.is_set():
                raise Stopped
            if time.monotonic() > hard:
                raise OverBudget(seconds, job.cells, "killed")
            if not child.is_alive() and not receive.poll(0):
                raise UserError(SOURCE, f"the mesh's process ended with exit code {child.exitcode}: try fewer cells")
        try:
            kind, *what = receive.recv()
        except EOFError:
            raise UserError(SOURCE, f"the mesh's process ended with exit code {child.exitcode}") from None
    finally:
        if child.is_alive():
            child.kill()
        child.join(GRACE)
        receive.close()
    if kind == "ok":
        return what[0], what[1]
    if kind == "user":
        raise UserError(what[0], what[1])
    raise RuntimeError(f"in the mesh's process: {what[0]}")


def _child(job: MeshJob, seconds: float, send) -> None:
    """The child process: make the mesh, send ("ok", bytes, line), ("user", source, message) or ("bug", text)."""
    try:
        reply = ("ok", *make(job, time.monotonic() + seconds))
    except UserError as err:
        reply = ("user", err.source, err.message)
    except Exception as err:  # a bug: its kind and text to the server's log
        reply = ("bug", f"{type(err).__name__}: {err}")
    send.send(reply)
    send.close()


def make(job: MeshJob, deadline: float) -> tuple[bytes, str]:
    """The STL's bytes and a line saying what they hold (in the child process)."""
    t0 = time.monotonic()
    result = mesh_spec(job.spec, job.values, job.cells, job.clips, False, SOURCE, deadline, cells_name="cells")
    verts, faces = result.mesh.vertices, result.mesh.faces
    normals = vertex_normals(result.lib, result.clips, verts)
    if job.matrix is not None:
        verts, faces, normals = place(job.matrix, verts, faces, normals)
    closed, euler = closed_and_euler(faces, len(verts))
    data = mesh_bytes("stl", verts, faces, normals)
    shape = "closed" if closed else "NOT closed"
    line = (
        f"saved {job.name}: {len(faces)} triangles at {job.cells} cells, {shape}, Euler characteristic {euler} "
        f"({time.monotonic() - t0:.1f} s)"
    )
    return data, line


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

        def started() -> None:  # the save pool's thread: the mesh starts now (it may have waited behind saves)
            asyncio.run_coroutine_threadsafe(self._tell("running", text, job), loop)

        await self._tell("running", f"{text}: waiting for the saves before it", job)
        try:
            data, line = await self.work.stoppable(
                self.work.save, stop, run, job, self.work.limits.mesh_budget, stop, started
            )
        except Stopped:
            await self._tell("stopped", "meshing stopped")
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
