"""One mesh made in a process of its own, for the viewer's Save mesh (view/meshsave.py is the server's side).

`python -c CHILD FD` reads one pickled (MeshJob, deadline, seconds) from its stdin, makes the closed
binary STL and writes one pickled reply to the pipe FD: ("ok", bytes, line), ("user", source, message) or
("bug", kind, traceback). The server starts it in a session of its own, so a Ctrl-C at the terminal never
reaches it (the server kills it on Stop, a closed page, Ctrl-C or its budget); it ignores SIGINT all the same.
The server keeps the stdin open while it waits: end of file there means the server has gone (killed, crashed),
and the mesh stops at its next check (budget.Stopped) instead of running on to its budget.

This module imports nothing of the viewer: the child has no viewer state to build (the viewer's document parses
its clip shapes with SymPy at import).
"""

from __future__ import annotations

import os
import pickle
import signal
import struct
import sys
import threading
import time
import traceback
from dataclasses import dataclass

import numpy as np

from implgen.errors import UserError, out_of_files, out_of_files_error
from implgen.mesh.pipeline import closed_and_euler, mesh_spec
from implgen.mesh.region import Clip
from implgen.mesh.write import mesh_bytes, place, vertex_normals
from implgen.spec.parse import Spec

SOURCE = "save_mesh"
LENGTH = struct.Struct("<Q")  # the byte count before each pickle on the pipes


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


def make(job: MeshJob, deadline: float, seconds: float, cancel: threading.Event | None = None) -> tuple[bytes, str]:
    """The STL's bytes and a line saying what they hold. Past `deadline` (time.monotonic(), a budget of
    `seconds`) budget.OverBudget; once `cancel` is set budget.Stopped."""
    t0 = time.monotonic()
    result = mesh_spec(  # no refinement: its memory (up to refine.MAX_FINE fine cells) is not in the estimate
        job.spec, job.values, job.cells, job.clips, False, SOURCE, deadline, cancel, "cells", seconds, refine=False
    )  # fmt: skip
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


def write_message(fd: int, obj) -> None:
    """One pickle, its length first, to a pipe (raises OSError when the reader has gone)."""
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(LENGTH.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view) :]


def read_message(stream):
    """One pickle written by write_message; EOFError when the stream ends first. Only between this package's own
    processes (the server and the child it started): never anything a user sent."""
    head = stream.read(LENGTH.size)
    if len(head) < LENGTH.size:
        raise EOFError
    data = stream.read(LENGTH.unpack(head)[0])
    if len(data) < LENGTH.unpack(head)[0]:
        raise EOFError
    return pickle.loads(data)


def _watch_parent(stdin, cancel: threading.Event) -> None:
    """Set `cancel` when the server's end of our stdin closes (the server has gone)."""
    try:
        while stdin.read(4096):
            pass
    except OSError:
        pass
    cancel.set()


def child(fd: int) -> int:
    """The child process's work: read the job, mesh it, write the reply to `fd`."""
    cancel = threading.Event()
    try:
        job, deadline, seconds = read_message(sys.stdin.buffer)
        threading.Thread(target=_watch_parent, args=(sys.stdin.buffer, cancel), daemon=True).start()
        reply = ("ok", *make(job, deadline, seconds, cancel))
    except UserError as err:
        reply = ("user", err.source, err.message)
    except OSError as err:  # out of descriptors: said as it is; any other: a bug
        said = out_of_files_error(SOURCE, err) if out_of_files(err) else None
        reply = ("user", said.source, said.message) if said else ("bug", type(err).__name__, traceback.format_exc())
    except BaseException as err:  # a bug (or the server gone: no one reads it): its kind and traceback to the log
        reply = ("bug", type(err).__name__, traceback.format_exc())
    try:
        write_message(fd, reply)
    except OSError:  # the server has gone
        return 1
    return 0


def main() -> None:
    """`python -c` entry (CHILD): SIGINT ignored first (the server owns this process's lifetime), the reply, then
    out at once: never a traceback on the server's stderr, no interpreter teardown (a watcher thread may still
    read)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        code = child(int(sys.argv[1]))
    except BaseException:
        code = 1
    os._exit(code)


# the child's command after the interpreter: SIGINT ignored before any import of this package
CHILD = (
    "-c",
    "import signal; signal.signal(signal.SIGINT, signal.SIG_IGN); import implgen.mesh.job as j; j.main()",
)
