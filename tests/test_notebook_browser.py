"""`implgen.show` in a real JupyterLab, driven in headless Chromium (SwiftShader's WebGL2, as the shared page's
browser tests): the notebook's cell runs in a kernel, the widget draws the ball with the generated GLSL, its
disc as large as the camera's geometry says; the slider moves to r = 0.5 and the disc shrinks to a quarter; the
kernel hears the new value; the orbit and the param set from Python move the view; the browser's console holds
no error."""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
import time
import urllib.request

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_notebook

from test_notebook import disc_area

WAIT = 240  # seconds for each step on a loaded 2-core machine
TOKEN = "implgen-test"
CELLS = [
    'import implgen\nw = implgen.show("x^2 + y^2 + z^2 - r^2", r=1.0)\nw',
    "import json; print(json.dumps({'values': w.values, 'webgl': w.webgl}))",
    "w.orbit = {**w.orbit, 'distance': w.orbit['distance'] / 2}; w.values = [1.0]",
]
# the widget's canvas: pixels that are not the background (31, 31, 36)
COVERED_FN = """() => {
const r = document.querySelector('.implgen-widget').implgen.renderer; const p = r.readPixels(); let n = 0;
const far = (i) => Math.abs(p[i] - 31) + Math.abs(p[i + 1] - 31) + Math.abs(p[i + 2] - 36) > 12;
for (let i = 0; i < p.length; i += 4) if (far(i)) n++;
return n; }"""
COVERED = f"return ({COVERED_FN})();"
# the widget's state once it has drawn more than n frames and rests
DRAWN = """const e = document.querySelector('.implgen-widget'); const s = e && e.implgen;
return s && s.drawn > {n} && (!s.progressive || s.progressive.idle) ? {{drawn: s.drawn, mode: s.mode}} : null;"""
LAST_OUTPUT = """const o = [...document.querySelectorAll('.jp-OutputArea-output pre')].map((e) => e.innerText);
return o.length && o[o.length - 1].includes('0.5') ? o[o.length - 1] : '';"""


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def lab(tmp_path):
    """JupyterLab on a free port over tmp_path/nb holding the notebook; yields its URL for the notebook."""
    root = tmp_path / "nb"
    root.mkdir()
    nb = new_notebook(cells=[new_code_cell(c) for c in CELLS])
    nb.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    nbformat.write(nb, root / "ball.ipynb")
    port = free_port()
    dirs = {
        k: str(tmp_path / k.lower()) for k in ("JUPYTER_CONFIG_DIR", "JUPYTERLAB_SETTINGS_DIR", "JUPYTER_RUNTIME_DIR")
    }
    env = dict(os.environ, JUPYTERLAB_WORKSPACES_DIR=str(tmp_path / "ws"), **dirs)
    cmd = [sys.executable, "-m", "jupyterlab", "--no-browser", "--allow-root", f"--ServerApp.port={port}"]
    cmd += ["--ServerApp.ip=127.0.0.1", f"--IdentityProvider.token={TOKEN}", f"--ServerApp.root_dir={root}"]
    cmd += ["--LabApp.expose_app_in_browser=True", "--LabApp.check_for_updates_class=jupyterlab.NeverCheckForUpdate"]
    log = open(tmp_path / "lab.log", "w")  # noqa: SIM115 -- closed below, after the server
    server = subprocess.Popen(cmd, env=env, stdout=log, stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + WAIT
        while True:
            assert server.poll() is None, (tmp_path / "lab.log").read_text()[-3000:]
            try:
                urllib.request.urlopen(f"http://127.0.0.1:{port}/api/status?token={TOKEN}", timeout=5)
                break
            except OSError:
                assert time.monotonic() < deadline, "JupyterLab did not start"
                time.sleep(0.3)
        yield f"http://127.0.0.1:{port}/lab/tree/ball.ipynb?token={TOKEN}"
    finally:
        server.terminate()
        server.wait(60)
        log.close()


def wait(d, script: str, what: str):
    deadline = time.monotonic() + WAIT
    while not (value := d.execute_script(script)):
        assert time.monotonic() < deadline, f"{what}: not within {WAIT} s"
        time.sleep(0.25)
    return value


def run_cell(d, index: int) -> None:
    d.execute_script(
        "const nb = window.jupyterapp.shell.currentWidget.content; nb.activeCellIndex = arguments[0];"
        "window.jupyterapp.commands.execute('notebook:run-cell');",
        index,
    )


ACCEPT_KERNEL = """
const b = document.querySelector('.jp-Dialog .jp-mod-accept'); if (b) { b.click(); return false; }
const c = window.jupyterapp.shell.currentWidget && window.jupyterapp.shell.currentWidget.sessionContext;
return !!(c && c.session && c.session.kernel && c.session.kernel.status === 'idle');"""


@pytest.mark.needs_program("chromium", "chromedriver")
def test_the_widget_draws_in_jupyterlab_and_the_slider_moves_it(lab):
    from implgen.measure.webgl import WebGL

    with WebGL(console_log=True) as gl:
        d = gl.driver
        d.get(lab)
        wait(d, "return !!(window.jupyterapp && document.querySelector('.jp-Notebook .jp-Cell'));", "JupyterLab")
        # JupyterLab may ask which kernel, in a dialog that comes late: the notebook's own, until it is idle
        wait(d, ACCEPT_KERNEL, "the kernel")
        run_cell(d, 0)
        state = wait(d, DRAWN.format(n=0), "the widget's drawing")
        assert state["mode"] == "gpu"
        before = d.execute_script(COVERED)
        d.execute_script(
            "const s = document.querySelector('.implgen-widget input[type=range]'); s.value = 0.5;"
            "s.dispatchEvent(new Event('input')); s.dispatchEvent(new Event('change'));"
        )
        wait(d, DRAWN.format(n=state["drawn"]), "the redraw")
        after = d.execute_script(COVERED)
        home = {"fov": 40.0, "distance": 3.0 / math.sin(math.radians(20.0)) * 1.1}  # share.page.framing, unbounded
        assert before == pytest.approx(disc_area(1.0, home, 360), rel=0.03)
        assert after == pytest.approx(disc_area(0.5, home, 360), rel=0.05)
        # the second cell: the kernel has the slider's value
        run_cell(d, 1)
        text = wait(d, LAST_OUTPUT, "the kernel's answer")
        assert json.loads(text) == {"values": [0.5], "webgl": "yes"}
        # the third cell sets the orbit and the param from Python: the view follows
        drawn = d.execute_script("return document.querySelector('.implgen-widget').implgen.drawn;")
        run_cell(d, 2)
        wait(d, DRAWN.format(n=drawn), "the redraw from Python")
        near = {**home, "distance": home["distance"] / 2}
        wait(
            d,
            f"return Math.abs(({COVERED_FN})() - {disc_area(1.0, near, 360)}) < {0.03 * disc_area(1.0, near, 360)};",
            "the nearer, larger ball",
        )
        errors = [e["message"] for e in d.get_log("browser") if e["level"] == "SEVERE"]
        assert not errors, errors
