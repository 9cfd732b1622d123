"""A GPU-drawn scene's rest (docs/viewer.md, "The GPU preview"): the pixels the page's GLSL flagged are traced in
double by view/fix.py, one sample at the pixel's centre, and must be exactly `implgen render`'s pixels at one
sample (scene.render, the C render loop: an independent path through rt_render); through the WebSocket a `fix`
message answers with a KIND_FIX frame of those bytes, and bad `fix` messages get one error line."""

from __future__ import annotations

import json
import threading

import numpy as np
import pytest
from starlette.testclient import TestClient

from conftest import ROOT
from implgen.imagefile import to_uint8
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.render import render
from implgen.view import fix
from implgen.view.command import document_factory
from implgen.view.document import Document
from implgen.view.fix import KIND_FIX
from implgen.view.server import create_app
from implgen.view.session import SAMPLES
from test_view_api import reply

SCENES = ROOT / "examples" / "scenes"
SIZE = (48, 36)


def _some_pixels(w: int, h: int) -> list[int]:
    rng = np.random.default_rng(5)
    return sorted(int(i) for i in rng.choice(w * h, 300, replace=False))


@pytest.mark.parametrize("name", ["glassware.yaml", "csg_trio.yaml"])
def test_fixed_pixels_are_the_render_s_at_one_sample(name) -> None:
    """Glass (refraction, Fresnel, shadows through glass) and CSG: every asked pixel, bit for bit."""
    doc = Document.for_scene(load_scene(SCENES / name))
    sc = doc.scene(*SIZE, 1)
    lib = build_scene(sc)
    pixels = _some_pixels(*SIZE)
    got = np.frombuffer(fix.fix_pixels(sc, lib, pixels, threads=2), np.uint8).reshape(-1, 3)
    want = to_uint8(render(sc, spp=1, threads=2, built=lib)).reshape(-1, 3)[pixels]
    assert (got == want).all(), np.argwhere((got != want).any(axis=1))[:5]


def test_a_stopped_fix_returns_nothing() -> None:
    doc = Document.for_scene(load_scene(SCENES / "csg_trio.yaml"))
    sc = doc.scene(*SIZE, 1)
    stop = threading.Event()
    stop.set()
    assert fix.fix_pixels(sc, build_scene(sc), list(range(500)), stop=stop) is None
    assert fix.fix_pixels(sc, build_scene(sc), list(range(500)), seconds=-1.0) is None


def _fix_msg(hello: dict, pixels, **over) -> str:
    msg = {
        "type": "fix",
        "seq": 3,
        "width": SIZE[0],
        "height": SIZE[1],
        "values": hello["values"],
        "orbit": hello["orbit"],
        "options": hello["options"],
        "part": 1,
        "pixels": pixels,
    }
    return json.dumps({**msg, **over})


def test_a_fix_message_gets_the_pixels_in_double() -> None:
    """Through the socket: the reply's header names the view's seq, KIND_FIX and the part; its bytes are the
    render's pixels at the view the message gave (not the document's older one)."""
    path = SCENES / "csg_trio.yaml"
    with TestClient(create_app(document_factory(str(path)), threads=2)) as client:
        with client.websocket_connect("/ws") as ws:
            hello = reply(ws)
            orbit = {**hello["orbit"], "yaw": hello["orbit"]["yaw"] + 20.0}
            pixels = _some_pixels(*SIZE)
            ws.send_text(_fix_msg(hello, pixels, orbit=orbit))
            msg = ws.receive_bytes()
    seq, kind, _, part, w, h = SAMPLES.unpack(msg[: SAMPLES.size])
    assert (seq, kind, part, w, h) == (3, KIND_FIX, 1, *SIZE)
    doc = Document.for_scene(load_scene(path))
    doc.orbit.yaw = orbit["yaw"]
    want = to_uint8(render(doc.scene(*SIZE, 1), spp=1, threads=2)).reshape(-1, 3)[pixels]
    assert (np.frombuffer(msg[SAMPLES.size :], np.uint8).reshape(-1, 3) == want).all()


@pytest.mark.parametrize(
    "pixels,over,says",
    [
        ([], {}, "pixels: expected a list of 1 to"),
        (list(range(fix.MAX_PIXELS + 1)), {}, "pixels: expected a list of 1 to"),
        ([5, 5], {}, "each pixel at most once"),
        ([SIZE[0] * SIZE[1]], {}, "is outside [0, "),
        ([1.5], {}, "expected a whole number"),
        ("12", {}, "pixels: expected a list"),
        ([1], {"part": fix.MAX_PARTS}, "part"),
    ],
)
def test_a_bad_fix_message_gets_one_line(pixels, over, says) -> None:
    with TestClient(create_app(document_factory(str(SCENES / "csg_trio.yaml")), threads=2)) as client:
        with client.websocket_connect("/ws") as ws:
            hello = reply(ws)
            ws.send_text(_fix_msg(hello, pixels, **over))
            err = reply(ws)
    assert err["type"] == "error" and says in err["message"], err


def test_a_part_asked_twice_is_refused_and_an_older_view_s_is_dropped() -> None:
    """A page cannot queue more than MAX_PARTS traces for one rest: a part asked again gets one error line; a fix
    of an older view than one already asked is dropped (no reply), a newer one answered."""
    with TestClient(create_app(document_factory(str(SCENES / "csg_trio.yaml")), threads=2)) as client:
        with client.websocket_connect("/ws") as ws:
            hello = reply(ws)
            ws.send_text(_fix_msg(hello, [1, 2], seq=5, part=0))
            first = ws.receive_bytes()
            ws.send_text(_fix_msg(hello, [3], seq=5, part=0))
            again = reply(ws)
            ws.send_text(_fix_msg(hello, [4], seq=4, part=1))  # older: dropped
            ws.send_text(_fix_msg(hello, [7], seq=6, part=0))
            newer = ws.receive_bytes()
    assert SAMPLES.unpack(first[: SAMPLES.size])[0] == 5 and len(first) == SAMPLES.size + 6
    assert again["type"] == "error" and "part 0 of this view was asked already" in again["message"]
    assert SAMPLES.unpack(newer[: SAMPLES.size])[0] == 6 and len(newer) == SAMPLES.size + 3
