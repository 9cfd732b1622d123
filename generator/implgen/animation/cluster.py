"""Dask: where frames and tiles run when they leave this process.

    --local-workers N        a LocalCluster of N worker processes on this machine (scheduler on 127.0.0.1)
    --cluster tcp://H:8786   a running Dask scheduler (`dask scheduler` / `dask worker tcp://H:8786`)

`ordered(client, fn, jobs, ...)` submits one task per job, at most `window` at a time, and yields the results
in the jobs' order, so the caller can write frames in order while later ones still render. Each task has
Dask's `retries`: a task that raises is run again; a task whose worker dies (a crash, a kill, a lost
machine) is rescheduled by the scheduler on another worker. Workers need implgen and a C compiler installed;
they build each scene's library through their own content-hash cache (docs/animation.md).
"""

from __future__ import annotations

import logging
import re
import secrets
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any

from implgen.errors import UserError

MAX_LOCAL_WORKERS = 256
CONNECT_TIMEOUT = 20  # seconds to reach a scheduler given with --cluster
_ADDRESS = re.compile(r"^(tcp|tls)://[A-Za-z0-9.\-\[\]:]+:[0-9]{1,5}$")


def check_address(address: str, option: str = "--cluster") -> str:
    """A scheduler address: tcp://host:port or tls://host:port (host:port is taken as tcp://)."""
    text = address if "://" in address else f"tcp://{address}"
    if not _ADDRESS.match(text):
        raise UserError(option, f"{address[:60]!r} is not a scheduler address like tcp://host:8786")
    return text


@contextmanager
def connect(local_workers: int | None = None, address: str | None = None, threads_per_task: int | None = None):
    """A dask.distributed Client: to `address`, or to a LocalCluster of `local_workers` processes (one task
    at a time each). Closed, with the local cluster, on exit."""
    from dask.distributed import Client, LocalCluster

    if address is not None:
        try:
            client = Client(address, timeout=CONNECT_TIMEOUT)
        except (OSError, TimeoutError) as err:
            raise UserError("--cluster", f"cannot reach a Dask scheduler at {address} ({err})") from None
        try:
            yield client
        finally:
            client.close()
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
        cluster.close()


def local_threads(workers: int) -> int:
    """Render threads per task when `workers` processes share this machine's cores."""
    from implgen.scene.render import usable_cores

    return max(1, usable_cores() // max(1, workers))


def tag_of(index: Any) -> str:
    """A job index as it appears in task keys and messages: a frame number, or frame-tile."""
    return "-".join(map(str, index)) if isinstance(index, tuple) else str(index)


def ordered(
    client: Any,
    fn: Callable[..., Any],
    jobs: Iterable[tuple[Any, tuple]],
    *,
    window: int,
    retries: int,
    name: str = "implgen",
) -> Iterator[tuple[Any, Any]]:
    """Run fn(*args) for each (index, args) of `jobs` on the cluster; yield (index, result) in job order
    with at most `window` tasks submitted and not yet yielded."""
    from distributed import KilledWorker

    run = secrets.token_hex(4)
    todo = iter(jobs)
    pending: deque = deque()

    def submit_one() -> bool:
        job = next(todo, None)
        if job is None:
            return False
        index, args = job
        fut = client.submit(fn, *args, key=f"{name}-{run}-{tag_of(index)}", retries=retries, pure=False)
        pending.append((index, fut))
        return True

    try:
        while len(pending) < max(1, window) and submit_one():
            pass
        while pending:
            index, fut = pending.popleft()
            try:
                result = fut.result()
            except KilledWorker:  # every retry lost its worker: one line, not Dask's traceback
                raise UserError(
                    "render", f"task {tag_of(index)} lost its worker more often than the scheduler allows"
                ) from None
            fut.release()
            submit_one()
            yield index, result
    finally:
        for _, fut in pending:
            fut.cancel()


def serial(fn: Callable[..., Any], jobs: Iterable[tuple[Any, tuple]]) -> Iterator[tuple[Any, Any]]:
    """The same contract in this process, one job after the other."""
    for index, args in jobs:
        yield index, fn(*args)
