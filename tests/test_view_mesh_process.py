"""The lifetime of Save mesh's child process (view/meshsave.py, mesh/job.py): a Ctrl-C at the terminal (SIGINT to
the whole process group) is the server's one line and leaves no mesh running; a server killed outright leaves no
mesh running on to its budget, and nothing on stderr; a mesh whose page closes while it waits in its pool
never starts a process; a child killed from outside is one line; its budget counts from when the pool starts it;
a bug in the child is its kind on the page and its traceback in the server's log; the child imports nothing of
the viewer."""

from __future__ import annotations

import asyncio
import json
import logging
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from starlette.testclient import TestClient
from websockets.sync.client import connect

from conftest import ROOT
from implgen.mesh.budget import Stopped
from implgen.mesh.job import MeshJob
from implgen.mesh.pipeline import mesh_spec
from implgen.spec.entry import load_spec
from implgen.view import meshsave
from implgen.view.command import document_factory
from implgen.view.server import create_app
from implgen.view.work import Limits, Work
from view_fixtures import mesh_children, running, view_server

HEAVY = ROOT / "examples/mesh/chmutov20.yaml"  # degree 20: seconds of meshing at 128 cells
TORUS = ROOT / "examples/shapes/torus_z.yaml"
GUARD = 60  # seconds: a hang guard, not a timing


@pytest.fixture(scope="module")
def heavy_built():
    mesh_spec(load_spec(HEAVY, cache=True), {}, 4, [], singular=False)  # built and cached for the server's children too


def _start_mesh(ws, srv: subprocess.Popen) -> int:
    """Ask the server for a mesh of the heavy surface at 128 cells; return once its child has read the job (its
    thread watching the server has started): the child's pid."""
    hello = json.loads(ws.recv())
    ws.send(json.dumps({"type": "save_mesh", "cells": 128, "values": hello["values"], "options": hello["options"]}))
    deadline = time.monotonic() + GUARD
    while True:
        assert time.monotonic() < deadline, "no mesh process reading its job"
        kids = mesh_children(srv.pid)
        if kids and len(list(Path(f"/proc/{kids[0]}/task").glob("*"))) >= 2:
            return kids[0]
        time.sleep(0.05)


def _ws(url: str):
    return connect(url.replace("http://", "ws://") + "ws", max_size=2**26)


def _gone(pid: int) -> bool:
    deadline = time.monotonic() + GUARD
    while running(pid):
        if time.monotonic() > deadline:
            return False
        time.sleep(0.05)
    return True


def test_ctrl_c_to_the_process_group_is_one_line_and_leaves_no_mesh(heavy_built) -> None:
    """A terminal's Ctrl-C goes to every process of its foreground group: the server says one line and exits 130
    (cli.py), and its mesh process, in a session of its own, never sees it (no "Process ...:" traceback)."""
    with view_server(str(HEAVY), session=True, stderr=subprocess.PIPE) as (srv, url):
        with _ws(url) as ws:
            kid = _start_mesh(ws, srv)
            os.killpg(srv.pid, signal.SIGINT)
            srv.wait(GUARD)
        assert srv.returncode == 130
        assert srv.stderr.read() == "implgen: interrupted\n"  # one line, no traceback
        assert _gone(kid), "the mesh process outlived the server"


def test_a_killed_server_s_mesh_stops_and_says_nothing(heavy_built) -> None:
    """SIGKILL: the server cannot kill its child, but the child sees its stdin end and stops at its next check,
    long before its budget (300 s), and says nothing on the stderr it shares with the server."""
    env = {**os.environ, "IMPLGEN_VIEW_MESH_BUDGET": "300"}
    with view_server(str(HEAVY), env=env, session=True, stderr=subprocess.PIPE) as (srv, url):
        with _ws(url) as ws:
            kid = _start_mesh(ws, srv)
            srv.kill()
            srv.wait(GUARD)
        _, err = srv.communicate(timeout=GUARD)  # the stderr ends when the child, which shares it, has ended
        assert err == "" and _gone(kid)


def test_a_mesh_cancelled_while_it_waits_in_the_save_pool_never_starts(monkeypatch) -> None:
    ran: list[str] = []

    async def main() -> None:
        work = Work(Limits(save_threads=1))
        gate = threading.Event()
        busy = asyncio.create_task(work.stoppable(work.save, threading.Event(), gate.wait, GUARD))
        stop = threading.Event()
        queued = asyncio.create_task(work.stoppable(work.save, stop, ran.append, "ran"))
        await asyncio.sleep(0)  # both in the pool: one running, one queued behind it
        queued.cancel()  # its page closes
        await asyncio.sleep(0)  # the cancel reaches it
        gate.set()
        await asyncio.wait([busy, queued], timeout=GUARD)
        await work.call(work.save, ran.append, "after")  # the pool has passed the cancelled item
        assert queued.cancelled() and stop.is_set()
        work.shutdown()

    asyncio.run(main())
    assert ran == ["after"]

    # and a mesh whose stop is set by the time the pool starts it starts no process
    monkeypatch.setattr(meshsave.subprocess, "Popen", lambda *a, **k: pytest.fail("a process started"))
    stop = threading.Event()
    stop.set()
    job = MeshJob(load_spec(TORUS, cache=True), {}, [], None, 16)
    with pytest.raises(Stopped):
        meshsave.run(job, 10.0, stop, lambda: pytest.fail("said to be running"))


def test_the_budget_counts_from_when_the_pool_starts_the_mesh(monkeypatch) -> None:
    """The child gets the deadline run() set before it started the child, and the seconds the message names."""
    sent = []
    real = meshsave.write_message

    def write(fd, message):
        sent.append(message)
        real(fd, message)

    monkeypatch.setattr(meshsave, "write_message", write)
    starts = []
    t0 = time.monotonic()
    data, line = meshsave.run(
        MeshJob(load_spec(TORUS, cache=True), {}, [], None, 16),
        30.0,
        threading.Event(),
        lambda: starts.append(time.monotonic()),
    )
    assert line.startswith("saved torus_z.stl: ") and data
    (job, deadline, seconds), = sent  # fmt: skip
    assert seconds == 30.0 and t0 + 30.0 <= deadline <= starts[0] + 30.0


def test_a_bug_in_the_mesh_process_is_its_kind_on_the_page_and_its_traceback_in_the_log(monkeypatch, caplog):
    bad = MeshJob(load_spec(TORUS, cache=True), {}, [], np.zeros((2, 2)), 16)  # a 2 x 2 "transform": place() fails
    with pytest.raises(meshsave.ChildBug) as info:
        meshsave.run(bad, 30.0, threading.Event(), lambda: None)
    assert info.value.kind == "ValueError"
    assert info.value.text.startswith("Traceback (most recent call last):") and "in place" in info.value.text

    monkeypatch.setattr(meshsave, "job_for", lambda *a: bad)
    app = create_app(document_factory(None), threads=2, limits=Limits(idle=GUARD))
    with caplog.at_level(logging.ERROR, "implgen.view"), TestClient(app) as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(
            json.dumps({"type": "save_mesh", "cells": 16, "values": hello["values"], "options": hello["options"]})
        )
        while (reply := ws.receive_json())["type"] != "mesh" or reply["state"] == "running":
            pass
    assert reply == {"type": "mesh", "state": "failed", "text": "internal error: ValueError"}
    logged = [r.getMessage() for r in caplog.records]
    assert any("viewer mesh failed in its process" in m and "in place" in m for m in logged), logged


def test_the_mesh_process_imports_nothing_of_the_viewer() -> None:
    code = "import sys, implgen.mesh.job; print(sorted(m for m in sys.modules if m.startswith('implgen.view')))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout == "[]\n", out


def test_a_mesh_process_killed_from_outside_is_one_line(heavy_built) -> None:
    """The system's OOM killer, say: the page hears how the process ended, in one line."""
    job = MeshJob(load_spec(HEAVY, cache=True), {}, [], None, 128)
    out: list = []

    def mesh() -> None:
        try:
            meshsave.run(job, 300.0, threading.Event(), lambda: None)
        except Exception as err:
            out.append(err)

    t = threading.Thread(target=mesh)
    t.start()
    deadline = time.monotonic() + GUARD
    while not (kids := mesh_children(os.getpid())):
        assert time.monotonic() < deadline, "no mesh process"
        time.sleep(0.05)
    os.kill(kids[0], signal.SIGKILL)
    t.join(GUARD)
    assert [str(e) for e in out] == ["save_mesh: the mesh's process ended with exit code -9: try fewer cells"]


SLOW_CC = """#!/bin/sh
# A compiler that starts its output, then takes a minute (as cc1 on a large source): what Stop must end.
[ "$1" = --version ] && exec cc "$@"
while [ $# -gt 0 ]; do [ "$1" = -o ] && : > "$2"; shift; done
exec sleep 60
"""


def _group(pgid: int) -> list[int]:
    """The processes of process group `pgid` that still run, from /proc."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                fields = (d / "stat").read_text().rsplit(")", 1)[1].split()
            except (OSError, IndexError):
                continue
            if fields[2] == str(pgid) and fields[0] != "Z":
                out.append(int(d.name))
    return out


def _temporaries(cache: Path) -> list[Path]:
    return sorted(p for p in cache.rglob(".tmp-*"))


def test_stop_ends_the_mesh_s_compilers_and_leaves_no_temporary(tmp_path) -> None:
    """The mesh's process was killed by its pid alone, so the compilers of its build ran on under PID 1
    and their `.tmp-*.o` stayed in the cache. Stop now kills the process group (the child's session), and the
    server removes what the child's builds left half written. A cold cache and a compiler that takes a minute:
    Stop comes while they compile."""
    cc = tmp_path / "slowcc"
    cc.write_text(SLOW_CC)
    cc.chmod(0o700)
    cache = tmp_path / "cache"
    env = {**os.environ, "CC": str(cc), "IMPLGEN_CACHE": str(cache)}
    with view_server(str(TORUS), env=env) as (srv, url), _ws(url) as ws:
        hello = json.loads(ws.recv())
        ws.send(json.dumps({"type": "save_mesh", "cells": 16, "values": hello["values"], "options": hello["options"]}))
        deadline = time.monotonic() + GUARD
        while not ((kids := mesh_children(srv.pid)) and len(_group(kids[0])) > 1 and _temporaries(cache)):
            assert time.monotonic() < deadline, "no compiler started by the mesh's process"
            time.sleep(0.05)
        compilers = [pid for pid in _group(kids[0]) if pid != kids[0]]
        ws.send(json.dumps({"type": "stop_mesh"}))
        while (msg := json.loads(ws.recv(GUARD)))["type"] != "mesh" or msg["state"] == "running":
            pass
        assert msg["state"] == "stopped", msg
        assert _gone(kids[0])
        left = [pid for pid in compilers if running(pid)]
        assert not left and not _group(kids[0]), f"compilers of the stopped mesh still run: {left}"
        assert _temporaries(cache) == []


def test_cache_info_counts_temporaries_and_a_build_removes_only_those_whose_writer_has_gone(tmp_path, monkeypatch):
    """A killed build's `.tmp-*` files were not counted by `implgen cache info` (not for a minute) and
    stayed. Each temporary names the process writing it: one whose process runs is "writing" (counted, never
    removed: a concurrent build renames it into place), one whose process has gone is a "leftover", counted and
    removed at the next eviction, whatever the bound."""
    from implgen import cachedir
    from implgen.compile import cachesize

    obj = tmp_path / "cache" / "obj"
    obj.mkdir(parents=True, mode=0o700)
    (tmp_path / "cache").chmod(0o700)
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    gone = int(ended.stdout)  # a process that has ended (and been reaped)
    mine, theirs = (obj / f".tmp-{pid}-{'5a' * 8}.o" for pid in (os.getpid(), gone))  # as cachedir.temp_path
    for path in (mine, theirs):
        path.write_bytes(b"\x7fELF half an object")
    env = {**os.environ, "IMPLGEN_CACHE": str(tmp_path / "cache")}
    cmd = [sys.executable, "-m", "implgen.cli", "cache", "info"]
    info = subprocess.run(cmd, capture_output=True, text=True, env=env)
    assert info.returncode == 0, info.stderr
    lines = {line.split()[0]: line for line in info.stdout.splitlines() if line.startswith("  ")}
    assert " 1 entries" in lines["writing"] and " 1 entries" in lines["leftover"], info.stdout
    assert "total: 2 entries" in info.stdout, info.stdout
    monkeypatch.setenv("IMPLGEN_CACHE", str(tmp_path / "cache"))
    removed = cachesize.evict(bound=10**9)  # far within the bound: only the leftover goes
    assert [u.path for u in removed] == [theirs] and mine.exists() and not theirs.exists()
    cachesize.clear(tmp_path / "cache")  # `implgen cache clear` too leaves what a running build writes
    assert mine.exists()
    named = cachedir.temp_path(obj, ".o")  # the names a build gives its temporaries
    assert cachedir.writer(named.name) == os.getpid() and named.name.endswith(".o")
