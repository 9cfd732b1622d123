"""The share link's numbers are read within the server's ranges, stated once.

The page's share link (view/static/share.js) kept param values up to ±1e300 where the server takes ±1e9, with its
own copy of every range. The ranges now live in view/protocol.py RANGES: the server's checks use them, the hello
sends them, and share.js reads a link's numbers within what the hello says. Here the link reader runs in headless
Chromium on the hello's ranges, and keeps a number exactly when the server's own check takes it.
"""

from __future__ import annotations

import json

import pytest
from starlette.testclient import TestClient

from conftest import ROOT
from implgen.errors import UserError
from implgen.spec.entry import parse_spec
from implgen.view import protocol
from implgen.view.command import document_factory
from implgen.view.server import create_app

SHARE_JS = (ROOT / "generator" / "implgen" / "view" / "static" / "share.js").read_text()
SPEC = parse_spec({"name": "s", "equation": "x^2 + y^2 + z^2 - a", "params": {"a": 1.0}}, "s")
CAM = {"yaw": 10.0, "pitch": 20.0, "distance": 5.0, "target": [0.0, 0.0, 0.0], "fov": 40.0}
CAM_KEYS = ["yaw", "pitch", "distance", "tx", "ty", "tz", "fov"]


def hello_ranges() -> dict:
    with TestClient(create_app(document_factory(None), threads=1)) as client, client.websocket_connect("/ws") as ws:
        while True:
            msg = ws.receive_json()
            if msg["type"] == "hello":
                return msg["limits"]["ranges"]


def test_the_hello_sends_the_ranges_the_server_checks():
    ranges = hello_ranges()
    assert ranges == {k: list(v) for k, v in protocol.RANGES.items()}
    assert ranges["value"] == [-1e9, 1e9]


def server_takes(field: str, text: str) -> bool:
    """Whether the server's own check (view/protocol.py) takes the number `text` as `field`."""
    x = float(text)
    try:
        if field == "value":
            protocol.parse_values({"a": x}, SPEC)
        elif field == "clip_size":
            protocol.parse_options({"clip": "sphere", "clip_size": x})
        else:
            key = "target" if field in ("tx", "ty", "tz") else field
            cam = dict(CAM, target=[x, 0.0, 0.0] if field == "tx" else [0.0, 0.0, x]) if key == "target" else CAM
            protocol.parse_orbit(dict(cam, **({} if key == "target" else {key: x})))
    except UserError:
        return False
    return True


def cases() -> list[tuple[str, str]]:
    out = []
    for field, (lo, hi) in [*protocol.RANGES.items(), ("tx", protocol.RANGES["target"])]:
        if field == "target":
            field = "tz"
        for x in (lo, hi):
            out += [(field, repr(x)), (field, repr(x * 1.5 if x else 1e-9)), (field, repr(x * 0.5))]
        out += [(field, "1e300"), (field, "-1e300"), (field, "0")]
    return out


def fragment(field: str, text: str) -> str:
    if field == "value":
        return f"#v=1&values=a:{text}"
    if field == "clip_size":
        return f"#v=1&clip=sphere:{text}"
    cam = [str(CAM["yaw"]), str(CAM["pitch"]), str(CAM["distance"]), "0", "0", "0", str(CAM["fov"])]
    cam[CAM_KEYS.index(field)] = text
    return "#v=1&cam=" + ",".join(cam)


def kept(view: dict, field: str) -> bool:
    if field == "value":
        return "a" in view.get("values", {})
    if field == "clip_size":
        return "clip_size" in view.get("options", {})
    return "orbit" in view


@pytest.mark.needs_program("chromium", "chromedriver")
def test_a_share_link_keeps_exactly_the_numbers_the_server_takes():
    from test_view_page import chromium

    ranges = hello_ranges()
    todo = cases()
    assert any(not server_takes(f, t) for f, t in todo) and any(server_takes(f, t) for f, t in todo)
    driver = chromium(400, 300)
    try:
        driver.get("about:blank")
        read = driver.execute_script(
            SHARE_JS + "\nreturn arguments[0].map((f) => window.implgenLink.decode(f, arguments[1]));",
            [fragment(f, t) for f, t in todo],
            ranges,
        )
        without = driver.execute_script(SHARE_JS + "\nreturn window.implgenLink.decode('#v=1&values=a:1', null);")
    finally:
        driver.quit()
    wrong = [(f, t) for (f, t), r in zip(todo, read) if kept(r["view"], f) != server_takes(f, t)]
    assert not wrong, json.dumps(wrong)
    assert without["view"]["values"] == {} and without["bad"] == ["values (a:1)"]  # no ranges: no number
