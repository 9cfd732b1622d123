"""The viewer's connections, bounded: in time while a request is being sent, in number below the process's
file-descriptor limit, and quiet when the descriptors run out all the same.

- **Time.** uvicorn times out a kept-alive connection between requests, but not one that never finishes its
  request: a client that sent half a request head (or stopped in its body) held its connection and its
  descriptor for ever. `BoundedH11` (uvicorn's h11 protocol) gives each request `Limits.request` seconds,
  counted from the connection's start or from the end of the previous answer, to arrive whole; past them the
  connection is closed. Beyond loopback the token is only seen once the request is whole, so this also bounds a
  client without it. Once its request is whole a WebSocket is uvicorn's other protocol, bounded by its pings
  and the page's idle time (server.py).
- **Number.** At most `connection_cap` connections at once: `Limits.max_connections`, fewer when RLIMIT_NOFILE
  leaves less after RESERVE descriptors for what the server opens besides (cache files, the compilers' pipes,
  the meshes' processes). `Listener` keeps the cap where the descriptors are made (asyncio accepts up to its
  backlog before any protocol sees one, so the backlog is kept to a quarter of the cap): at the cap a new
  connection closes the one that has been sending its request the longest, so half-sent requests cannot keep a
  page out; when every connection has sent its request, the new one is answered 503 and closed.
- **Running out.** Should the descriptors run out anyway, asyncio's accept loop logs a traceback for each try
  left in its backlog (uvicorn's default: 2048), and again each second (96,217 in 15 s were measured). After a
  failed accept `Listener.accept` says "nothing to accept" for HOLD seconds, which ends that loop, and
  `quiet_accept_errors` makes the report one line a minute.
"""

from __future__ import annotations

import asyncio
import errno
import logging
import os
import resource
import socket
import time
import weakref
from collections.abc import Callable

import h11
from uvicorn.protocols.http.h11_impl import H11Protocol

from implgen.errors import UserError

log = logging.getLogger("implgen.view")

RESERVE = 64  # descriptors kept for the server's own files, besides its connections ...
RESERVE_PER_CPU = 8  # ... and for each core: a compile's pipes (the build compiles one source a core at once)
MIN_CAP = 8  # fewer connections than this and a page cannot load: refuse to start
OUT_OF_RESOURCES = (errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM)  # what asyncio's accept backs off on
HOLD = 0.5  # seconds an accept says "nothing to accept" after one failed for want of descriptors
LOG_EVERY = 60.0  # seconds between two lines saying the descriptors have run out, or that the cap turned one away
REFUSED = b"HTTP/1.1 503 Service Unavailable\r\nConnection: close\r\nContent-Length: 21\r\n\r\ntoo many connections\n"


def connection_cap(wanted: int, nofile: int | None = None, cpus: int | None = None) -> int:
    """The most connections at once: `wanted`, or fewer when RLIMIT_NOFILE's soft limit (`nofile`) leaves less
    after the reserve. A limit that leaves fewer than MIN_CAP is a UserError (`implgen view` exits 2)."""
    if nofile is None:
        nofile = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
    if nofile == resource.RLIM_INFINITY:
        return wanted
    reserve = RESERVE + RESERVE_PER_CPU * (cpus or os.cpu_count() or 1)
    if nofile - reserve < MIN_CAP:
        raise UserError(
            "ulimit -n",
            f"this process may open {nofile} files, and the viewer keeps {reserve} of them for its builds and "
            f"meshes, which leaves fewer than {MIN_CAP} for connections: raise the limit (e.g. ulimit -n 1024)",
        )
    return min(wanted, nofile - reserve)


class _Every:
    """Whether a rate-limited line may be said now (at most once every LOG_EVERY seconds)."""

    def __init__(self) -> None:
        self.last = -LOG_EVERY

    def now(self) -> bool:
        t = time.monotonic()
        if t - self.last < LOG_EVERY:
            return False
        self.last = t
        return True


_refusals = _Every()
_out_of_files = _Every()


class BoundedH11(H11Protocol):
    """uvicorn's h11 protocol with a time for each request to arrive whole: `request`, the class attribute of the
    subclass `protocol_class` makes."""

    request: float = 10.0

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.waiting_since: float | None = None  # loop time from which a request is awaited
        self._timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._await_request()

    def on_response_complete(self) -> None:
        super().on_response_complete()
        if not self.transport.is_closing():
            self._await_request()  # kept alive: the next request has its own time

    def connection_lost(self, exc: Exception | None) -> None:
        if self._timer is not None:
            self._timer.cancel()
            self._timer = None
        super().connection_lost(exc)

    def sending(self) -> bool:
        """Whether the client is still sending a request (its head or its body) on this connection, ours still."""
        if self.transport is None or self.transport.is_closing() or self.transport.get_protocol() is not self:
            return False
        return self.conn.their_state in (h11.IDLE, h11.SEND_BODY)

    def _await_request(self) -> None:
        if self._timer is not None:
            self._timer.cancel()
        self.waiting_since = self.loop.time()
        self._timer = self.loop.call_later(self.request, self._time_is_up)

    def _time_is_up(self) -> None:
        """`request` seconds since a request was awaited: a connection whose request is not whole is closed (a
        complete one is being answered: on_response_complete starts the next wait)."""
        self._timer = None
        if self.sending():
            self.transport.abort()


def protocol_class(request: float) -> type[BoundedH11]:
    """The HTTP protocol for uvicorn's Config(http=...): BoundedH11 with this time for a request."""
    return type("BoundedH11", (BoundedH11,), {"request": float(request)})


def make_room(connections: set) -> int | None:
    """Close the connection (of uvicorn's set) that has been sending its request the longest: its socket's
    descriptor, or None when every connection has sent its request."""
    slow = [c for c in connections if isinstance(c, BoundedH11) and c.sending()]
    if not slow:
        return None
    oldest = min(slow, key=lambda c: c.waiting_since if c.waiting_since is not None else 0.0)
    fd = oldest.transport.get_extra_info("socket").fileno()
    connections.discard(oldest)  # its connection_lost comes later: it no longer counts from now
    oldest.transport.abort()  # its socket is closed on the loop's next turn
    return fd


class Listener(socket.socket):
    """The listening socket: at most `cap` of the connections it accepted open at once (None: no cap). asyncio
    accepts up to its backlog at once before any protocol sees them, so the cap is kept here, where the
    descriptors are made: at the cap `make_room` (set by the server: the function above on uvicorn's connections)
    closes the slowest sender, or, when every connection has sent its request, the new one is answered 503 and
    closed at once.

    After an accept fails for want of descriptors, asyncio stops watching the socket for a second but goes on
    accepting for the rest of its backlog (each try logged): for HOLD seconds this says there is nothing to
    accept instead, which ends that loop."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.cap: int | None = None
        self.make_room: Callable[[], int | None] | None = None
        self.held_until = 0.0
        self.accepted: weakref.WeakSet[socket.socket] = weakref.WeakSet()
        self.leaving: weakref.WeakSet[socket.socket] = weakref.WeakSet()  # closed by make_room, not yet shut

    def open_connections(self) -> int:
        """The accepted sockets not yet closed nor closing."""
        for sock in [s for s in self.accepted if s.fileno() < 0]:
            self.accepted.discard(sock)
        return sum(s not in self.leaving for s in self.accepted)

    def accept(self):
        if time.monotonic() < self.held_until:
            raise BlockingIOError(errno.EAGAIN, "holding off after running out of descriptors")
        try:
            sock, addr = super().accept()
        except OSError as err:
            if err.errno in OUT_OF_RESOURCES:
                self.held_until = time.monotonic() + HOLD
            raise
        if self.cap is not None and self.open_connections() >= self.cap and not self._room():
            _refuse(sock, self.cap)
            raise BlockingIOError(errno.EAGAIN, "too many connections: one refused")
        self.accepted.add(sock)
        return sock, addr

    def _room(self) -> bool:
        fd = self.make_room() if self.make_room is not None else None
        if fd is None:
            return False
        self.leaving.update(s for s in self.accepted if s.fileno() == fd)
        return True


def capped(sock: socket.socket, wanted: int) -> Listener:
    """`sock`, a bound socket, as a Listener capped at connection_cap(wanted) connections."""
    if not isinstance(sock, Listener):
        sock = Listener(sock.family, sock.type, sock.proto, fileno=sock.detach())
    sock.cap = connection_cap(wanted)
    return sock


def _refuse(sock: socket.socket, cap: int) -> None:
    if _refusals.now():
        log.warning("implgen view: %d connections open, the most at once: new ones are refused (503)", cap)
    try:
        sock.setblocking(False)
        sock.send(REFUSED)
    except OSError:
        pass
    sock.close()


def quiet_accept_errors(loop: asyncio.AbstractEventLoop) -> None:
    """Make the loop's report of an accept that failed for want of descriptors one line a minute, without its
    traceback; anything else goes to the loop's default handler."""

    def handler(loop: asyncio.AbstractEventLoop, context: dict) -> None:
        err = context.get("exception")
        if not (isinstance(err, OSError) and err.errno in OUT_OF_RESOURCES and "accept" in context.get("message", "")):
            loop.default_exception_handler(context)
        elif _out_of_files.now():
            limit = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
            log.error(
                "implgen view: cannot accept a connection: %s (this process may open %s files): new connections "
                "wait, retried every second",
                err.strerror or err,
                "any number of" if limit == resource.RLIM_INFINITY else limit,
            )

    loop.set_exception_handler(handler)
