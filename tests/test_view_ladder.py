"""The viewer's refinement ladder (view/ladder.py): a resting view is refined in passes of one C render context --
a half-size picture when the page shows less, the full size at 1 sample, samples added up to 4 -- each picture
sent as its pass ends, the last one what `implgen render` makes of the view, pixel for pixel; a refined request
for the same view renders nothing again; the render budget's message names the scene and says what to do."""

from __future__ import annotations

import io
import json
import re

import numpy as np
import pytest
import yaml
from PIL import Image
from starlette.testclient import TestClient

from conftest import ROOT
from implgen.cli import main as cli_main
from implgen.scene.renderjob import PIXELS_ALL, PIXELS_EVEN, PIXELS_ODD
from implgen.view import ladder, pace
from implgen.view.command import document_factory
from implgen.view.server import create_app
from implgen.view.session import (
    KIND_COARSE,
    KIND_FULL,
    KIND_MORE,
    KIND_ONE,
    KIND_QUARTER,
    SAMPLES,
)
from implgen.view.work import Limits, Ticket

GLASSWARE = ROOT / "examples" / "scenes" / "glassware.yaml"
W, H = 160, 120


# ------------------------------------------------------------------------------------- the plan


def test_the_plan_adds_every_sample_once_in_order() -> None:
    """Unknown cost: 1 sample, then the rest at once. A costly view: a pass a sample. A cheap one: one pass. A
    page showing less than a quarter of the picture gets the half-size picture first."""
    S = ladder.Step
    assert ladder.plan(640, 480, 4, None, False) == [S("one", 0, 1), S("full", 1, 4)]
    costly = ladder.plan(640, 480, 4, 2.4e-6, True)  # glassware: 0.74 s a sample of the whole picture
    assert costly == [
        S("quarter", 0, 1, PIXELS_EVEN),
        S("one", 0, 1, PIXELS_ODD),
        S("more", 1, 2),
        S("more", 2, 3),
        S("full", 3, 4),
    ]
    assert ladder.plan(640, 480, 4, 1.3e-6, False) == [S("one", 0, 1), S("more", 1, 3), S("full", 3, 4)]  # 0.4 s
    assert ladder.plan(640, 480, 4, 1e-6, False) == [S("one", 0, 1), S("full", 1, 4)]  # 0.31 s a sample
    assert ladder.plan(640, 480, 4, 1e-7, True) == [S("full", 0, 4, PIXELS_ALL)]  # 0.12 s in all
    assert ladder.plan(64, 48, 1, None, True)[-1] == S("full", 0, 1, PIXELS_ODD)


# ------------------------------------------------------------------------------------- through the socket


def frames_until_full(ws) -> list[tuple[int, int, int, int, int, bytes]]:
    """(seq, kind, samples, width, height, image bytes) of each picture up to a full one; status lines skipped."""
    out = []
    while not out or out[-1][1] != KIND_FULL:
        msg = ws.receive()
        if msg.get("bytes") is None:
            assert json.loads(msg["text"])["type"] == "status", msg
            continue
        seq, kind, flags, samples, w, h = SAMPLES.unpack(msg["bytes"][: SAMPLES.size])
        out.append((seq, kind, samples, w, h, msg["bytes"][SAMPLES.size :]))
    return out


def pixels(data: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(int)


def request(hello: dict, seq: int, refine: bool) -> str:
    keys = ("values", "orbit", "options")
    return json.dumps(
        {"type": "render", "seq": seq, "refine": refine, "width": W, "height": H, **{k: hello[k] for k in keys}}
    )


@pytest.fixture()
def glassware(monkeypatch):
    """A page on the glassware scene whose ladder goes a sample a pass (its targets at 0), after a first coarse
    frame of the smallest size (48 pixels a row: less than a quarter of the picture)."""
    monkeypatch.setattr(ladder, "REFINE_TARGET", 0.0)
    monkeypatch.setattr(ladder, "PASS_TARGET", 0.0)
    monkeypatch.setattr(pace, "START_PIXELS", 48 * 36)
    with TestClient(create_app(document_factory(GLASSWARE), threads=2)) as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        assert hello["type"] == "hello" and hello["mode"] == "scene"
        yield ws, hello


def test_the_ladder_comes_in_order_and_ends_on_implgen_render_s_picture(glassware, tmp_path) -> None:
    ws, hello = glassware
    ws.send_text(request(hello, 1, refine=False))  # the drag's last move: a coarse frame
    ws.send_text(request(hello, 2, refine=True))  # the release, on the same view
    got = frames_until_full(ws)
    assert [(seq, kind, samples, w) for seq, kind, samples, w, _, _ in got] == [
        (1, KIND_COARSE, 0, 48),
        (2, KIND_QUARTER, 0, W // 2),  # sample 0 of the even pixels: the half-size picture
        (2, KIND_ONE, 0, W),
        (2, KIND_MORE, 2, W),
        (2, KIND_MORE, 3, W),
        (2, KIND_FULL, 0, W),
    ]
    quarter, one, two, three, full = (pixels(g[5]) for g in got[1:])
    assert np.array_equal(quarter, one[::2, ::2])  # the even pixels' sample 0, then the others
    assert full.std() > 10
    # each picture is the mean of more of the final one's samples: nearer to it, pass by pass
    errors = [np.abs(p - full).mean() for p in (one, two, three)]
    assert errors[0] > errors[1] > errors[2] > 0, errors
    # the final picture is `implgen render`'s of the view saved as YAML, pixel for pixel
    ws.send_text(json.dumps({"type": "save_yaml", "width": W, "height": H}))
    while (reply := ws.receive_json())["type"] != "yaml":
        pass
    saved = yaml.safe_load(reply["text"])
    assert saved["image"]["spp"] == 4 and saved["image"]["max_depth"] == 12
    path = tmp_path / "view.yaml"
    path.write_text(reply["text"])
    assert cli_main(["render", str(path), "-o", str(tmp_path / "out.png"), "-q"]) == 0
    assert np.array_equal(pixels((tmp_path / "out.png").read_bytes()), full)


def test_a_refined_request_for_the_same_view_renders_nothing_again(glassware, monkeypatch) -> None:
    """Asked again (the page's rest timer after a release, a slider's change after its input), the view being
    refined goes on, its pictures numbered for the newer request; once refined, its picture is sent again."""
    runs = []
    real = ladder.run
    monkeypatch.setattr(ladder, "run", lambda *a: runs.append(1) or real(*a))
    ws, hello = glassware
    ws.send_text(request(hello, 1, refine=True))
    first = []
    while not first or first[-1][1] == KIND_COARSE:
        first += [(seq, kind) for seq, kind, *_ in next_picture(ws)]  # the coarse frame, then the ladder's first
    ws.send_text(request(hello, 2, refine=True))  # the same view while it is being refined
    rest = frames_until_full(ws)
    if rest[-1][0] == 1:  # the ladder had ended before the request came: its picture, sent again
        rest += frames_until_full(ws)
    assert rest[-1][:2] == (2, KIND_FULL) and all(kind != KIND_COARSE for _, kind, *_ in rest)
    full = rest[-1][5]
    ws.send_text(request(hello, 3, refine=True))  # once refined
    again = frames_until_full(ws)
    assert [(seq, kind) for seq, kind, *_ in again] == [(3, KIND_FULL)] and again[0][5] == full
    assert runs == [1]


def next_picture(ws) -> list[tuple]:
    """The next picture (as frames_until_full gives them)."""
    while True:
        msg = ws.receive()
        if msg.get("bytes") is not None:
            seq, kind, _, samples, w, h = SAMPLES.unpack(msg["bytes"][: SAMPLES.size])
            return [(seq, kind, samples, w, h, msg["bytes"][SAMPLES.size :])]


# ------------------------------------------------------------------------------------- the budget's message


def test_the_budget_message_names_the_pass_and_samples_it_stopped_at() -> None:
    t = Ticket(20.0, "render", "render", 1280, 1, 2, name="glassware.yaml", height=800)
    t.begin_pass(1, 1.0)
    t.shown = 2
    t.total = 4
    t.expired = (20.0, 100)
    assert str(t.over_budget()) == (
        "render: glassware.yaml costs 0.31 ms a pixel: its 1280 × 800 picture stopped at 2 of 4 samples a pixel (a "
        "pass ran past the 20 s budget): a smaller window gets all 4 in time"
    )
    save = Ticket(300.0, "save", "save_png", 4096, 64, 2, name="glassware.yaml", height=4096)
    save.expired = (300.0, 0)
    assert str(save.over_budget()) == (
        "save_png: glassware.yaml costs more than 73 ms a pixel at 64 samples: the 4096 × 4096 save stopped after "
        "300 s: try fewer samples or fewer pixels"
    )


def test_a_scene_over_the_render_budget_is_named_in_the_message() -> None:
    """The glassware scene with a render budget of 0.01 s: one line naming the scene file (not 'this surface'),
    the size of the picture stopped, and what to do."""
    limits = Limits(render_budget=0.01)
    with TestClient(create_app(document_factory(GLASSWARE), threads=2, limits=limits)) as c:
        with c.websocket_connect("/ws") as ws:
            hello = ws.receive_json()
            ws.send_text(json.dumps({**json.loads(request(hello, 1, refine=True)), "width": 640, "height": 480}))
            while "text" not in (msg := ws.receive()) or json.loads(msg["text"])["type"] == "status":
                pass  # past the pictures that came in time
            err = json.loads(msg["text"])
    cost = r"glassware\.yaml costs (more than )?[0-9.e+]+ ms a pixel"
    stopped = (
        r"its \d+ × \d+ picture stopped after 0\.01 s: try a smaller window, or a larger budget "
        r"\(IMPLGEN_VIEW_RENDER_BUDGET\)"
    )
    row = r"a row of \d+ pixels would take about [0-9.e+]+ s, more than the 0\.01 s budget of a render: .*"
    assert err["type"] == "error" and re.fullmatch(f"render: {cost}: ({stopped}|{row})", err["message"]), err
