"""The viewer's web server: Starlette routes for the page's own three files and one WebSocket per page.

Nothing else is served: the static files are a fixed table read from the package, not a folder mapped onto
URLs. Messages are bounded (uvicorn's ws_max_size and protocol.MAX_MESSAGE); each page gets its own Session.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from importlib import resources

from starlette.applications import Starlette
from starlette.responses import Response
from starlette.routing import Route, WebSocketRoute
from starlette.websockets import WebSocket, WebSocketDisconnect

from implgen.view.document import Document
from implgen.view.session import Session

log = logging.getLogger("implgen.view")

STATIC = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/app.js": ("app.js", "text/javascript; charset=utf-8"),
    "/style.css": ("style.css", "text/css; charset=utf-8"),
}
HEADERS = {
    "Cache-Control": "no-store",
    "X-Content-Type-Options": "nosniff",
    "Content-Security-Policy": "default-src 'self'; img-src 'self' blob: data:; connect-src 'self'",
}
MAX_PAGES = 8  # pages connected at once


def _static(name: str, media: str) -> Callable:
    body = resources.files("implgen.view").joinpath("static", name).read_bytes()

    async def serve(request) -> Response:
        return Response(body, media_type=media, headers=HEADERS)

    return serve


def create_app(make_document: Callable[[], Document], threads: int | None = None) -> Starlette:
    """The app; `make_document` gives each new page its own copy of the starting state."""
    pages = {"open": 0}

    async def frames(ws: WebSocket) -> None:
        await ws.accept()
        if pages["open"] >= MAX_PAGES:
            await ws.close(code=1013, reason="too many pages open")
            return
        pages["open"] += 1

        async def send(msg: dict | bytes) -> None:
            if isinstance(msg, bytes):
                await ws.send_bytes(msg)
            else:
                await ws.send_json(msg)

        session = Session(make_document(), send, threads=threads)
        try:
            await send(session.hello())
            while True:
                msg = await ws.receive()
                if msg["type"] == "websocket.disconnect":
                    break
                text = msg.get("text")
                if text is None:
                    await send({"type": "error", "field": "message", "message": "message: expected text (JSON)"})
                    continue
                try:
                    await session.handle(text)
                except Exception as err:  # a bug, not bad input: tell the page, keep serving
                    log.exception("viewer message failed")
                    text = f"internal error: {type(err).__name__}"
                    await send({"type": "error", "field": "message", "message": text})
        except WebSocketDisconnect:
            pass
        finally:
            pages["open"] -= 1
            await session.close()

    routes = [Route(path, _static(name, media)) for path, (name, media) in STATIC.items()]
    routes.append(WebSocketRoute("/ws", frames))
    return Starlette(routes=routes)
