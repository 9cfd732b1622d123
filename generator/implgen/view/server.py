"""The viewer's web server: Starlette routes for the page's own files (the page, its script, its style, its
icon), the gallery's list (gallerylist.py) and one WebSocket per page.

Nothing else is served: the static files are a fixed table read from the package, not a folder mapped onto
URLs. Messages are bounded (uvicorn's ws_max_size and protocol.MAX_MESSAGE); each page gets its own Session,
all of them one Work (work.py: the pools, budgets and limits).

Browsers let any web page open a WebSocket to 127.0.0.1, so the socket accepts a browser's connection only
from the page's own origin (Origin equal to the Host the request was sent to), and, when the server listens
on a loopback address, only under a loopback host name: a foreign site, or one that re-binds its DNS name to
127.0.0.1, cannot drive the renderer. Beyond loopback any host name may reach it, so the page and the socket
ask for the token the server was started with (in the URL it prints).

A page is counted from its accept to the end of its last piece of work (`try/finally`), whatever ended it: a
scene file that no longer reads (one line to the page), the page closing, idle for Limits.idle seconds, or a
bug.
"""

from __future__ import annotations

import asyncio
import hmac
import logging
from collections.abc import Callable, Sequence
from importlib import resources

from starlette.applications import Starlette
from starlette.responses import PlainTextResponse, Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect, WebSocketState

from implgen.errors import UserError
from implgen.view import protocol
from implgen.view.document import Document
from implgen.view.gallerylist import gallery_json
from implgen.view.session import Session
from implgen.view.work import Limits, Work

log = logging.getLogger("implgen.view")

STATIC = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/favicon.svg": ("favicon.svg", "image/svg+xml"),
    "/favicon.ico": ("favicon.ico", "image/x-icon"),
    "/app.js": ("app.js", "text/javascript; charset=utf-8"),
    "/share.js": ("share.js", "text/javascript; charset=utf-8"),
    "/mesh.js": ("mesh.js", "text/javascript; charset=utf-8"),
    "/style.css": ("style.css", "text/css; charset=utf-8"),
    "/gpu.js": ("gpu.js", "text/javascript; charset=utf-8"),
    # the GPU preview draws with the shared page's renderer and orbit camera: the same files, not copies
    "/surface.js": ("share:surface.js", "text/javascript; charset=utf-8"),
    "/orbit.js": ("share:orbit.js", "text/javascript; charset=utf-8"),
    "/scenerender.js": ("share:scenerender.js", "text/javascript; charset=utf-8"),
}
HEADERS = {
    "Cache-Control": "no-store",
    "X-Content-Type-Options": "nosniff",
    "Content-Security-Policy": "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'",
}
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")
NO_TOKEN = "this viewer listens beyond this machine: open it with the link it printed, token included\n"


def _host_name(host: str) -> str:
    """`Host` header -> host name without the port (`[::1]:8765` -> `::1`)."""
    if host.startswith("["):
        return host[1 : host.find("]")] if "]" in host else host
    return host.rsplit(":", 1)[0] if host.count(":") == 1 else host


def origin_allowed(headers, allowed_hosts: Sequence[str] | None) -> bool:
    """Whether a request with these headers may use the socket: its Host among `allowed_hosts` (None: any),
    and an Origin, when the client sends one (browsers always do), equal to the page's own."""
    host = headers.get("host", "")
    if allowed_hosts is not None and _host_name(host).lower() not in allowed_hosts:
        return False
    origin = headers.get("origin")
    return origin is None or origin.lower() in (f"http://{host}".lower(), f"https://{host}".lower())


def token_allowed(query: str | None, token: str | None) -> bool:
    """Whether a request's `token` query parameter is the server's (always, when it has none)."""
    return token is None or hmac.compare_digest((query or "").encode(), token.encode())


async def _close(ws: WebSocket, code: int, reason: str) -> None:
    """Close the socket from our side, whatever state the page left it in."""
    try:
        await ws.close(code=code, reason=reason)
    except (WebSocketDisconnect, RuntimeError, OSError):
        pass


def _static(name: str, media: str, token: str | None) -> Callable:
    package, _, file = name.rpartition(":")
    body = resources.files(f"implgen.{package or 'view'}").joinpath("static", file).read_bytes()
    guarded = name == "index.html"  # the page itself; its script and style are the package's, public anyway

    async def serve(request) -> Response:
        if guarded and not token_allowed(request.query_params.get("token"), token):
            return PlainTextResponse(NO_TOKEN, status_code=403, headers=HEADERS)
        return Response(body, media_type=media, headers=HEADERS)

    return serve


def _sender(ws: WebSocket) -> Callable:
    """send(msg): a JSON message or bytes to the page, nothing once the page or the server has closed it."""

    async def send(msg: dict | bytes) -> None:
        if ws.application_state != WebSocketState.CONNECTED:
            return  # closed by the server (idle): a render that ends later has no one to tell
        try:
            if isinstance(msg, bytes):
                await ws.send_bytes(msg)
            else:
                await ws.send_json(msg)
        except (WebSocketDisconnect, RuntimeError, OSError):
            pass  # the page has gone; its receive loop ends on the disconnect

    return send


class _Pages:
    """The WebSocket endpoint: each page's admission, its session, its messages until it goes or idles."""

    def __init__(self, make_document, threads, allowed_hosts, token, work: Work) -> None:
        self.make_document, self.threads, self.work = make_document, threads, work
        self.allowed_hosts, self.token = allowed_hosts, token
        self.open = 0

    async def _admit(self, ws: WebSocket) -> bool:
        """The page's origin and token checked, the socket accepted, the open pages counted."""
        if not origin_allowed(ws.headers, self.allowed_hosts):
            await ws.close(code=1008, reason="not this page's origin")
            return False
        if not token_allowed(ws.query_params.get("token"), self.token):
            await ws.close(code=1008, reason="no token, or not this server's")
            return False
        await ws.accept()
        if self.open >= self.work.limits.max_pages:
            message = f"too many pages open (at most {self.work.limits.max_pages}): close one, then reload this one"
            await ws.send_json(protocol.error("pages", message))
            await ws.close(code=1013, reason="too many pages open")
            return False
        return True

    async def _session(self, ws: WebSocket, send) -> Session | None:
        """The page's session, its hello sent; None (the page told, the socket closed) when it cannot start."""
        try:  # a scene file is read again for each page: on the parse pool
            slow = getattr(self.make_document, "reads_files", False)
            doc = await self.work.call(self.work.parse, self.make_document) if slow else self.make_document()
        except Exception as err:  # a scene file that no longer reads: its line to the page; a bug: logged
            if not isinstance(err, UserError):
                log.exception("viewer page could not start")
            await send(protocol.error_for(err))
            await _close(ws, 1011, "the page could not start")
            return None
        session = Session(doc, send, threads=self.threads, work=self.work)
        await send(session.hello())
        return session

    async def _messages(self, ws: WebSocket, session: Session, send) -> None:
        """The page's messages, each handled in turn, until it disconnects or is idle for the limit."""
        idle = self.work.limits.idle
        while True:
            try:
                async with asyncio.timeout(idle):  # not wait_for: it would receive in a task of its own
                    msg = await ws.receive()
            except TimeoutError:
                await _close(ws, 1001, f"idle for {idle:g} s: reload the page to go on")
                return
            if msg["type"] == "websocket.disconnect":
                return
            text = msg.get("text")
            if text is None:
                await send(protocol.error("message", "message: expected text (JSON)"))
                continue
            try:
                await session.handle(text)
            except Exception as err:  # a bug, not bad input: tell the page, keep serving
                log.exception("viewer message failed")
                await send(protocol.error_for(err))

    async def serve(self, ws: WebSocket) -> None:
        """One page, from its connection to its end (Starlette's WebSocket endpoint: a method, not an ASGI app)."""
        if not await self._admit(ws):
            return
        send = _sender(ws)
        self.open += 1
        session = None
        try:
            session = await self._session(ws, send)
            if session is not None:
                await self._messages(ws, session, send)
        except (WebSocketDisconnect, asyncio.CancelledError):
            pass  # the page has gone, or the server stops (Ctrl-C) while it waits for a parse: end quietly
        finally:
            try:
                if session is not None:
                    await session.close()  # its renders and its save stop first: they count against the page
            finally:
                self.open -= 1


def create_app(
    make_document: Callable[[], Document],
    threads: int | None = None,
    allowed_hosts: Sequence[str] | None = None,
    limits: Limits | None = None,
    token: str | None = None,
) -> Starlette:
    """The app; `make_document` gives each new page its own copy of the starting state (on the parse pool when
    it says `reads_files`: a scene file is read again for each page). `allowed_hosts`: the host names the page
    may be reached under (None: any, for a server listening beyond this machine, which then needs `token`). The
    app's Work is `app.state.work`: shut it down when the server stops."""
    work = Work(limits)
    pages = _Pages(make_document, threads, allowed_hosts, token, work)
    routes = [Route(path, _static(name, media, token)) for path, (name, media) in STATIC.items()]
    listing = gallery_json()  # the gallery specs' YAML, read once: no equation is parsed here

    async def serve_gallery(request) -> Response:
        return Response(listing, media_type="application/json", headers=HEADERS)

    routes.append(Route("/gallery.json", serve_gallery))
    routes.append(WebSocketRoute("/ws", pages.serve))
    app = Starlette(routes=routes)
    app.state.work = work
    return app
