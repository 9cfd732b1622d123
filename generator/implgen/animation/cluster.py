"""Dask: where frames and tiles run when they leave this process.

    --local-workers N        a LocalCluster of N worker processes on this machine (scheduler on 127.0.0.1)
    --cluster tcp://H:8786   a running Dask scheduler (`dask scheduler` / `dask worker tcp://H:8786`)

Before a Client is made for `--cluster`, `probe` asks the address who it is, every step under a timeout:
the port is reached within CONNECT_TIMEOUT, and Dask's handshake and an `identity` answer come within
HANDSHAKE_TIMEOUT. Dask's own connect waits for the handshake without a limit, so a port that says nothing
held the command for good, an HTTP server's answer read as a frame length asked NumPy for exabytes, and a
worker's address failed deep in the Client. Each is now one line naming --cluster.

`ordered(client, fn, jobs, ...)` submits one task per job and yields the results in the jobs' order, so the
caller can write frames in order while later ones still render. The tasks in flight follow the workers:
PER_THREAD per worker thread the scheduler has now, looked up again while results come in, so workers that
join later are used, and with none (yet, or any more) the caller is told it waits. Each task has Dask's
`retries`: a task that raises is run again; a task whose worker dies (a crash, a kill, a lost machine) is
rescheduled by the scheduler on another worker. A scheduler lost mid-run is SchedulerLost, which the caller
turns into one line; the frames already written stay. Workers need implgen and a C compiler installed; they
build each scene's library through their own content-hash cache (docs/animation.md).
"""

from __future__ import annotations

import asyncio
import logging
import re
import secrets
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any

from implgen.errors import UserError

MAX_LOCAL_WORKERS = 256
CONNECT_TIMEOUT = 20  # seconds to reach a scheduler's port given with --cluster
HANDSHAKE_TIMEOUT = 10  # seconds, once reached, for Dask's handshake and the answer to `identity`
CLOSE_TIMEOUT = 2  # seconds a client is given to close (a lost scheduler cannot answer)
PER_THREAD = 3  # tasks in flight per worker thread: enough to hide the round trip, little memory
POLL = 0.5  # seconds between looks at the workers while a result is awaited
_ADDRESS = re.compile(r"^(tcp|tls)://[A-Za-z0-9.\-\[\]:]+:[0-9]{1,5}$")


class SchedulerLost(Exception):
    """The connection to the scheduler went away during a run (the tasks in flight are gone with it)."""


def check_address(address: str, option: str = "--cluster") -> str:
    """A scheduler address: tcp://host:port or tls://host:port (host:port is taken as tcp://)."""
    text = address if "://" in address else f"tcp://{address}"
    if not _ADDRESS.match(text):
        raise UserError(option, f"{address[:60]!r} is not a scheduler address like tcp://host:8786")
    return text


def probe(address: str, connect_timeout: float | None = None, handshake_timeout: float | None = None) -> str:
    """Ask `address` who it is, within the timeouts; return the scheduler's type name, or raise a UserError
    naming --cluster: the port cannot be reached, says nothing, does not speak Dask's protocol, or is a
    Dask worker (or another Dask server) rather than a scheduler. The timeouts default to the module's."""
    ct = CONNECT_TIMEOUT if connect_timeout is None else connect_timeout
    ht = HANDSHAKE_TIMEOUT if handshake_timeout is None else handshake_timeout
    with _quiet_dask():
        return asyncio.run(_probe(address, ct, ht))


async def _probe(address: str, connect_timeout: float, handshake_timeout: float) -> str:
    from distributed.comm import connect as dask_connect
    from distributed.comm.addressing import parse_address, parse_host_port
    from distributed.security import Security

    label = "--cluster"
    host, port = parse_host_port(parse_address(address)[1])
    try:  # the port first, on its own timeout: "cannot reach" is not "does not answer"
        _, writer = await asyncio.wait_for(asyncio.open_connection(host, port), connect_timeout)
    except (TimeoutError, OSError) as err:
        why = f"no connection within {connect_timeout:g} s" if isinstance(err, TimeoutError) else err
        raise UserError(label, f"cannot reach a Dask scheduler at {address} ({why})") from None
    writer.close()
    silent = f"{address}: no answer within {handshake_timeout:g} s (not a Dask scheduler, or a stuck one)"
    comm = None
    try:
        deadline = time.monotonic() + handshake_timeout
        args = Security().get_connection_args("client")  # TLS settings from Dask's config, as a Client takes
        comm = await asyncio.wait_for(dask_connect(address, timeout=handshake_timeout, **args), handshake_timeout)
        await comm.write({"op": "identity", "reply": True})
        answer = await asyncio.wait_for(comm.read(), max(0.1, deadline - time.monotonic()))
    except TimeoutError:
        raise UserError(label, silent) from None
    except Exception:  # an HTTP answer read as a frame length (MemoryError), garbage, a closed stream
        raise UserError(label, f"{address}: not a Dask scheduler (the answer is not Dask's protocol)") from None
    finally:
        if comm is not None:
            comm.abort()
    kind = str(answer.get("type", "")) if isinstance(answer, dict) else ""
    if kind.endswith("Scheduler"):
        return kind
    if kind in ("Worker", "Nanny"):
        raise UserError(
            label, f"{address}: a Dask {kind.lower()}, not a scheduler (give the address `dask worker` was given)"
        )
    raise UserError(label, f"{address}: not a Dask scheduler (it answers as {kind[:40] or 'something else'!r})")


@contextmanager
def _quiet_dask():
    """Dask's own log lines off (a lost connection, a refused handshake, a client closed in a hurry): the
    command says what went wrong in one line of its own. Dask's loggers have levels of their own, so each is
    disabled, not their parent."""
    import distributed  # noqa: F401  (its loggers exist once it is imported)

    names = [n for n in logging.root.manager.loggerDict if n == "distributed" or n.startswith("distributed.")]
    loggers = [logging.getLogger(n) for n in names]
    before = [log.disabled for log in loggers]
    for log in loggers:
        log.disabled = True
    try:
        yield
    finally:
        for log, was in zip(loggers, before):
            log.disabled = was


class _InterruptedSyncNoise(logging.Filter):
    """Ctrl-C in a Dask call made from this thread (distributed.utils.sync) before its coroutine has started
    leaves a cancel callback that fails on the event loop (NameError: its `future` is not bound yet), and
    tornado logs it with a traceback after `implgen: interrupted`. Only that record is dropped."""

    def filter(self, record: logging.LogRecord) -> bool:
        err = record.exc_info[1] if record.exc_info else None
        return not (isinstance(err, NameError) and "sync.<locals>.cancel" in record.getMessage())


def _drop_interrupted_sync_noise() -> None:
    log = logging.getLogger("tornado.application")
    if not any(isinstance(f, _InterruptedSyncNoise) for f in log.filters):
        log.addFilter(_InterruptedSyncNoise())


@contextmanager
def connect(local_workers: int | None = None, address: str | None = None):
    """A dask.distributed Client: to the scheduler at `address` (probed first), or to a LocalCluster of
    `local_workers` processes (one task at a time each). Closed, with the local cluster, on exit."""
    from dask.distributed import Client, LocalCluster

    _drop_interrupted_sync_noise()
    if address is not None:
        probe(address)
        with _quiet_dask():
            try:
                client = Client(address, timeout=CONNECT_TIMEOUT)
            except (OSError, TimeoutError) as err:
                raise UserError("--cluster", f"cannot reach a Dask scheduler at {address} ({err})") from None
            try:
                yield client
            finally:
                _close(client)
        return
    cluster = LocalCluster(
        n_workers=local_workers or 1,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
        silence_logs=logging.ERROR,
    )
    try:
        with Client(cluster) as client:
            yield client
    finally:
        with _quiet_dask():  # the connections the kill cuts are expected, not news
            _kill_local_workers(cluster)
            cluster.close()


def _kill_local_workers(cluster: Any) -> None:
    """End this LocalCluster's worker processes at once, at the end of a run as on Ctrl-C: they hold nothing
    (frames are written here), and their nannies stop them one by one, in 1 to 2 s on 2 cores (in the middle
    of a task after Ctrl-C, about 2 s); killed first, the cluster closes in a few ms."""
    import os
    import signal

    for nanny in list(getattr(cluster, "workers", {}).values()):
        pid = getattr(getattr(getattr(nanny, "process", None), "process", None), "pid", None)
        if pid:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:  # gone already
                pass


def _close(client: Any) -> None:
    """Close a client in bounded time: after a lost scheduler it would otherwise try to reach it again."""
    try:
        client.close(timeout=CLOSE_TIMEOUT)
    except Exception:  # a timeout, or a connection already gone: nothing is left to tidy
        pass


def local_threads(workers: int) -> int:
    """Render threads per task when `workers` processes share this machine's cores."""
    from implgen.scene.render import usable_cores

    return max(1, usable_cores() // max(1, workers))


def tag_of(index: Any) -> str:
    """A job index as it appears in task keys and messages: a frame number, or frame-tile."""
    return "-".join(map(str, index)) if isinstance(index, tuple) else str(index)


def slots(client: Any) -> int:
    """Worker threads the scheduler has now (0 while no worker is connected). A scheduler that cannot be
    asked (the connection is closed or refused) is lost."""
    try:
        return sum(client.nthreads().values())
    except OSError as err:  # CommClosedError is one
        raise SchedulerLost(type(err).__name__) from None


class _Window:
    """The tasks of one `ordered` run submitted and not yet yielded, and what it knows of the workers: how many
    threads they have (looked up again at most every `poll` seconds) and how many looks in a row found none."""

    def __init__(self, client: Any, jobs: Iterable[tuple[Any, tuple]], poll: float, say) -> None:
        self.client, self.todo, self.poll, self.say = client, iter(jobs), poll, say
        self.pending: deque = deque()
        self.more = True
        self.threads, self.looked = slots(client), time.monotonic()
        self.idle = 1 if self.threads == 0 else 0  # looks in a row that found no worker

    def look(self) -> None:
        if time.monotonic() - self.looked < self.poll:
            return
        if self.client.status != "running":  # reconnecting, or closed: the scheduler is gone
            raise SchedulerLost(self.client.status)
        self.threads, self.looked = slots(self.client), time.monotonic()
        self.idle = self.idle + 1 if self.threads == 0 else 0
        if self.idle == 2 and self.say is not None:  # twice in a row: a closing cluster (workers first) says nothing
            self.say("waiting for Dask workers: none is connected to the scheduler")

    def fill(self, size: int, submit: Callable[[Any, tuple], Any]) -> None:
        """Submit jobs until `size` are pending or none is left."""
        while self.more and len(self.pending) < size:
            job = next(self.todo, None)
            if job is None:
                self.more = False
                return
            fut = submit(*job)
            ready = threading.Event()  # set from Dask's callback thread when the task ends, however it ends
            fut.add_done_callback(lambda _fut, ready=ready: ready.set())
            self.pending.append((job[0], fut, ready))


def _first_result(win: _Window) -> tuple[bool, Any]:
    """Wait up to `poll` for the oldest pending task: (True, its result), or (False, None) when it is not done
    yet. Its own error is raised; a lost worker or scheduler in one line. The wait is this module's, and the
    result is asked of Dask only once the task has ended: Dask's own wait with a timeout (Future.result)
    could, on a busy machine, end in its internal UnboundLocalError rather than a timeout."""
    from distributed import KilledWorker
    from distributed.client import FutureCancelledError

    index, fut, ready = win.pending[0]
    if not ready.wait(win.poll) and not fut.done():
        return False, None
    try:
        return True, fut.result()
    except KilledWorker:  # every retry lost its worker: one line, not Dask's traceback
        raise UserError(
            "render", f"task {tag_of(index)} lost its worker more often than the scheduler allows"
        ) from None
    except FutureCancelledError as err:
        if err.reason == "scheduler-connection-lost" or win.client.status != "running":
            raise SchedulerLost(err.reason) from None
        raise


def ordered(
    client: Any,
    fn: Callable[..., Any],
    jobs: Iterable[tuple[Any, tuple]],
    *,
    retries: int,
    name: str = "implgen",
    per_thread: int = PER_THREAD,
    window: int | None = None,
    poll: float = POLL,
    say: Callable[[str], None] | None = None,
) -> Iterator[tuple[Any, Any]]:
    """Run fn(*args) for each (index, args) of `jobs` on the cluster; yield (index, result) in job order,
    with at most `per_thread` tasks submitted and not yet yielded per worker thread the scheduler has (at
    least `per_thread`), or a fixed `window` of them when given (the benchmark's). The workers are looked up
    again at most every `poll` seconds while results come in or are awaited; `say` is told when there are
    none. A lost scheduler raises SchedulerLost."""
    run = secrets.token_hex(4)

    def submit(index: Any, args: tuple) -> Any:
        return client.submit(fn, *args, key=f"{name}-{run}-{tag_of(index)}", retries=retries, pure=False)

    win = _Window(client, jobs, poll, say)
    try:
        while True:
            win.fill(window or per_thread * max(1, win.threads), submit)
            if not win.pending:
                return
            done, result = _first_result(win)
            if done:
                index, fut, _ = win.pending.popleft()
                fut.release()
            win.look()
            if done:
                yield index, result
    except SchedulerLost:
        win.pending.clear()  # gone with the scheduler: nothing to cancel
        raise
    finally:
        for _, fut, _ in win.pending:
            fut.cancel()
