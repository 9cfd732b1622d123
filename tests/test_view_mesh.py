"""The viewer's Save mesh: the shape the page shows, with its param values and its clip,
as a closed binary STL, read back with trimesh and checked against analytic volumes; a scene's picked object
placed by its transform and cut by its own clip; and every way it can fail said in one line, with no file: a
surface that runs on without end, no real points, a mesh beyond the saves' memory, over its time budget, a
second mesh while one runs. Stop and a closed page stop the mesh in progress (the life of its process:
test_view_mesh_process.py). First through Starlette's test client, then in real headless Chromium: the button, its
status while it runs, the file handed to the browser.
"""

from __future__ import annotations

import base64
import io
import json
import math
import os
import threading
import time

import numpy as np
import pytest
import trimesh
import yaml
from starlette.testclient import TestClient

from conftest import ROOT
from implgen.mesh.budget import Stopped
from implgen.mesh.pipeline import mesh_spec
from implgen.spec.entry import load_spec
from implgen.view import meshsave
from implgen.view.command import document_factory
from implgen.view.server import create_app
from implgen.view.session import HEADER, KIND_SAVE
from implgen.view.work import Limits
from view_fixtures import mesh_children, view_process

HEAVY = ROOT / "examples/mesh/chmutov20.yaml"  # degree 20: the costliest of bench/results/mesh_budget.md
TORUS_VOLUME = 2 * math.pi**2 * 1.0 * 0.35**2  # the starter torus: 2 pi^2 R r^2, R = a = 1, r = b = 0.35
GUARD = 60  # seconds: a hang guard, not a timing


def stl(data: bytes) -> trimesh.Trimesh:
    """A binary STL read back by trimesh (equal corners merged: the mesh's own vertices)."""
    return trimesh.load(io.BytesIO(data), file_type="stl", force="mesh")


def client(path=None, **limits) -> TestClient:
    limits.setdefault("idle", GUARD)  # a reply that never comes ends the page, and the test, soon
    return TestClient(create_app(document_factory(path), threads=2, limits=Limits(**limits)))


def mesh_replies(ws, until=("done", "failed", "stopped")) -> tuple[list[dict], bytes | None]:
    """The mesh messages (past build status lines and shape replies) up to the last one, and the STL if one came."""
    said, data = [], None
    deadline = time.monotonic() + GUARD
    while time.monotonic() < deadline:
        msg = ws.receive()
        if msg.get("bytes") is not None:
            seq, kind, flags, w, h = HEADER.unpack(msg["bytes"][: HEADER.size])
            assert (seq, kind, flags, w, h) == (0, 4, 0, 0, 0)
            data = msg["bytes"][HEADER.size :]
            continue
        assert "text" in msg, msg  # not the socket's close
        reply = json.loads(msg["text"])
        if reply["type"] != "mesh":
            continue
        said.append(reply)
        if reply["state"] in until:
            return said, data
        assert reply["state"] == "running", said
    raise AssertionError(f"no end of the mesh: {said}")


def meshing(ws) -> None:
    """Wait until the mesh pool has started the mesh (the running line past "waiting for the meshes"): a page closed
    before then takes its mesh out of the pool's queue (test_view_mesh_process.py)."""
    while "waiting for the meshes" in mesh_replies(ws, until=("running",))[0][-1]["text"]:
        pass


def save_mesh(ws, hello: dict, cells: int, **options) -> dict:
    return {"type": "save_mesh", "cells": cells, "values": hello["values"], "options": {**hello["options"], **options}}


def mesh_processes() -> list[int]:
    """The meshes' child processes still alive (the test client runs the server in this process)."""
    return mesh_children(os.getpid())


@pytest.fixture(scope="module")
def heavy_built():
    mesh_spec(load_spec(HEAVY, cache=True), {}, 4, [], singular=False)  # built and cached: a budget is the mesh's own


def test_the_starter_torus_as_a_closed_stl_with_its_volume() -> None:
    with client() as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(json.dumps(save_mesh(ws, hello, 48)))
        said, data = mesh_replies(ws)
        assert said[0] == {"type": "mesh", "state": "running", "name": "torus.stl", "text": said[0]["text"]}
        assert any(m["text"] == "meshing torus at 48 cells" for m in said if m["state"] == "running")
        assert said[-1]["state"] == "done" and "closed, Euler characteristic 0" in said[-1]["text"], said
        mesh = stl(data)
        assert len(data) == 84 + 50 * len(mesh.faces)  # binary STL
        assert mesh.is_watertight and mesh.is_winding_consistent and mesh.euler_number == 0
        assert f"saved torus.stl: {len(mesh.faces)} triangles at 48 cells" in said[-1]["text"]
        assert abs(mesh.volume / TORUS_VOLUME - 1) < 0.01, mesh.volume
        assert np.allclose(mesh.bounds, [[-1.35, -0.35, -1.35], [1.35, 0.35, 1.35]], atol=0.02)

        # the page's values, and its clip as a capped solid: the torus with b = 0.5, cut by the box |x|,|y|,|z| < 1
        ws.send_text(json.dumps(save_mesh(ws, {**hello, "values": {"a": 1.0, "b": 0.5}}, 48, clip="box", clip_size=1)))
        said, data = mesh_replies(ws)
        mesh = stl(data)
        assert mesh.is_watertight and mesh.volume > 0 and np.allclose(mesh.bounds, [[-1, -0.5, -1], [1, 0.5, 1]])
        # a cut torus: inside the cube lies all of it but four caps, so less than its whole 2 pi^2 R r^2
        assert 0.5 * 2 * math.pi**2 * 0.25 < mesh.volume < 2 * math.pi**2 * 0.25


def test_a_scene_s_picked_object_in_its_own_clip_placed_by_its_transform(tmp_path) -> None:
    """The unit ball cut by a ball of radius 0.8 about (0.3, 0, 0), in its own space, then scaled by 0.5 and
    moved to x = 2: a lens of volume pi (R1 + R2 - d)^2 (d^2 + 2 d (R1 + R2) - 3 (R1 - R2)^2) / (12 d) x 0.5^3."""
    scene = {
        "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0]},
        "lights": [{"position": [0, 5, 5], "color": [1, 1, 1]}],
        "objects": [
            {"equation": "y + 2", "name": "floor"},
            {
                "equation": "x^2 + y^2 + z^2 - 1",
                "name": "ball",
                "transform": {"scale": 0.5, "translate": [2, 0, 0]},
                "clip": {"sphere": 0.8, "center": [0.3, 0, 0]},
            },
        ],
    }
    path = tmp_path / "lens.yaml"
    path.write_text(yaml.safe_dump(scene))
    r1, r2, d = 1.0, 0.8, 0.3
    lens = math.pi * (r1 + r2 - d) ** 2 * (d * d + 2 * d * (r1 + r2) - 3 * (r1 - r2) ** 2) / (12 * d) * 0.5**3
    with client(path) as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(json.dumps(save_mesh(ws, hello, 48)))  # the floor: an unbounded plane, no clip
        said, data = mesh_replies(ws)
        assert said[-1]["state"] == "failed" and data is None
        assert (
            said[-1]["text"] == "save_mesh: floor runs on without end and the scene gives it no clip: no solid to mesh"
        )
        ws.send_text(json.dumps({"type": "object", "index": 1}))
        ws.send_text(json.dumps(save_mesh(ws, hello, 48)))
        said, data = mesh_replies(ws)
        assert said[0]["name"] == "ball.stl"
        mesh = stl(data)
        assert mesh.is_watertight and mesh.euler_number == 2
        assert abs(mesh.volume / lens - 1) < 0.01, (mesh.volume, lens)
        assert np.allclose(mesh.bounds[:, 0], [2 + 0.5 * (0.3 - 0.8), 2.5], atol=0.01)


def test_every_refusal_is_one_line_and_no_file(heavy_built) -> None:
    with client(HEAVY, save_memory=1200, mesh_budget=0.3) as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        for cells, says in ((3, "save_mesh: cells: 3 is outside [4, 256]"), ("64", "expected a whole number")):
            ws.send_text(json.dumps(save_mesh(ws, hello, cells)))
            said, data = mesh_replies(ws)
            assert said[-1]["state"] == "failed" and says in said[-1]["text"] and data is None, said
        ws.send_text(json.dumps(save_mesh(ws, hello, 192)))  # estimated beyond the 1200 MB of the saves
        said, data = mesh_replies(ws)
        assert said[-1]["text"].startswith("save_mesh: a mesh of chmutov20 at 192 cells needs about ")
        assert said[-1]["text"].endswith("MB; saves may use at most 1200 MB together: try fewer cells")
        assert len(said) == 1 and data is None  # refused before any work
        ws.send_text(json.dumps(save_mesh(ws, hello, 96)))  # fits, but not in 0.3 s
        said, data = mesh_replies(ws)
        assert said[-1]["state"] == "failed" and data is None
        assert said[-1]["text"].startswith("mesh: over its time budget of 0.3 s at 96 cells ("), said
        assert said[-1]["text"].endswith("); try fewer cells")

    with client() as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        for equation, clip, says in (
            ("x^2 + y^2 - z^2", "none", "save_mesh: the surface runs on without end: choose a sphere or box clip"),
            (
                "x^2 + y^2 + z^2 + 1",
                "sphere",
                "save_mesh: no real points of the surface in the region meshed: nothing to mesh",
            ),
        ):
            ws.send_text(json.dumps({"type": "shape", "equation": equation, "params": {}}))
            ws.send_text(json.dumps(save_mesh(ws, {**hello, "values": {}}, 32, clip=clip)))
            said, data = mesh_replies(ws)
            assert said[-1]["state"] == "failed" and said[-1]["text"].startswith(says) and data is None, said


def test_one_mesh_a_page_stop_and_a_closed_page_stop_it(heavy_built, monkeypatch) -> None:
    ended: list[str] = []
    real_run = meshsave.run

    def run(*args):
        try:
            out = real_run(*args)
        except Stopped:
            ended.append("stopped")
            raise
        ended.append("finished")
        return out

    monkeypatch.setattr(meshsave, "run", run)
    with client(HEAVY) as c:
        with c.websocket_connect("/ws") as ws:
            hello = ws.receive_json()
            ws.send_text(json.dumps(save_mesh(ws, hello, 128)))  # seconds of work
            meshing(ws)
            ws.send_text(json.dumps(save_mesh(ws, hello, 32)))
            said, _ = mesh_replies(ws, until=("failed",))
            assert said[-1]["text"] == "save_mesh: a mesh is already being made: wait for it, or stop it"
            ws.send_text(json.dumps({"type": "stop_mesh"}))
            said, data = mesh_replies(ws)
            assert said[-1] == {"type": "mesh", "state": "stopped", "text": "meshing stopped"} and data is None
            assert ended == ["stopped"] and not mesh_processes()  # killed, not left running
            ws.send_text(json.dumps(save_mesh(ws, hello, 128)))  # again, then the page closes
            meshing(ws)
        deadline = time.monotonic() + GUARD
        while len(ended) < 2:
            assert time.monotonic() < deadline, "the closed page's mesh went on"
            time.sleep(0.05)
        assert ended == ["stopped", "stopped"] and not mesh_processes()


def test_a_save_png_does_not_wait_behind_a_mesh(monkeypatch) -> None:
    """A mesh holds its pool's thread until its process ends (here: held until the picture has come); Save PNG
    has a pool of its own, so the picture comes meanwhile, and the mesh then ends as usual."""
    gate = threading.Event()
    real_run = meshsave.run

    def run(*args):
        gate.wait(GUARD)
        return real_run(*args)

    monkeypatch.setattr(meshsave, "run", run)
    with client() as c, c.websocket_connect("/ws") as ws:
        hello = ws.receive_json()
        ws.send_text(json.dumps(save_mesh(ws, hello, 24)))
        assert mesh_replies(ws, until=("running",))[0][-1]["state"] == "running"  # taken by the mesh pool
        ws.send_text(json.dumps({"type": "save_png", "width": 32, "height": 24, "spp": 1}))
        deadline = time.monotonic() + GUARD
        while True:
            assert time.monotonic() < deadline and not gate.is_set()
            msg = ws.receive()
            assert "text" in msg or msg.get("bytes") is not None, msg  # not the socket's close
            if msg.get("bytes") is not None:
                _, kind, _, w, h = HEADER.unpack(msg["bytes"][: HEADER.size])
                assert (kind, w, h) == (KIND_SAVE, 32, 24)  # the picture, while the mesh still waits
                break
            assert json.loads(msg["text"]).get("state") not in ("done", "failed", "stopped"), msg
        gate.set()
        said, data = mesh_replies(ws)
        assert said[-1]["state"] == "done" and stl(data).is_watertight, said


def test_ctrl_c_kills_a_mesh_in_progress(heavy_built) -> None:
    """Work.shutdown (Ctrl-C) sets every mesh's stop, as it cancels every render: the mesh's process is killed."""
    import asyncio
    import threading

    from implgen.view.work import Work

    doc = document_factory(HEAVY)()
    job = meshsave.job_for(doc, 128, doc.values, doc.options)
    ended: list[str] = []

    def mesh(stop: threading.Event) -> None:
        try:
            meshsave.run(job, 100.0, stop, lambda: None)
            ended.append("finished")
        except Stopped:
            ended.append("stopped")

    async def main() -> None:
        work = Work()
        stop = threading.Event()
        task = asyncio.get_running_loop().create_task(work.stoppable(work.save, stop, mesh, stop))
        deadline = time.monotonic() + GUARD
        while not mesh_processes():  # the child is meshing
            assert time.monotonic() < deadline
            await asyncio.sleep(0.05)
        work.shutdown()
        assert stop.is_set()
        await asyncio.wait([task], timeout=GUARD)

    asyncio.run(main())
    deadline = time.monotonic() + GUARD
    while not ended:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert ended == ["stopped"] and not mesh_processes()


# ------------------------------------------------------------------------------------- in Chromium

browser = pytest.mark.needs_program("chromium", "chromedriver")


@pytest.fixture(scope="module")
def page():
    from test_view_page import chromium

    d = chromium(1100, 700)
    with view_process() as url:
        yield d, url
    d.quit()


def _open_and_catch_downloads(driver, url: str) -> None:
    from test_view_page import open_page

    open_page(driver, url)
    driver.execute_script(  # keep what the page hands to its download link, and the link's name; save nothing
        "window.saved = []; window.names = []; window.statuses = [];"
        "const make = URL.createObjectURL; URL.createObjectURL = (b) => { window.saved.push(b); return make(b); };"
        "HTMLAnchorElement.prototype.click = function () { window.names.push(this.download); };"
        "const s = document.getElementById('mesh-status');"
        "new MutationObserver(() => window.statuses.push(s.textContent))"
        "  .observe(s, { childList: true, characterData: true, subtree: true });"
    )


@browser
def test_save_mesh_in_the_page_downloads_the_torus_as_a_closed_stl(page) -> None:
    from selenium.webdriver.support.ui import Select

    from test_view_page import text, wait

    driver, url = page
    _open_and_catch_downloads(driver, url)
    Select(driver.find_element("id", "mesh-cells")).select_by_value("64")
    button = driver.find_element("id", "save-mesh")
    button.click()
    wait(driver, lambda d: d.execute_script("return window.saved.length") == 1, "no STL handed to the browser")
    data = driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "window.saved[0].arrayBuffer().then((b) => { let s = ''; const u = new Uint8Array(b);"
        "  for (let i = 0; i < u.length; i += 8192) s += String.fromCharCode(...u.subarray(i, i + 8192));"
        "  done(btoa(s)); });"
    )
    mesh = stl(base64.b64decode(data))
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.euler_number == 0
    assert abs(mesh.volume / TORUS_VOLUME - 1) < 0.005, mesh.volume  # 0.17 % below it at 64 cells
    assert driver.execute_script("return window.names") == ["torus.stl"]
    statuses = driver.execute_script("return window.statuses")
    assert any(s.startswith("meshing torus at 64 cells...") for s in statuses), statuses
    wait(driver, lambda d: text(d, "message").startswith("saved torus.stl: "), "no word of the saved file")
    assert "closed, Euler characteristic 0" in text(driver, "message")
    assert button.text == "Save mesh" and text(driver, "mesh-status") == ""


@browser
def test_save_mesh_of_a_surface_with_no_real_points_says_so_and_saves_nothing(page) -> None:
    from test_view_page import apply, text, wait

    driver, url = page
    _open_and_catch_downloads(driver, url)
    apply(driver, "x^2 + y^2 + z^2 + 1")
    wait(driver, lambda d: text(d, "degree") == "degree 2", "the equation was not accepted")
    driver.find_element("id", "save-mesh").click()
    wait(driver, lambda d: "no real points" in text(d, "message"), "no word of the empty mesh")
    assert text(driver, "message") == "save_mesh: no real points of the surface in the region meshed: nothing to mesh"
    assert driver.execute_script("return [window.saved.length, window.names.length]") == [0, 0]
    assert driver.find_element("id", "save-mesh").text == "Save mesh"
