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
    idle = work.limits.idle
    pages = {"open": 0}

    async def frames(ws: WebSocket) -> None:
        if not origin_allowed(ws.headers, allowed_hosts):
            await ws.close(code=1008, reason="not this page's origin")
            return
        if not token_allowed(ws.query_params.get("token"), token):
            await ws.close(code=1008, reason="no token, or not this server's")
            return
        await ws.accept()
        if pages["open"] >= work.limits.max_pages:
            message = f"too many pages open (at most {work.limits.max_pages}): close one, then reload this one"
            await ws.send_json(protocol.error("pages", message))
            await ws.close(code=1013, reason="too many pages open")
            return

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

        pages["open"] += 1
        session = None
        try:
            try:  # a scene file is read again for each page: on the parse pool
                slow = getattr(make_document, "reads_files", False)
                doc = await work.call(work.parse, make_document) if slow else make_document()
            except Exception as err:  # a scene file that no longer reads: its line to the page; a bug: logged
                if not isinstance(err, UserError):
                    log.exception("viewer page could not start")
                await send(protocol.error_for(err))
                await _close(ws, 1011, "the page could not start")
                return
            session = Session(doc, send, threads=threads, work=work)
            await send(session.hello())
            while True:
                try:
                    async with asyncio.timeout(idle):  # not wait_for: it would receive in a task of its own
                        msg = await ws.receive()
                except TimeoutError:
                    await _close(ws, 1001, f"idle for {idle:g} s: reload the page to go on")
                    break
                if msg["type"] == "websocket.disconnect":
                    break
                text = msg.get("text")
                if text is None:
                    await send(protocol.error("message", "message: expected text (JSON)"))
                    continue
                try:
                    await session.handle(text)
                except Exception as err:  # a bug, not bad input: tell the page, keep serving
                    log.exception("viewer message failed")
                    await send(protocol.error_for(err))
        except (WebSocketDisconnect, asyncio.CancelledError):
            pass  # the page has gone, or the server stops (Ctrl-C) while it waits for a parse: end quietly
        finally:
            try:
                if session is not None:
                    await session.close()  # its renders and its save stop first: they count against the page
            finally:
                pages["open"] -= 1

    routes = [Route(path, _static(name, media, token)) for path, (name, media) in STATIC.items()]
    listing = gallery_json()  # the gallery specs' YAML, read once: no equation is parsed here

    async def serve_gallery(request) -> Response:
        return Response(listing, media_type="application/json", headers=HEADERS)

    routes.append(Route("/gallery.json", serve_gallery))
    routes.append(WebSocketRoute("/ws", frames))
    app = Starlette(routes=routes)
    app.state.work = work
    return app
