"""`implgen view` through Starlette's test client and the session directly: what is served, the frames, the
checks on every message, the newest request winning, and the pictures against the normal render path."""

from __future__ import annotations

import asyncio
import io
import json
import socket

import numpy as np
import pytest
import yaml
from PIL import Image
from starlette.testclient import TestClient

from conftest import ROOT
from implgen.cli import main as cli_main
from implgen.errors import UserError
from implgen.imagefile import to_uint8
from implgen.scene import build
from implgen.scene.load import parse_scene
from implgen.scene.render import render
from implgen.scene.tracer import CScene
from implgen.spec.entry import parse_spec
from implgen.view import builds as builds_mod
from implgen.view import frames as view_frames
from implgen.view import session as session_mod
from implgen.view.command import document_factory
from implgen.view.document import Document
from implgen.view.protocol import MAX_MESSAGE
from implgen.view.server import create_app, origin_allowed
from implgen.view.session import HEADER, KIND_COARSE, KIND_FULL, KIND_MORE, KIND_ONE, KIND_QUARTER, KIND_SAVE, Session
from view_fixtures import BALLS_SCENE

SCENES = ROOT / "examples" / "scenes"


@pytest.fixture()
def client():
    with TestClient(create_app(document_factory(None), threads=2)) as c:
        yield c


def picture(ws) -> bytes:
    """The next picture, past the build's status lines ("compiling ...") that may come before it."""
    while True:
        msg = ws.receive()
        if msg.get("bytes") is not None:
            return msg["bytes"]
        data = json.loads(msg["text"])
        assert data["type"] == "status", data


def reply(ws) -> dict:
    """The next JSON message, past the build's status lines."""
    while True:
        data = ws.receive_json()
        if data["type"] != "status":
            return data


def frame(msg: bytes) -> tuple[int, int, np.ndarray]:
    seq, kind, _, w, h = HEADER.unpack(msg[: HEADER.size])
    img = np.asarray(Image.open(io.BytesIO(msg[HEADER.size :])).convert("RGB"))
    assert img.shape == (h, w, 3)
    return seq, kind, img


def render_msg(hello: dict, seq: int = 1, refine: bool = True, w: int = 160, h: int = 120, **over) -> str:
    msg = {
        "type": "render",
        "seq": seq,
        "refine": refine,
        "width": w,
        "height": h,
        "values": hello["values"],
        "orbit": hello["orbit"],
        "options": hello["options"],
    }
    msg.update(over)
    return json.dumps(msg)


def scene_of(hello: dict, w: int, h: int, spp: int, values=None) -> dict:
    """The scene a page with this state shows, built independently of the session from the hello message."""
    from implgen.view import protocol

    doc = document_factory(None)()
    req = protocol.parse_render(json.loads(render_msg(hello, values=values or hello["values"])), doc.spec)
    doc.values, doc.orbit, doc.options = req.values, req.orbit, req.options
    return yaml.safe_load(session_mod.dump.to_yaml(session_mod.dump.scene_mapping(doc.scene(w, h, spp))))


# ------------------------------------------------------------------------------------- serving


def test_only_the_pages_files_are_served(client) -> None:
    served = (
        ("/", "text/html"),
        ("/app.js", "text/javascript"),
        ("/share.js", "text/javascript"),
        ("/style.css", "text/css"),
        ("/favicon.ico", "image/x-icon"),
        ("/favicon.svg", "image/svg+xml"),
    )
    for path, kind in served:
        r = client.get(path)
        assert r.status_code == 200 and r.headers["content-type"].startswith(kind)
        assert "default-src 'self'" in r.headers["content-security-policy"]
    for path in ("/static/app.js", "/index.html", "/../pyproject.toml", "/%2e%2e/generator/implgen/cli.py", "/ws/x"):
        assert client.get(path).status_code == 404
    assert 'src="/app.js"' in client.get("/").text


# ------------------------------------------------------------------------------------- frames


def test_coarse_then_full_frame_match_the_normal_render(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        assert hello["type"] == "hello" and hello["params"] == {"a": 1.0, "b": 0.35} and hello["degree"] == 4
        ws.send_text(render_msg(hello, seq=3, w=160, h=120))
        seq, kind, coarse = frame(picture(ws))
        ch, cw = coarse.shape[:2]  # a page's first coarse frame: at most half the width and height
        assert (seq, kind) == (3, KIND_COARSE) and 16 <= cw <= 80 and ch == round(cw * 0.75)
        seq, kind, full = frame(picture(ws))
        while kind in (KIND_QUARTER, KIND_ONE, KIND_MORE):  # the refinement's first pictures, when it may be slow
            seq, kind, full = frame(picture(ws))
        assert (seq, kind, full.shape) == (3, KIND_FULL, (120, 160, 3))
    # the same view through parse_scene + render(): the full frame is lossless PNG of the same samples
    ref = to_uint8(render(parse_scene(scene_of(hello, 160, 120, 4), "view.yaml"), threads=2))
    assert np.abs(full.astype(int) - ref).max() <= 1
    assert full.std() > 10  # not a blank picture: the torus is there
    ref_coarse = to_uint8(render(parse_scene(scene_of(hello, cw, ch, 1), "view.yaml"), threads=2))
    assert np.abs(coarse.astype(int) - ref_coarse).mean() < 4  # JPEG


def test_a_slider_rerenders_without_building(client, monkeypatch) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(render_msg(hello, seq=1, refine=False))
        _, _, before = frame(picture(ws))
        calls = []
        real = builds_mod.build_scene
        monkeypatch.setattr(builds_mod, "build_scene", lambda *a, **k: calls.append(1) or real(*a, **k))
        ws.send_text(render_msg(hello, seq=2, refine=False, values={"a": 1.0, "b": 0.6}))
        seq, _, after = frame(picture(ws))
        assert seq == 2 and calls == []
        assert np.abs(after.astype(int) - before).mean() > 2  # a fatter tube


def test_bad_equation_keeps_the_last_shape_and_the_server_up(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 +* z^2 - 1"}))
        err = reply(ws)
        assert err["type"] == "error" and err["field"] == "equation" and "syntax error" in err["message"]
        assert "\n" not in err["message"]
        for bad in ("__import__('os').system('true')", "x^25 + y", "x + w", "x" * 30_000):
            ws.send_text(json.dumps({"type": "shape", "equation": bad}))
            err = reply(ws)
            assert err["field"] in ("equation", "message"), err
        ws.send_text(render_msg(hello, seq=5, refine=False))
        seq, _, img = frame(picture(ws))
        assert seq == 5 and img.std() > 10
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": "1.5"}}))
        ok = reply(ws)
        assert ok == {
            "type": "shape",
            "name": "torus",  # no name sent: the current shape's
            "equation": "x^2 + y^2 + z^2 - r^2",  # the user's tree printed back, in the user's order
            "params": {"r": 1.5},
            "values": {"r": 1.5},
            "degree": 2,
            "object_clip": None,  # a scene's picked object's clip (a shape page's clip is the Look's)
            "ranges": {"r": [0.0, 3.0]},  # the slider's span: r only squared (a radius), 0 where the ball shrinks away
            "shape_id": 1,  # the first shape accepted since the hello (the GPU preview's GLSL names it)
            "fit": None,  # not asked for
            "unbounded": False,  # a ball: the probe finds all of it (a cone would run on without end)
            "objects": [],  # a scene file's, to pick from
        }
        ws.send_text(
            json.dumps({"type": "shape", "equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1.5}, "fit": True})
        )
        assert reply(ws)["fit"] == 1.8  # the ball of radius 1.5, and a margin


@pytest.mark.parametrize(
    "msg, needle",
    [
        ("not json", "not JSON"),
        ('{"type": "launch"}', "expected an object with type"),
        ('{"type": "render", "width": 4096}', "width"),
        ('{"type": "render", "orbit": {"pitch": 95}}', "pitch"),
        ('{"type": "render", "options": {"clip": "cone"}}', "clip"),
        ('{"type": "render", "options": {"color": [1, 2, 0]}}', "color"),
        ('{"type": "render", "values": {"a": 1e300}}', "a"),
        ('{"type": "save_png", "width": 8192, "height": 8192}', "pixels"),
        ('{"type": "save_png", "spp": 65}', "spp"),
        ("[" * 100_000, "longer than"),
    ],
)
def test_bad_messages_are_answered_in_one_line(client, msg: str, needle: str) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(msg)
        err = reply(ws)
        assert err["type"] == "error" and needle in err["message"] and "\n" not in err["message"]
        ws.send_bytes(b"\x00" * 10)
        assert reply(ws)["type"] == "error"
        ws.send_text(render_msg(hello, seq=9, refine=False))  # still serving
        assert frame(picture(ws))[0] == 9
    assert len("[" * 100_000) > MAX_MESSAGE


def test_save_png_yaml_and_c(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(render_msg(hello, seq=1, refine=False))
        frame(picture(ws))
        ws.send_text(json.dumps({"type": "save_png", "width": 96, "height": 64, "spp": 2}))
        seq, kind, saved = frame(picture(ws))
        assert kind == KIND_SAVE and saved.shape == (64, 96, 3)
        ref = to_uint8(render(parse_scene(scene_of(hello, 96, 64, 2), "view.yaml"), threads=2))
        assert np.abs(saved.astype(int) - ref).max() <= 1
        ws.send_text(json.dumps({"type": "show_c"}))
        c = reply(ws)["text"]
        assert "torus_coeffs(" in c and "torus.h" in c


@pytest.mark.parametrize("clip, cut", [("sphere", False), ("box", False), ("sphere", True), ("none", False)])
def test_save_yaml_is_a_scene_that_renders_to_the_page_s_full_frame(client, tmp_path, clip: str, cut: bool) -> None:
    """Save YAML writes a scene (camera, lights, clip, colours, the shape inline, named `surface` when typed)
    that `implgen render` renders to the page's full frame, pixel for pixel; `implgen view` opens it on the same
    view."""
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(
            json.dumps(
                {
                    "type": "shape",
                    "equation": "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + c",
                    "params": {"c": 11.8},
                    "name": "surface",
                    "fit": True,
                }
            )
        )
        shape = reply(ws)
        assert shape["name"] == "surface" and shape["fit"] == 4.0
        options = dict(hello["options"], clip=clip, cut=cut, clip_size=3.5, color=[0.2, 0.7, 0.4])
        orbit = dict(hello["orbit"], yaw=40.0, pitch=20.0, distance=11.0)
        ws.send_text(render_msg(hello, seq=1, w=96, h=72, values=shape["values"], options=options, orbit=orbit))
        while True:
            seq, kind, full = frame(picture(ws))
            if kind == KIND_FULL:
                break
        ws.send_text(json.dumps({"type": "save_yaml", "width": 96, "height": 72}))
        text = reply(ws)["text"]
    saved = yaml.safe_load(text)
    leaf = saved["objects"][0] if not cut else saved["objects"][0]["intersection"][0]
    assert leaf["name"] == "surface" and leaf["params"] == {"c": 11.8}
    assert (leaf.get("clip") == {clip: 3.5}) == (clip != "none" and not cut)
    path = tmp_path / "saved.yaml"
    path.write_text(text)
    assert cli_main(["render", str(path), "-o", str(tmp_path / "out.png"), "-q"]) == 0
    rendered = np.asarray(Image.open(tmp_path / "out.png").convert("RGB"))
    assert np.array_equal(rendered, full)  # the same picture, pixel for pixel
    assert full.std() > 10
    doc = document_factory(path)()  # `implgen view saved.yaml`: the same view, on the page it was saved from
    assert doc.base is None and (doc.options.clip, doc.options.cut, doc.options.lights) == (clip, cut, "studio")
    assert doc.options.color == (0.2, 0.7, 0.4) and doc.options.clip_size == (3.5 if clip != "none" else 3.0)
    again = to_uint8(render(doc.scene(96, 72, 4), threads=2))
    assert np.abs(again.astype(int) - full).mean() < 0.5


def test_scene_file_mode(tmp_path) -> None:
    make = document_factory(SCENES / "torus_shadow.yaml")
    with TestClient(create_app(make, threads=2)) as c, c.websocket_connect("/ws") as ws:
        hello = reply(ws)
        assert hello["mode"] == "scene" and hello["options"]["lights"] == "scene"
        ws.send_text(render_msg(hello, seq=1, refine=False))
        assert frame(picture(ws))[2].std() > 10
        ws.send_text(json.dumps({"type": "save_yaml", "width": 64, "height": 48}))
        saved = yaml.safe_load(reply(ws)["text"])
        assert saved["image"]["width"] == 64
    sc = parse_scene(saved, tmp_path / "saved.yaml")  # a scene file implgen render takes
    assert len(sc.objects) == 2 and len(sc.lights) == 1


def test_failures_are_one_error_reply_and_the_page_keeps_going(client, monkeypatch, caplog) -> None:
    """Bad input is its line; a bug is 'internal error: <kind>' on the page and a traceback in the log; either
    way the next request is served (protocol.error_for builds every reply)."""

    def bug(*a, **k):
        raise ZeroDivisionError("not for the page")

    def bad(*a, **k):
        raise UserError("save_png", "too big for today")

    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        monkeypatch.setattr(view_frames, "RenderJob", bug)
        ws.send_text(render_msg(hello, seq=1, refine=False))
        assert reply(ws) == {
            "type": "error",
            "field": "message",
            "message": "internal error: ZeroDivisionError",
        }
        monkeypatch.undo()
        for raise_, line in ((bug, "internal error: ZeroDivisionError"), (bad, "save_png: too big for today")):
            monkeypatch.setattr(view_frames, "file_png", raise_)  # the save, on its pool thread
            ws.send_text(json.dumps({"type": "save_png", "width": 32, "height": 32, "spp": 1}))
            assert reply(ws) == {"type": "error", "field": "message", "message": line}
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 +"}))
        err = reply(ws)
        assert err["field"] == "equation" and "syntax error at column 5: '+' has nothing after it" in err["message"]
        assert err["position"] == 4  # the page's caret goes under the '+'

        ws.send_bytes(b"{}")
        assert reply(ws) == {"type": "error", "field": "message", "message": "message: expected text (JSON)"}
        ws.send_text(render_msg(hello, seq=2, refine=False))
        assert frame(picture(ws))[:2] == (2, KIND_COARSE)
    failed = [r for r in caplog.records if r.name == "implgen.view"]
    assert [r.getMessage() for r in failed] == ["viewer render failed", "viewer save failed"]
    assert all(r.exc_info and r.exc_info[0] is ZeroDivisionError for r in failed)


# ------------------------------------------------------------------------------------- clip: exact hits


@pytest.mark.parametrize(
    "clip, size, cut, t, entering",
    [
        ("none", 3.0, False, 3.65, 1),
        ("sphere", 1.2, False, 4.35, 0),
        ("box", 1.0, False, 4.35, 0),
        ("sphere", 1.2, True, 3.8, 1),
        ("box", 1.0, True, 4.0, 1),
    ],
)
def test_clip_shows_the_surface_inside_or_cuts_the_solid(clip: str, size: float, cut: bool, t, entering) -> None:
    """Torus about y (a = 1, b = 0.35): the ray down the z-axis from z = 5 meets the tube at z = 1.35 and leaves
    it at z = 0.65. By default (as SURFER) a clip shows the surface inside the ball of radius 1.2 or the cube
    [-1, 1]^3 only, cut open: the first hit is the tube's inner wall at z = 0.65, seen from inside the solid
    (its back, the inside colour). With `cut`, the solid is intersected with the ball or the cube: the cut face,
    at z = 1.2 or z = 1, is hit entering."""
    doc = document_factory(None)()
    doc.options.clip, doc.options.clip_size, doc.options.cut = clip, size, cut
    sc = doc.scene(8, 8, 1)
    hit = CScene(sc, build.build_scene(sc)).intersect([0, 0, 5], [0, 0, -1])
    assert hit.t == pytest.approx(t, abs=1e-9)
    assert hit.entering == entering


# ------------------------------------------------------------------------------------- newest wins


def test_a_coarse_frame_in_flight_is_finished_and_the_newest_request_drawn_next() -> None:
    """A drag: requests come faster than frames. Each coarse frame is finished and sent (never thrown away by
    the next move), the requests between are skipped, and the last one is drawn."""
    sent: list = []

    async def scenario() -> None:
        s = Session(Document.for_spec(parse_spec(_starter(), "starter")), _collect(sent), threads=2)
        hello = s.hello()
        for seq in range(1, 41):  # 40 moves 5 ms apart: far faster than a frame
            await s.handle(render_msg(hello, seq=seq, refine=False, w=1280, h=960))
            await asyncio.sleep(0.005)
        while not sent or HEADER.unpack(sent[-1][: HEADER.size])[0] != 40:
            await asyncio.sleep(0.01)
        await s.close()

    asyncio.run(scenario())
    seqs = [HEADER.unpack(m[: HEADER.size])[0] for m in sent]
    assert seqs[0] == 1 and seqs[-1] == 40 and seqs == sorted(seqs) and len(seqs) < 40


def _collect(sent: list):
    async def send(msg) -> None:
        sent.append(msg)

    return send


def test_a_newer_request_cancels_the_running_refinement() -> None:
    sent: list = []

    async def scenario() -> None:
        got = asyncio.Event()

        async def send(msg) -> None:
            sent.append(msg)
            got.set()

        s = Session(Document.for_spec(parse_spec(_starter(), "starter")), send, threads=2)
        hello = s.hello()
        # a big refined frame: the coarse one comes quickly, the full one takes long enough to be overtaken
        await s.handle(render_msg(hello, seq=1, w=2048, h=2048))
        while not sent:
            await got.wait()
            got.clear()
        await s.handle(render_msg(hello, seq=2, refine=False))
        while len(sent) < 2:
            await got.wait()
            got.clear()
        await asyncio.sleep(0.05)
        await s.close()

    asyncio.run(scenario())
    kinds = [HEADER.unpack(m[: HEADER.size])[:2] for m in sent]
    assert kinds == [(1, KIND_COARSE), (2, KIND_COARSE)]


def _starter() -> dict:
    from implgen.view.document import STARTER

    return STARTER


# ------------------------------------------------------------------------------------- the command


def test_command_refuses_bad_input_in_one_line(tmp_path, capsys) -> None:
    assert cli_main(["view", str(tmp_path / "missing.yaml"), "--no-browser"]) == 2
    assert cli_main(["view", "--port", "70000", "--no-browser"]) == 2
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: s\nequation: x^2 +\n")
    assert cli_main(["view", str(bad), "--no-browser"]) == 2
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        assert cli_main(["view", "--port", str(taken.getsockname()[1]), "--no-browser"]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 4 and all(line.startswith("implgen: error: ") for line in lines)
    assert "--port" in lines[1] and "syntax error" in lines[2] and "--port" in lines[3]


@pytest.mark.parametrize("name", ["csg_trio", "torus_shadow", "glass_sphere"])
def test_a_scene_written_back_renders_the_same(name: str, tmp_path) -> None:
    """dump.scene_mapping of a loaded scene (CSG, transforms, materials, checkers, glass) parses back to a
    scene that renders to the same pixels."""
    from implgen.scene.load import load_scene

    sc = load_scene(SCENES / f"{name}.yaml")
    again = parse_scene(yaml.safe_load(session_mod.dump.to_yaml(session_mod.dump.scene_mapping(sc))), tmp_path / "s")
    a = render(sc, width=48, height=36, spp=1, threads=2)
    b = render(again, width=48, height=36, spp=1, threads=2)
    assert np.array_equal(a, b)


def test_a_new_equation_drops_the_old_shapes_bounds() -> None:
    """The starter torus is bounded to |y| <= b; a sphere typed with the same params must not be cut by that
    box: the ray down the y-axis from y = 5 meets the unit sphere at t = 4. New defaults alone keep it."""
    from implgen.view import protocol

    doc = document_factory(None)()
    doc.options.clip = "none"
    same = protocol.parse_shape({"equation": doc.spec.equation, "params": {"a": 1.2, "b": 0.3}}, doc.spec)
    assert same.bounds is not None and same.box() == pytest.approx([-1.5, -0.3, -1.5, 1.5, 0.3, 1.5])
    ball = protocol.parse_shape({"equation": "x^2 + y^2 + z^2 - a^2", "params": {"a": 1, "b": 0.35}}, doc.spec)
    assert ball.bounds is None
    doc.set_spec(ball)
    sc = doc.scene(8, 8, 1)
    assert CScene(sc, build.build_scene(sc)).intersect([0, 5, 0], [0, -1, 0]).t == pytest.approx(4.0, abs=1e-12)


@pytest.mark.parametrize(
    "headers, allowed, ok",
    [
        ({"host": "127.0.0.1:8765", "origin": "http://127.0.0.1:8765"}, ("127.0.0.1", "localhost", "::1"), True),
        ({"host": "localhost:8765", "origin": "http://localhost:8765"}, ("127.0.0.1", "localhost", "::1"), True),
        ({"host": "[::1]:8765", "origin": "http://[::1]:8765"}, ("127.0.0.1", "localhost", "::1"), True),
        ({"host": "127.0.0.1:8765"}, ("127.0.0.1",), True),  # not a browser: no Origin
        ({"host": "127.0.0.1:8765", "origin": "http://evil.example"}, ("127.0.0.1",), False),  # another site
        ({"host": "127.0.0.1:8765", "origin": "http://127.0.0.1:9999"}, ("127.0.0.1",), False),  # another port
        ({"host": "evil.example:8765", "origin": "http://evil.example:8765"}, ("127.0.0.1",), False),  # rebinding
        ({"host": "evil.example:8765", "origin": "http://evil.example:8765"}, None, True),  # --host 0.0.0.0
        ({"host": "10.0.0.5:8765", "origin": "http://evil.example"}, None, False),
    ],
)
def test_the_socket_takes_only_the_pages_own_origin(headers, allowed, ok):
    assert origin_allowed(headers, allowed) is ok


def test_a_foreign_origin_or_host_is_turned_away_before_any_work():
    from starlette.websockets import WebSocketDisconnect

    made = []

    def make():
        made.append(1)
        return document_factory(None)()

    with TestClient(create_app(make, threads=2)) as c:
        with pytest.raises(WebSocketDisconnect) as err:
            with c.websocket_connect("/ws", headers={"origin": "http://evil.example"}) as ws:
                reply(ws)
        assert err.value.code == 1008
        with c.websocket_connect("/ws", headers={"origin": "http://testserver"}) as ws:
            assert reply(ws)["type"] == "hello"
    with TestClient(create_app(make, threads=2, allowed_hosts=("127.0.0.1", "localhost", "::1"))) as c:
        with pytest.raises(WebSocketDisconnect):  # the test client's Host is `testserver`, as a rebound name
            with c.websocket_connect("/ws") as ws:
                reply(ws)
    assert len(made) == 1  # only the accepted page got a document


def test_a_scene_s_object_is_picked_in_the_picture_or_from_the_list(tmp_path) -> None:
    """Two balls, left and right of the camera's axis, on a floor: a click on a ball's centre (where the camera
    projects it, worked out here) picks that ball, a click above the floor's horizon picks nothing, the list picks
    by index; the edits of each object are kept when another one is picked."""
    scene = BALLS_SCENE
    path = tmp_path / "balls.yaml"
    path.write_text(yaml.safe_dump(scene))
    half = np.tan(np.radians(20))  # the pixel of (x, 0, 0) at distance 10, in a 640 x 480 picture

    def pixel(x: float) -> float:
        return (x / 10 / (half * 640 / 480) + 1) / 2 * 640 - 0.5

    with TestClient(create_app(document_factory(path), threads=2)) as c, c.websocket_connect("/ws") as ws:
        hello = reply(ws)
        assert [o["name"] for o in hello["objects"]] == ["floor", "left", "right"] and hello["object"] == 0
        ws.send_text(json.dumps({"type": "pick", "x": pixel(2.0), "y": 239.5, "width": 640, "height": 480}))
        got = reply(ws)
        assert (got["object"], got["name"], got["equation"]) == (2, "right", "(x - 2)^2 + y^2 + z^2 - 1")  # as written
        ws.send_text(json.dumps({"type": "shape", "equation": "(x - 2)^2 + y^2 + z^2 - 0.25"}))
        assert reply(ws)["name"] == "right"  # a scene's shape keeps its name
        ws.send_text(json.dumps({"type": "pick", "x": pixel(-2.0), "y": 239.5, "width": 640, "height": 480}))
        assert reply(ws)["object"] == 1
        ws.send_text(json.dumps({"type": "pick", "x": 320, "y": 5, "width": 640, "height": 480}))
        assert "nothing there" in reply(ws)["message"]
        ws.send_text(json.dumps({"type": "object", "index": 2}))
        back = reply(ws)
        assert back["object"] == 2 and back["equation"] == "(x - 2)^2 + y^2 + z^2 - 0.25"  # its edit was kept
        ws.send_text(json.dumps({"type": "object", "index": 3}))
        assert "index" in reply(ws)["message"]
    with TestClient(create_app(document_factory(None), threads=2)) as c, c.websocket_connect("/ws") as ws:
        reply(ws)
        ws.send_text(json.dumps({"type": "object", "index": 0}))
        assert reply(ws)["message"] == "object: only a scene file has objects to pick"


def test_pace_sizes_live_frames_for_about_30_ms() -> None:
    """The live frame's size from the last frame's measure: TARGET seconds at the measured cost a pixel, at most
    GROW times the last frame's pixels, between MIN_WIDTH pixels a row and half the full frame, the aspect kept;
    a cut frame with no row done shrinks by FIRST_SHRINK^2, a new shape by FIRST_SHRINK."""
    from implgen.view import pace

    p = pace.Pace()
    assert p.size(640, 480) == (160, 120)  # the first frame of a page
    p.measured(160 * 120, 0.060)  # twice the target: half the pixels next
    w, h = p.size(640, 480)
    assert abs(w * h - 160 * 120 / 2) < 200 and abs(w / h - 4 / 3) < 0.02
    p.measured(w * h, 0.001)  # very cheap: it may only double
    assert abs(p.size(640, 480)[0] * p.size(640, 480)[1] - 2 * w * h) < 300
    for _ in range(12):  # cheap frames: twice the pixels each time, up to half the full frame a side
        w, h = p.size(640, 480)
        p.measured(w * h, 1e-6)
    assert p.size(640, 480) == (320, 240)
    p.cut(320 * 240)
    assert abs(p.pixels - 320 * 240 / 16) < 1
    p.measured(100, 10.0)  # hopelessly slow: the smallest frame, which is never cut
    w, h = p.size(640, 480)
    assert (w, h) == (pace.MIN_WIDTH, 36) and p.smallest(640, 480, w)
    p.pixels = 1000.0
    p.new_shape()
    assert p.pixels == 250.0


def test_export_page_is_the_shared_page_of_this_view(client) -> None:
    """Export page: `implgen share`'s page (share/page.py) with the shape, the param values, the camera, the clip
    and the colours the page shows now; the sliders over the spec's range or the page's default one."""
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        values = {k: v * 1.1 for k, v in hello["values"].items()}
        options = dict(hello["options"], clip="box", clip_size=2.5, color=[0.2, 0.7, 0.4])
        orbit = dict(hello["orbit"], yaw=40.0, pitch=20.0, distance=9.0)
        ws.send_text(render_msg(hello, seq=1, w=64, h=48, values=values, options=options, orbit=orbit))
        while frame(picture(ws))[1] != KIND_FULL:
            pass
        ws.send_text(json.dumps({"type": "export_page"}))
        page = reply(ws)
    assert page["type"] == "page" and page["name"] == f"{hello['name']}.html"
    html = page["text"]
    start = html.index('<script type="application/json" id="ig-data">')
    data = json.loads(html[html.index(">", start) + 1 : html.index("</script>", start)])
    assert data["orbit"] == {**orbit, "target": list(orbit["target"])}
    assert data["clip"] == {"kind": "box", "size": 2.5, "cut": False}
    assert {p["name"]: p["value"] for p in data["params"]} == pytest.approx(values)
    for p in data["params"]:
        assert p["min"] <= p["value"] <= p["max"]
    assert "#33b366" in html  # the outside colour, (0.2, 0.7, 0.4)
    assert "http://" not in html and "https://" not in html


def test_export_page_of_a_gallery_shape_keeps_its_slider_range(client) -> None:
    """A gallery pick sends the spec's ranges with its shape (the page's message); the exported page's slider runs
    over them (Kummer's mu: 0.65 to 1.7), not over the default one (0.3 to 2.3)."""
    kummer = next(g for g in client.get("/gallery.json").json() if g["name"] == "kummer")
    with client.websocket_connect("/ws") as ws:
        reply(ws)
        shape = {k: kummer[k] for k in ("equation", "name", "params", "ranges", "bounds")}
        ws.send_text(json.dumps({"type": "shape", **shape, "fit": True}))
        assert reply(ws)["name"] == "kummer"
        ws.send_text(json.dumps({"type": "export_page"}))
        html = reply(ws)["text"]
    start = html.index('<script type="application/json" id="ig-data">')
    data = json.loads(html[html.index(">", start) + 1 : html.index("</script>", start)])
    assert [(p["name"], p["min"], p["max"]) for p in data["params"]] == [("mu", 0.65, 1.7)]


def test_the_gallery_list_is_served_as_plain_json(client) -> None:
    from implgen.spec import gallery

    listing = client.get("/gallery.json").json()
    assert [g["name"] for g in listing] == [e.name for e in gallery.entries()] and len(listing) >= 20
    kummer = next(g for g in listing if g["name"] == "kummer")
    assert kummer["ranges"] == {"mu": [0.65, 1.7]} and kummer["params"] == {"mu": 1.3}
    assert set(kummer) == {"name", "title", "description", "reference", "equation", "params", "ranges", "bounds"}


def test_the_docs_count_the_runtime_s_files_as_the_page_does() -> None:
    """The first run's line counts the runtime's files as the build does ("3 of N files"); the docs said "of 9"
    when the page said "of 14". A number the docs give is the build's count."""
    import re

    from implgen.scene.build import runtime_ready

    text = (ROOT / "docs" / "viewer.md").read_text()
    assert "of N files" in text
    assert all(int(n) == runtime_ready()[1] for n in re.findall(r"\d+ of (\d+) files", text))


def test_a_scene_s_top_level_object_takes_the_page_s_clip_and_a_csg_part_does_not(tmp_path) -> None:
    """The Look's clip gives a scene's picked top-level object its own clip (the picture, Save YAML and Save mesh
    use it); inside CSG the other parts bound a leaf, so it takes none; a shape page has no objects to clip."""
    from implgen.view import meshsave
    from implgen.view.document import Options

    scene = dict(
        BALLS_SCENE,
        objects=[*BALLS_SCENE["objects"], {"difference": [{"equation": "x^2 + y^2 - 1"}, {"equation": "z"}]}],
    )
    doc = Document.for_scene(parse_scene(scene, tmp_path / "s.yaml"))
    assert doc.object_clip() == {"clip": "none", "size": 3.0, "clippable": True}  # the floor
    doc.set_clip("box", 2.5)
    assert doc.scene().objects[0].clip.size == 2.5 and doc.scene().objects[1].clip is None
    assert meshsave.job_for(doc, 64, doc.values, Options()).clips  # Save mesh: the floor in its box
    doc.select(3)  # a CSG part
    with pytest.raises(UserError, match="top-level object"):
        doc.set_clip("sphere", 1.0)
    doc.select(0)
    assert doc.object_clip()["clip"] == "box"  # kept with its object
    with pytest.raises(UserError, match="top-level object"):
        Document.for_spec(parse_spec(_starter(), "starter")).set_clip("sphere", 1.0)
