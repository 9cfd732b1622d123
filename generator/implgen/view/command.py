"""`implgen view [SPEC.yaml | SCENE.yaml] [--port P] [--host H] [--no-browser]`: the interactive viewer.

The file is read and checked like every input (a mapping with `objects` is a scene, anything else a spec);
with no file the page starts from a torus. The limits (work.py) are read from IMPLGEN_VIEW_* variables and the
socket is bound before anything starts, so a bad limit or a port in use is one line and exit status 2. Beyond
loopback the server makes a token, prints the link with it and a warning line. The server runs until Ctrl-C,
which cancels every render and returns within a second or two.
"""

from __future__ import annotations

import asyncio
import functools
import secrets
import socket
import sys
import threading
import webbrowser
from collections.abc import Sequence
from pathlib import Path

from implgen.args import ArgumentParser
from implgen.errors import UserError
from implgen.spec.entry import parse_spec
from implgen.spec.paramrange import param_ranges
from implgen.view.document import STARTER, Document
from implgen.view.work import Limits
from implgen.yamlfile import read_yaml

BACKLOG = 64  # connections the kernel holds for the server to accept, and asyncio accepts in one go
SHUTDOWN_GRACE = 1  # seconds uvicorn waits for the pages' handlers at Ctrl-C (their renders are cancelled first)


def document_factory(path: Path | None):
    """A function giving each page a fresh Document for the file (a spec parsed once, here: microseconds a page;
    a scene read again for each page, so the function says `reads_files` and the server calls it on its parse
    pool)."""
    from implgen.scene.load import parse_scene

    if path is None:
        spec = parse_spec(STARTER, "starter")
        param_ranges(spec)  # the sliders' spans, found once now (kept with the spec), not on the event loop
        return lambda: Document.for_spec(spec)
    data = read_yaml(path, what="spec or scene")
    if isinstance(data, dict) and "objects" in data:
        scene_path = path

        def scene_document() -> Document:
            doc = Document.for_file(parse_scene(read_yaml(scene_path, what="scene"), scene_path))
            param_ranges(doc.spec)  # on the parse pool, as this function is
            return doc

        scene_document.reads_files = True
        return scene_document
    spec = parse_spec(data, str(path))
    param_ranges(spec)
    from implgen.view import fit

    size = fit.fitted(spec)  # a shape without a box: its clip fitted as a new equation's is (and framed)
    return lambda: Document.for_spec(spec, size)


def bind(host: str, port: int) -> socket.socket:
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except OSError as err:
        raise UserError("--host", f"cannot resolve {host!r} ({err.strerror or err})") from None
    from implgen.view.connections import Listener

    family, _, _, _, addr = infos[0]
    sock = Listener(family, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        sock.bind(addr)
    except OSError as err:
        sock.close()
        raise UserError("--port", f"cannot listen on {host}:{port} ({err.strerror or err})") from None
    sock.listen(BACKLOG)
    return sock


def is_loopback(host: str) -> bool:
    from implgen.view.server import LOOPBACK_HOSTS

    return host in LOOPBACK_HOSTS or host.startswith("127.")


def _config(app, sock, limits: Limits):
    import uvicorn

    from implgen.view.connections import protocol_class
    from implgen.view.protocol import MAX_MESSAGE

    return uvicorn.Config(
        app,
        http=protocol_class(limits.request),
        backlog=max(1, min(BACKLOG, sock.cap // 4)),  # what asyncio accepts at once, before any protocol runs
        log_level="warning",
        ws_max_size=MAX_MESSAGE,
        ws_ping_interval=limits.ping,
        ws_ping_timeout=limits.ping,
        lifespan="off",
        timeout_graceful_shutdown=SHUTDOWN_GRACE,
    )


def serve(
    sock: socket.socket,
    make_document,
    threads: int | None = None,
    on_ready=None,
    limits: Limits | None = None,
    token: str | None = None,
) -> None:
    """Run the server on a bound socket until it is stopped (Ctrl-C, or server.should_exit). A socket bound beyond
    loopback needs a `token` (the page's link carries it)."""
    import uvicorn

    from implgen.view.connections import capped, make_room, quiet_accept_errors
    from implgen.view.server import LOOPBACK_HOSTS, create_app

    host = sock.getsockname()[0]
    loopback = is_loopback(host)
    if not loopback and not token:
        raise ValueError(f"a server listening on {host} needs a token")
    limits = limits or Limits()
    app = create_app(
        make_document,
        threads=threads,
        allowed_hosts=(*LOOPBACK_HOSTS, host) if loopback else None,
        limits=limits,
        token=None if loopback else token,
    )
    sock = capped(sock, limits.max_connections)
    config = _config(app, sock, limits)
    work = app.state.work
    # the event loop's turn at the GIL comes sooner while SymPy parses on the parse pool (5 ms by default; the
    # heavy-neighbours measure of bench/view_latency.py is the check)
    switch = sys.getswitchinterval()
    sys.setswitchinterval(0.001)

    class Server(uvicorn.Server):
        async def startup(self, sockets=None) -> None:
            quiet_accept_errors(asyncio.get_running_loop())  # out of descriptors: one line a minute
            await super().startup(sockets=sockets)

        def handle_exit(self, sig, frame) -> None:
            """Ctrl-C: every render is cancelled at once and no page waits for its C threads to finish their
            row (on the event loop: this is a signal handler, which must not take the pools' locks)."""
            super().handle_exit(sig, frame)
            try:
                asyncio.get_running_loop().call_soon_threadsafe(work.shutdown)
            except RuntimeError:  # no loop running in this thread: the `finally` below does it
                pass

    server = Server(config)
    sock.make_room = functools.partial(make_room, server.server_state.connections)
    if on_ready is not None:
        on_ready(server)
    try:
        server.run(sockets=[sock])  # uvicorn then closes every socket, and waits SHUTDOWN_GRACE at most
    finally:
        work.shutdown()
        sys.setswitchinterval(switch)


EXAMPLES = (
    ("start from a torus, and open the page in the browser", "implgen view"),
    ("a shape spec", "implgen view examples/shapes/heart.yaml"),
    (
        "a scene, on a free port, without opening a browser",
        "implgen view examples/scenes/csg_trio.yaml --port 0 --no-browser",
    ),
)


def main(argv: Sequence[str]) -> int:
    ap = ArgumentParser(
        label="view",
        prog="implgen view",
        description="Type an equation, turn it, drag its params: in the browser (docs/viewer.md). The server runs "
        "until Ctrl-C.",
        examples=EXAMPLES,
    )
    ap.add_argument("file", type=Path, nargs="?", help="a spec or a scene (default: a torus)")
    ap.add_argument("--port", type=int, default=8765, help="0 picks a free port (default 8765)")
    ap.add_argument("--host", default="127.0.0.1", help="address to listen on (default 127.0.0.1: this machine)")
    ap.add_argument("--no-browser", action="store_true", dest="no_browser", help="do not open a browser")
    args = ap.parse_args(list(argv))
    if not 0 <= args.port <= 65535:
        raise UserError("--port", f"{args.port} is outside [0, 65535]")
    from implgen.view.connections import connection_cap

    limits = Limits.from_env()
    connection_cap(limits.max_connections)  # a file-descriptor limit too low to serve: one line, before any work
    make_document = document_factory(args.file)
    make_document()  # a scene's shapes are checked now, not when the first page connects
    sock = bind(args.host, args.port)
    host, port = sock.getsockname()[:2]
    token = None
    shown = host
    if not is_loopback(host):
        token = secrets.token_urlsafe(24)
        if host in ("0.0.0.0", "::"):  # every address: the link names the machine
            shown = socket.gethostname()
        print(
            f"implgen view: warning: listening on {host}:{port}, beyond this machine: anyone who can reach the "
            "port and has the link (its token) can use the page and this machine's CPU",
            file=sys.stderr,
            flush=True,
        )
    url = f"http://{'[' + shown + ']' if ':' in shown else shown}:{port}/" + (f"?token={token}" if token else "")
    print(f"implgen view: {url}  (Ctrl-C stops)", flush=True)
    if not args.no_browser:
        threading.Timer(0.5, webbrowser.open, args=(url,)).start()
    serve(sock, make_document, limits=limits, token=token)
    return 0
