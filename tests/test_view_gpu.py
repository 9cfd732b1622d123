"""The server's side of the viewer's GPU preview (view/gpu.py; docs/viewer.md, "The GPU preview"), through
Starlette's test client: the hello carries the GLSL ES header, the runtime, the light presets and the material;
a `glsl` request answers with the current shape's generated GLSL (the same text `implgen SPEC --lang glsl`
writes), numbered like the shape replies; a scene file gets its whole scene program (past the GLSL budget the
reply says the server draws); a render request with `gpu` gets no coarse frames; the served surface.js,
orbit.js and scenerender.js are the shared page's files.
The browser side is tests/test_view_gpu_browser.py."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest
from starlette.testclient import TestClient

from conftest import ROOT
from implgen.codegen.backends.glsl import chebform
from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.backends.glsl.scene import scene_program
from implgen.codegen.emit import generate
from implgen.measure.glslcases import chmutov
from implgen.scene.load import load_scene
from implgen.share.scenegpu import scene_tables
from implgen.view import gpu
from implgen.view.command import document_factory
from implgen.view.document import LIGHT_PRESETS, Document
from implgen.view.server import create_app
from implgen.view.session import HEADER, KIND_COARSE, KIND_FULL, KIND_ONE
from implgen.view.work import Limits
from test_view_api import picture, render_msg, reply

SCENES = ROOT / "examples" / "scenes"
SHARE_STATIC = ROOT / "generator" / "implgen" / "share" / "static"


@pytest.fixture()
def client():
    with TestClient(create_app(document_factory(None), threads=2)) as c:
        yield c


def test_the_hello_and_the_glsl_of_each_shape(client) -> None:
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        assert hello["gpu"]["header"] == HEADERS["es"] and hello["gpu"]["runtime"] == runtime_text()
        assert hello["gpu"]["material"] == {"ambient": 0.12, "diffuse": 0.75, "specular": 0.45, "shininess": 40.0}
        assert set(hello["gpu"]["lights"]) == set(LIGHT_PRESETS) and hello["shape_id"] == 0
        ws.send_text(json.dumps({"type": "glsl"}))
        first = reply(ws)
        doc = document_factory(None)()
        assert first == {
            "type": "glsl",
            "name": "torus",
            "glsl_name": "torus",  # the prefix of its GLSL identifiers: the name, where GLSL takes it
            "shape": generate(doc.spec, ("glsl",))["torus.glsl"],
            "params": ["a", "b"],
            "shape_id": 0,
        }
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1.5}}))
        shape = reply(ws)
        ws.send_text(json.dumps({"type": "glsl"}))
        second = reply(ws)
        ws.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 + z^2 - 1", "name": "ball_"}))
        reply(ws)
        ws.send_text(json.dumps({"type": "glsl"}))
        third = reply(ws)
    assert shape["shape_id"] == second["shape_id"] == 1
    assert second["params"] == ["r"] and second["name"] == shape["name"]
    assert "f(x, y, z) = -r^2 + x^2 + y^2 + z^2" in second["shape"] and second["shape"] != first["shape"]
    # ball__hit would be reserved in GLSL: the page gets the prefix the shape's GLSL uses (backends/glsl/printer.py)
    assert third["name"] == "ball_" and third["glsl_name"] == "ig_shape_ball_u"
    assert "int ig_shape_ball_u_hit(vec3 o" in third["shape"]


def test_a_scene_file_gets_its_whole_program_with_live_lights() -> None:
    """glassware.yaml (CSG, glass, several shapes): the reply is the scene tracer's program of the scene the
    server would draw, its lights and background uniforms (slots for the file's lights or a preset's), and the
    file's lights; the shape's GLSL is not in it."""
    scene = load_scene(SCENES / "glassware.yaml")
    doc = Document.for_scene(scene)
    msg = gpu.program_message(doc)
    assert "shape" not in msg and "reason" not in msg and msg["name"] == "glassware"
    s = msg["scene"]
    slots = max(len(scene.lights), max(len(v) for v in LIGHT_PRESETS.values()))
    want = scene_program(scene_tables(doc.scene(16, 16, 1)), "es", live_lights=slots)
    assert s["header"] == HEADERS["es"] and s["header"] + s["program"] == want and s["slots"] == slots
    assert "uniform vec3 ig_light_pos[IG_SCENE_LIGHTS];" in s["program"]
    assert f"#define IG_SCENE_LIGHTS {slots}\n" in s["program"] and "uniform vec3 ig_scene_background;" in s["program"]
    assert s["lights"] == [{"position": list(li.position), "colour": list(li.color)} for li in scene.lights]
    for word in ("CSG", "glass", "shapes"):
        assert word in s["what"], s["what"]


def test_a_scene_s_program_is_asked_with_the_page_s_values_and_past_the_budget_is_the_server_s(tmp_path) -> None:
    """The ask's number comes back; the picked leaf's values from the ask are folded into the program; the same
    program again is not derived again; past the GLSL budget (a Chebyshev form that takes longer) the reply says
    the server draws."""
    path = tmp_path / "two.yaml"
    spec = chmutov(12, nested=False)
    bounds = {a: [float(lo), float(hi)] for a, (lo, hi) in spec.bounds.items()}
    path.write_text(
        "camera: {position: [0, 0, 8], look_at: [0, 0, 0]}\n"
        "objects:\n  - {equation: 'x^2 + y^2 + z^2 - r^2', params: {r: 1.0}}\n"
        f"  - {{equation: '{spec.equation}', bounds: {json.dumps(bounds)}, transform: {{translate: [3, 0, 0]}}}}\n"
    )
    with TestClient(create_app(document_factory(str(path)), threads=2)) as c, c.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(json.dumps({"type": "glsl", "ask": 7, "values": {"r": 1.0}}))
        first = reply(ws)
        ws.send_text(json.dumps({"type": "glsl", "ask": 8, "values": {"r": 1.0}}))
        again = reply(ws)
        ws.send_text(json.dumps({"type": "glsl", "ask": 9, "values": {"r": 0.625}}))
        other = reply(ws)
    assert hello["mode"] == "scene" and first["ask"] == 7 and again["ask"] == 8 and other["ask"] == 9
    assert again["scene"] == first["scene"]
    assert other["scene"]["program"] != first["scene"]["program"] and "0.625" in other["scene"]["program"]
    app = create_app(document_factory(str(path)), threads=2, limits=Limits(glsl_budget=0.01))
    with TestClient(app) as c, c.websocket_connect("/ws") as ws:
        reply(ws)
        ws.send_text(json.dumps({"type": "glsl", "ask": 1}))
        cut = reply(ws)
    assert "scene" not in cut and "the server draws" in cut["reason"] and "0.01 s GLSL budget" in cut["reason"]


def test_the_presets_place_the_lights_the_tracer_gets() -> None:
    """Document.lights() from the one table: studio's key light at target + 2 d (-0.6 right + 0.8 up + back),
    the headlight at the eye, top above the target; computed here from the orbit's formula."""
    doc = document_factory(None)()
    doc.orbit.yaw, doc.orbit.pitch, doc.orbit.distance, doc.orbit.target = 70.0, -20.0, 7.0, (0.5, -1.0, 2.0)
    y, p = np.radians(70.0), np.radians(-20.0)
    back = np.array([np.cos(p) * np.sin(y), np.sin(p), np.cos(p) * np.cos(y)])
    right = np.array([np.cos(y), 0.0, -np.sin(y)])
    up = np.cross(back, right)
    t = np.array([0.5, -1.0, 2.0])
    key = doc.lights()[0]
    assert np.allclose(key.position, t + 14.0 * (-0.6 * right + 0.8 * up + back), atol=1e-12)
    assert key.color == (0.8, 0.8, 0.8) and len(doc.lights()) == 2
    doc.options.lights = "headlight"
    assert np.allclose(doc.lights()[0].position, t + 7.0 * back, atol=1e-12)
    doc.options.lights = "top"
    assert np.allclose(doc.lights()[0].position, t + (0.0, 21.0, 2.1), atol=1e-12)


def test_a_gpu_request_gets_no_coarse_frames(client) -> None:
    """The page draws the live picture itself: a moving request is noted (no frame), a resting one goes straight
    to the full frame."""
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(render_msg(hello, seq=1, refine=False, gpu=True, w=64, h=48))
        ws.send_text(render_msg(hello, seq=2, refine=True, gpu=True, w=64, h=48))
        kinds = []
        while not kinds or kinds[-1] != KIND_FULL:
            seq, kind = HEADER.unpack(picture(ws)[: HEADER.size])[:2]
            kinds.append(kind)
            assert seq == 2
    assert KIND_COARSE not in kinds and set(kinds) <= {KIND_ONE, KIND_FULL}


def test_a_slow_glsl_does_not_hold_the_renders_behind_it(client, monkeypatch) -> None:
    """The GLSL's derivation (SymPy: seconds at a high degree) runs beside the page's messages: a render sent
    after the `glsl` request is answered while the derivation is held, and the GLSL then comes, numbered as the
    shape it was asked for."""
    gate = threading.Event()
    real = gpu.program_message

    def held(*args):
        gate.wait(30)
        return real(*args)

    monkeypatch.setattr(gpu, "program_message", held)
    with client.websocket_connect("/ws") as ws:
        hello = reply(ws)
        ws.send_text(render_msg(hello, seq=1, refine=False, w=64, h=48))
        picture(ws)  # the shape is built (as it is when the page asks for its GLSL: after the shape reply)
        ws.send_text(json.dumps({"type": "glsl"}))
        ws.send_text(render_msg(hello, seq=2, refine=True, gpu=True, w=64, h=48))
        seq, kind = HEADER.unpack(picture(ws)[: HEADER.size])[:2]
        assert seq == 2 and kind in (KIND_ONE, KIND_FULL) and not gate.is_set()  # the frame, the GLSL still held
        gate.set()
        texts = []
        while not texts or texts[-1]["type"] != "glsl":  # past the refined frame that may follow
            msg = ws.receive()
            assert "text" in msg or msg.get("bytes") is not None, msg  # not the socket's close
            if msg.get("text") is not None:
                texts.append(json.loads(msg["text"]))
        assert texts[-1]["shape_id"] == hello["shape_id"] == 0 and texts[-1]["name"] == "torus"


GUARD = 30  # seconds: a hang guard, not a timing
BOX = {a: [-2, 2] for a in "xyz"}  # a spec without params in a finite box: its GLSL tries the Chebyshev form


def test_a_glsl_derivation_does_not_hold_another_page_s_new_equation(client, monkeypatch) -> None:
    """One page's GLSL (a degree-24 Chebyshev form took 38 s) held the shared parse thread, and another
    page's trivial equation waited 73-87 s for it. Now the GLSL has a pool of its own: with page A's Chebyshev
    step held, page B's new equation is answered (before: only once A's derivation had ended)."""
    entered, gate, released = threading.Event(), threading.Event(), threading.Event()
    real = chebform.chebyshev_form

    def held(f, bounds):
        entered.set()
        gate.wait(GUARD)
        released.set()
        return real(f, bounds)

    monkeypatch.setattr(chebform, "chebyshev_form", held)
    with client.websocket_connect("/ws") as a, client.websocket_connect("/ws") as b:
        reply(a), reply(b)
        a.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 + z^2 - 1", "params": {}, "bounds": BOX}))
        assert reply(a)["type"] == "shape"
        a.send_text(json.dumps({"type": "glsl"}))
        assert entered.wait(GUARD)
        b.send_text(json.dumps({"type": "shape", "equation": "x^2 + y^2 - z^2 - 1/4", "params": {}}))
        answer = reply(b)
        answered_while_held = not released.is_set()
        gate.set()
        glsl = reply(a)
    assert answer["type"] == "shape" and answer["equation"] == "x^2 + y^2 - z^2 - 1/4", answer
    assert answered_while_held, "page B's new equation waited for page A's GLSL derivation"
    assert glsl["type"] == "glsl" and "Evaluated in the tree as written (not expanded)." in glsl["shape"]


def _expanded_chmutov(ws) -> None:
    """The page's shape: Chmutov's degree-12 surface typed expanded in its box, whose GLSL the Chebyshev form
    evaluates (tests/test_glsl_chebform.py)."""
    spec = chmutov(12, nested=False)
    bounds = {a: [float(lo), float(hi)] for a, (lo, hi) in spec.bounds.items()}
    ws.send_text(json.dumps({"type": "shape", "equation": spec.equation, "params": {}, "bounds": bounds}))
    assert reply(ws)["type"] == "shape"


def test_past_the_glsl_budget_the_shader_evaluates_the_tree_and_the_page_is_told() -> None:
    """The GPU preview's GLSL and Export page under a GLSL budget too small for the Chebyshev form: f's tree as
    written, and a note for the page naming the budget; under the default budget, the Chebyshev form."""
    app = create_app(document_factory(None), threads=2, limits=Limits(glsl_budget=0.01))
    with TestClient(app) as c, c.websocket_connect("/ws") as ws:
        reply(ws)
        _expanded_chmutov(ws)
        ws.send_text(json.dumps({"type": "glsl"}))
        glsl = reply(ws)
        ws.send_text(json.dumps({"type": "export_page"}))
        page = reply(ws)
    assert "Evaluated in the tree as written (not expanded): the Chebyshev basis" in glsl["shape"]
    assert "within the 0.01 s GLSL budget (IMPLGEN_VIEW_GLSL_BUDGET)" in glsl["note"], glsl.get("note")
    assert "Evaluated in the tree as written (not expanded): the Chebyshev basis" in page["text"]
    assert page["note"].startswith("the exported page's shader: the GLSL evaluates f as written"), page["note"]
    with TestClient(create_app(document_factory(None), threads=2)) as c, c.websocket_connect("/ws") as ws:
        reply(ws)
        _expanded_chmutov(ws)
        ws.send_text(json.dumps({"type": "glsl"}))
        glsl = reply(ws)
        ws.send_text(json.dumps({"type": "export_page"}))
        page = reply(ws)
    assert "Evaluated in the Chebyshev basis of the box" in glsl["shape"] and "note" not in glsl
    assert "Evaluated in the Chebyshev basis of the box" in page["text"] and "note" not in page


def test_the_page_s_scripts_are_the_shared_page_s_files(client) -> None:
    for name in ("surface.js", "orbit.js", "scenerender.js"):
        r = client.get(f"/{name}")
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/javascript")
        assert r.content == (SHARE_STATIC / name).read_bytes()
    assert client.get("/gpu.js").status_code == 200
