"""`--cluster` pointed at things that are not a working Dask scheduler (issue 22, item 6), and Ctrl-C.

Every address is on 127.0.0.1: a socket that accepts and says nothing, an HTTP server, a worker of a real
LocalCluster, a scheduler that goes away in the middle of a run. Each is one line and exit status 2 within
the timeouts. The command is the installed `implgen`, run as a child process.
"""

from __future__ import annotations

import http.server
import logging
import signal
import socket
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
import yaml

from implgen.animation import cluster
from implgen_proc import assert_one_line, implgen, start

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_animation_render import anim_scene  # noqa: E402

distributed = pytest.importorskip("distributed")
cloudpickle = pytest.importorskip("cloudpickle")
cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the workers cannot import this test file

# what a refusal may take: the handshake timeout, the interpreter's start and the imports, on a busy machine
REFUSED_WITHIN = cluster.HANDSHAKE_TIMEOUT + 8


def write_scene(folder: Path, frames: int = 6, **image) -> Path:
    data = anim_scene(frames)
    data["image"].update(image)
    path = folder / "anim.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@contextmanager
def silent_port() -> Iterator[tuple[int, list]]:
    """A TCP port on 127.0.0.1 that accepts connections and never says a word."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    accepted: list = []

    def serve():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            accepted.append(conn)

    threading.Thread(target=serve, daemon=True).start()
    try:
        yield server.getsockname()[1], accepted
    finally:
        server.close()
        for conn in accepted:
            conn.close()


@contextmanager
def http_server() -> Iterator[int]:
    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        yield server.server_address[1]
    finally:
        server.shutdown()
        server.server_close()


@contextmanager
def local_cluster(workers: int):
    from dask.distributed import LocalCluster

    cl = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    )
    try:
        yield cl
    finally:
        cl.close()


def test_a_silent_port_is_one_line_within_the_timeout(tmp_path):
    scene = write_scene(tmp_path)
    with silent_port() as (port, _):
        ran = implgen("render", scene, "-o", tmp_path / "f%d.png", "--cluster", f"tcp://127.0.0.1:{port}", timeout=60)
    assert_one_line(ran, f"--cluster: tcp://127.0.0.1:{port}", "no answer", "not a Dask scheduler")
    assert ran.seconds < REFUSED_WITHIN, ran.seconds  # before: still waiting after minutes
    assert not list(tmp_path.glob("f*.png"))


def test_an_http_server_is_one_line(tmp_path):
    scene = write_scene(tmp_path)
    with http_server() as port:
        ran = implgen("render", scene, "-o", tmp_path / "f%d.png", "--cluster", f"127.0.0.1:{port}", timeout=60)
    assert_one_line(ran, f"--cluster: tcp://127.0.0.1:{port}", "not a Dask scheduler")  # before: a MemoryError
    assert ran.seconds < REFUSED_WITHIN, ran.seconds


def test_a_workers_address_is_one_line(tmp_path):
    scene = write_scene(tmp_path)
    with local_cluster(1) as cl:
        worker = next(iter(cl.scheduler_info["workers"]))
        ran = implgen("render", scene, "-o", tmp_path / "f%d.png", "--cluster", worker, timeout=60)
    assert_one_line(ran, f"--cluster: {worker}", "a Dask worker, not a scheduler")  # before: TypeError
    assert not list(tmp_path.glob("f*.png"))


def test_ctrl_c_while_waiting_for_an_answer_ends_within_2_s(tmp_path):
    scene = write_scene(tmp_path)
    with silent_port() as (port, accepted):
        proc = start("render", scene, "-o", tmp_path / "f%d.png", "--cluster", f"tcp://127.0.0.1:{port}")
        try:
            deadline = time.monotonic() + 30
            while not accepted and time.monotonic() < deadline:
                time.sleep(0.05)
            assert accepted, "the command never connected"
            time.sleep(0.5)
            proc.send_signal(signal.SIGINT)
            t0 = time.monotonic()
            out, err = proc.communicate(timeout=20)
            seconds = time.monotonic() - t0
        finally:
            proc.kill()
    assert seconds < 2.0, (seconds, err[-2000:])
    assert proc.returncode == 130 and err == "implgen: interrupted\n", (proc.returncode, err[-2000:])


def interrupt_after_two_frames(args: list, out: Path) -> tuple[float, int, str]:
    """Start the command, Ctrl-C it once two frames are written: (seconds to exit, status, stderr)."""
    proc = start(*args)
    try:
        deadline = time.monotonic() + 90
        while len(list(out.parent.glob("f*.png"))) < 2:
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=30)
        return time.monotonic() - t0, proc.returncode, err
    finally:
        proc.kill()


@pytest.mark.parametrize("where", ["--local-workers", "--cluster"])
def test_ctrl_c_during_a_dask_run_ends_within_2_s(tmp_path, where):
    scene = write_scene(tmp_path, frames=40, width=160, height=120, spp=32)
    out = tmp_path / "f" / "f%02d.png"
    args = ["render", scene, "-o", out, "-q"]
    if where == "--local-workers":
        seconds, code, err = interrupt_after_two_frames([*args, "--local-workers", "2"], out)
    else:
        with local_cluster(2) as cl:
            seconds, code, err = interrupt_after_two_frames([*args, "--cluster", cl.scheduler_address], out)
    assert code == 130 and err == "implgen: interrupted\n", (code, err[-3000:])
    assert seconds < 2.0, seconds  # before, --local-workers: 1.2 to 1.9 s, the nannies stopping busy workers


def drop_scheduler(cl) -> None:
    """The scheduler vanishes for its clients, as when its machine dies: it stops listening and its
    connections to clients are cut, with no word to anyone (its workers stay, unseen by the client)."""

    async def drop():
        for listener in cl.scheduler.listeners:
            listener.stop()
        for comm in list(cl.scheduler.client_comms.values()):
            comm.abort()

    cl.sync(drop)


def test_a_lost_scheduler_is_one_line_and_the_rerun_resumes(tmp_path):
    scene = write_scene(tmp_path, frames=40, width=160, height=120, spp=32)
    out = tmp_path / "f" / "f%02d.png"
    with local_cluster(2) as cl:
        proc = start("render", scene, "-o", out, "--cluster", cl.scheduler_address, "--threads", "1", "-q")
        try:
            deadline = time.monotonic() + 60
            while len(list(out.parent.glob("f*.png"))) < 2 and time.monotonic() < deadline:
                time.sleep(0.05)
                assert proc.poll() is None, proc.communicate()
            drop_scheduler(cl)
            t0 = time.monotonic()
            stdout, stderr = proc.communicate(timeout=60)
            seconds = time.monotonic() - t0
        finally:
            proc.kill()
    kept = sorted(p.name for p in out.parent.glob("f*.png"))
    assert 2 <= len(kept) < 40, kept
    assert proc.returncode == 2 and "Traceback" not in stderr and stderr.count("\n") == 1, stderr[-3000:]
    assert "--cluster: lost the Dask scheduler at" in stderr and f"{len(kept)} frames written" in stderr, stderr
    assert seconds < 10, seconds
    ran = implgen("render", scene, "-o", out, "--threads", "2", "-q", timeout=120)  # here, without Dask
    assert ran.code == 0 and "already there" in ran.out, ran.err
    assert f"{40 - len(kept)} frames, {len(kept)} already there" in ran.out, ran.out
