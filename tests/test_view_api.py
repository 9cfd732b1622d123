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
from implgen.codegen.spec import parse_spec
from implgen.errors import UserError
from implgen.imagefile import to_uint8
from implgen.scene import build
from implgen.scene.load import parse_scene
from implgen.scene.render import render
from implgen.scene.tracer import CScene
from implgen.view import session as session_mod
from implgen.view.command import document_factory
from implgen.view.document import Document
from implgen.view.protocol import MAX_MESSAGE
from implgen.view.server import create_app, origin_allowed
from implgen.view.session import HEADER, KIND_COARSE, KIND_FULL, KIND_SAVE, Session

SCENES = ROOT / "examples" / "scenes"


@pytest.fixture()
def client():
    with TestClient(create_app(document_factory(None), threads=2)) as c:
        yield c


def frame(msg: bytes) -> tuple[int, int, np.ndarray]:
    seq, kind, w, h = HEADER.unpack(msg[: HEADER.size])
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
    for path, kind in (("/", "text/html"), ("/app.js", "text/javascript"), ("/style.css", "text/css")):
        r = client.get(path)
        assert r.status_code == 200 and r.headers["content-type"].startswith(kind)
        assert "default-src 'self'" in r.headers["content-security-policy"]
    for path in ("/static/app.js", "/index.html", "/../pyproject.toml", "/%2e%2e/generator/implgen/cli.py", "/ws/x"):
        assert client.get(path).status_code == 404
    assert 'src="/app.js"' in client.get("/").text


# ------------------------------------------------------------------------------------- frames


def test_coarse_then_full_frame_match_the_normal_render(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        assert hello["type"] == "hello" and hello["params"] == {"a": 1.0, "b": 0.35} and hello["degree"] == 4
        ws.send_text(render_msg(hello, seq=3, w=160, h=120))
        seq, kind, coarse = frame(ws.receive_bytes())
        assert (seq, kind, coarse.shape) == (3, KIND_COARSE, (30, 40, 3))
        seq, kind, full = frame(ws.receive_bytes())
        assert (seq, kind, full.shape) == (3, KIND_FULL, (120, 160, 3))
    # the same view through parse_scene + render(): the full frame is lossless PNG of the same samples
    ref = to_uint8(render(parse_scene(scene_of(hello, 160, 120, 4), "view.yaml"), threads=2))
    assert np.abs(full.astype(int) - ref).max() <= 1
    assert full.std() > 10  # not a blank picture: the torus is there
    ref_coarse = to_uint8(render(parse_scene(scene_of(hello, 40, 30, 1), "view.yaml"), threads=2))
    assert np.abs(coarse.astype(int) - ref_coarse).mean() < 4  # JPEG


def test_a_slider_rerenders_without_building(client, monkeypatch) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(render_msg(hello, seq=1, refine=False))
        _, _, before = frame(ws.receive_bytes())
        calls = []
        real = session_mod.build_scene
        monkeypatch.setattr(session_mod, "build_scene", lambda *a, **k: calls.append(1) or real(*a, **k))
        ws.send_text(render_msg(hello, seq=2, refine=False, values={"a": 1.0, "b": 0.6}))
        seq, _, after = frame(ws.receive_bytes())
        assert seq == 2 and calls == []
        assert np.abs(after.astype(int) - before).mean() > 2  # a fatter tube


def test_bad_equation_keeps_the_last_shape_and_the_server_up(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 +* z^2 - 1"}))
        err = ws.receive_json()
        assert err["type"] == "error" and err["field"] == "equation" and "syntax error" in err["message"]
        assert "\n" not in err["message"]
        for bad in ("__import__('os').system('true')", "x^25 + y", "x + w", "x" * 30_000):
            ws.send_text(json.dumps({"type": "shape", "equation": bad}))
            err = ws.receive_json()
            assert err["field"] in ("equation", "message"), err
        ws.send_text(render_msg(hello, seq=5, refine=False))
        seq, _, img = frame(ws.receive_bytes())
        assert seq == 5 and img.std() > 10
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": "1.5"}}))
        ok = ws.receive_json()
        assert ok == {
            "type": "shape",
            "equation": "-r^2 + x^2 + y^2 + z^2",
            "params": {"r": 1.5},
            "values": {"r": 1.5},
            "degree": 2,
        }


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
        hello = ws.receive_json()
        ws.send_text(msg)
        err = ws.receive_json()
        assert err["type"] == "error" and needle in err["message"] and "\n" not in err["message"]
        ws.send_bytes(b"\x00" * 10)
        assert ws.receive_json()["type"] == "error"
        ws.send_text(render_msg(hello, seq=9, refine=False))  # still serving
        assert frame(ws.receive_bytes())[0] == 9
    assert len("[" * 100_000) > MAX_MESSAGE


def test_save_png_yaml_and_c(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(render_msg(hello, seq=1, refine=False))
        frame(ws.receive_bytes())
        ws.send_text(json.dumps({"type": "save_png", "width": 96, "height": 64, "spp": 2}))
        seq, kind, saved = frame(ws.receive_bytes())
        assert kind == KIND_SAVE and saved.shape == (64, 96, 3)
        ref = to_uint8(render(parse_scene(scene_of(hello, 96, 64, 2), "view.yaml"), threads=2))
        assert np.abs(saved.astype(int) - ref).max() <= 1
        ws.send_text(json.dumps({"type": "save_yaml"}))
        text = ws.receive_json()["text"]
        spec = parse_spec(yaml.safe_load(text), "saved.yaml")
        assert spec.equation == hello["equation"] and spec.params == {"a": 1, "b": 0.35} and spec.bounds
        ws.send_text(json.dumps({"type": "show_c"}))
        c = ws.receive_json()["text"]
        assert "torus_coeffs(" in c and "torus.h" in c


def test_scene_file_mode(tmp_path) -> None:
    make = document_factory(SCENES / "torus_shadow.yaml")
    with TestClient(create_app(make, threads=2)) as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        assert hello["mode"] == "scene" and hello["options"]["lights"] == "scene"
        ws.send_text(render_msg(hello, seq=1, refine=False))
        assert frame(ws.receive_bytes())[2].std() > 10
        ws.send_text(json.dumps({"type": "save_yaml"}))
        saved = yaml.safe_load(ws.receive_json()["text"])
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
        hello = ws.receive_json()
        monkeypatch.setattr(session_mod, "RenderJob", bug)
        ws.send_text(render_msg(hello, seq=1, refine=False))
        assert ws.receive_json() == {
            "type": "error",
            "field": "message",
            "message": "internal error: ZeroDivisionError",
        }
        monkeypatch.undo()
        for raise_, reply in ((bug, "internal error: ZeroDivisionError"), (bad, "save_png: too big for today")):
            monkeypatch.setattr(session_mod, "_file_png", raise_)  # the save, on its pool thread
            ws.send_text(json.dumps({"type": "save_png", "width": 32, "height": 32, "spp": 1}))
            assert ws.receive_json() == {"type": "error", "field": "message", "message": reply}
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 +"}))
        err = ws.receive_json()
        assert err["field"] == "equation" and "syntax error in 'x^2 +'" in err["message"], err
        ws.send_bytes(b"{}")
        assert ws.receive_json() == {"type": "error", "field": "message", "message": "message: expected text (JSON)"}
        ws.send_text(render_msg(hello, seq=2, refine=False))
        assert frame(ws.receive_bytes())[:2] == (2, KIND_COARSE)
    failed = [r for r in caplog.records if r.name == "implgen.view"]
    assert [r.getMessage() for r in failed] == ["viewer render failed", "viewer save failed"]
    assert all(r.exc_info and r.exc_info[0] is ZeroDivisionError for r in failed)


# ------------------------------------------------------------------------------------- clip: exact hits


@pytest.mark.parametrize("clip, size, t", [("none", 3.0, 3.65), ("sphere", 1.2, 3.8), ("box", 1.0, 4.0)])
def test_clip_is_an_intersection_with_a_ball_or_a_cube(clip: str, size: float, t: float) -> None:
    """Torus about y (a = 1, b = 0.35): the ray down the z-axis from z = 5 meets the tube at z = 1.35, the
    clip ball of radius 1.2 at z = 1.2, the clip cube [-1, 1]^3 at z = 1."""
    doc = document_factory(None)()
    doc.options.clip, doc.options.clip_size = clip, size
    sc = doc.scene(8, 8, 1)
    hit = CScene(sc, build.build_scene(sc)).intersect([0, 0, 5], [0, 0, -1])
    assert hit.t == pytest.approx(t, abs=1e-9)


# ------------------------------------------------------------------------------------- newest wins


def test_a_newer_request_cancels_the_running_render() -> None:
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
                ws.receive_json()
        assert err.value.code == 1008
        with c.websocket_connect("/ws", headers={"origin": "http://testserver"}) as ws:
            assert ws.receive_json()["type"] == "hello"
    with TestClient(create_app(make, threads=2, allowed_hosts=("127.0.0.1", "localhost", "::1"))) as c:
        with pytest.raises(WebSocketDisconnect):  # the test client's Host is `testserver`, as a rebound name
            with c.websocket_connect("/ws") as ws:
                ws.receive_json()
    assert len(made) == 1  # only the accepted page got a document
