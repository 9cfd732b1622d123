"""`implgen.show`, the notebook widget (docs/notebook.md), without a browser: what it sends the view (the shape's
GLSL exactly as `implgen --lang glsl` writes it, the runtime, the sliders, the shared page's framing), the
kernel's pictures (a sphere's disc as large as the camera's geometry says, a scene's frame as `implgen render`
draws it, the orbit turning it), the fallback without WebGL2, bad input as one line, and the example notebook
examples/notebooks/tour.ipynb executed by nbclient, its saved outputs holding the widget and a PNG."""

from __future__ import annotations

import base64
import io
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import implgen
from conftest import ROOT, SHAPES_DIR
from implgen.codegen.backends.glsl.program import runtime_text
from implgen.errors import UserError
from implgen.notebook import picture
from implgen.scene.preview import BACKGROUND
from implgen.spec.entry import load_spec

SCENES = ROOT / "examples" / "scenes"
NOTEBOOK = ROOT / "examples" / "notebooks" / "tour.ipynb"


def pixels(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def covered(png: bytes) -> int:
    """Pixels that are not the background."""
    bg = np.array([round(c * 255) for c in BACKGROUND])
    return int(np.count_nonzero(np.abs(pixels(png) - bg).max(axis=2) > 6))


def disc_area(radius: float, orbit: dict, height: int) -> float:
    """The pixels a ball of `radius` at the orbit's target covers: its silhouette's half-angle asin(r/d)."""
    focal = (height / 2) / math.tan(math.radians(orbit["fov"] / 2))
    return math.pi * (focal * math.tan(math.asin(radius / orbit["distance"]))) ** 2


def test_an_equation_sends_its_glsl_sliders_and_framing():
    w = implgen.show("x^2 + y^2 + z^2 - r^2", r=1.5)
    assert w.mode == "gpu" and w.values == [1.5]
    data = {"name": "surface", "equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1.5}}
    spec = implgen.parse_spec(data, "<equation>")
    assert w.data["shape"] == implgen.generate(spec, ("glsl",))["surface.glsl"]
    assert w.data["runtime"] == runtime_text()
    assert w.data["params"] == [{"name": "r", "value": 1.5, "min": 0.0, "max": 3.0}]
    assert w.data["clip"] == {"kind": "sphere", "size": 3.0, "cut": False}  # unbounded: the page's clip sphere
    assert w.orbit["target"] == [0.0, 0.0, 0.0] and (w.orbit["yaw"], w.orbit["pitch"]) == (30.0, 25.0)


def test_a_spec_file_with_params_overridden():
    w = implgen.show(SHAPES_DIR / "torus_y.yaml", b=0.4)
    spec = load_spec(SHAPES_DIR / "torus_y.yaml")
    assert w.values == [spec.params["a"], 0.4] and w.data["name"] == "torus_y"
    assert implgen.show(str(SHAPES_DIR / "heart.yaml")).data["name"] == "heart"


def test_the_kernel_picture_is_the_ball_the_camera_sees():
    """_repr_png_: the kernel's picture in double. A ball's disc covers what its silhouette's angle says, and a
    slider (values) set from Python changes it by the square of the radius."""
    w = implgen.show("x^2 + y^2 + z^2 - r^2", r=1.0)
    png = w._repr_png_()
    assert png.startswith(b"\x89PNG") and pixels(png).shape == (360, 480, 3)
    assert covered(png) == pytest.approx(disc_area(1.0, w.orbit, 360), rel=0.03)
    w.values = [0.5]
    assert covered(w._repr_png_()) == pytest.approx(disc_area(0.5, w.orbit, 360), rel=0.05)


def test_without_webgl2_the_kernel_draws_and_follows_the_orbit():
    w = implgen.show("x^2 + y^2 + z^2 - r^2", r=1.0)
    assert w.frame == b""
    w.webgl = "this browser has no WebGL2"  # what the view reports
    assert w.mode == "frames" and w.frame == w._repr_png_()
    before = covered(w.frame)
    w.orbit = {**w.orbit, "distance": w.orbit["distance"] / 2}  # zoomed in: a larger disc
    assert covered(w.frame) == pytest.approx(disc_area(1.0, w.orbit, 360), rel=0.03) and covered(w.frame) > before


def test_a_scene_is_the_tracers_frames_and_turns():
    w = implgen.show(SCENES / "torus_shadow.yaml")
    assert w.mode == "frames" and w.data == {} and w.values == []
    scene = implgen.load_scene(SCENES / "torus_shadow.yaml")
    assert np.array_equal(pixels(w.frame), pixels(picture.png(scene, (480, 360))))
    home, first = dict(w.orbit), w.frame
    assert picture.orbit_camera(home).position == pytest.approx(scene.camera.position)
    w.orbit = {**home, "yaw": home["yaw"] + 40}
    assert not np.array_equal(pixels(w.frame), pixels(first))
    w.orbit = home
    assert w.frame == first


@pytest.mark.parametrize(
    ("args", "params", "message"),
    [
        (("x^2 + w",), {}, "<equation>: equation: unknown symbol 'w' at column 7 (known: x, y, z)"),
        (("x^2 + y^2 + z^2 - r",), {"r": "1"}, "implgen.show: param 'r': expected a finite number"),
        (("x^2 + y^2 + z^2 - r",), {"r": math.nan}, "implgen.show: param 'r': expected a finite number"),
        ((str(SHAPES_DIR / "torus_y.yaml"),), {"q": 1}, "no param 'q' (params: a, b)"),
        ((str(SCENES / "torus_shadow.yaml"),), {"a": 1}, "a scene takes no params"),
        (("missing.yaml",), {}, "missing.yaml: not found"),
        ((42,), {}, "implgen.show: expected a spec or scene file, or an equation as text, got int"),
        (('x"}; alert(1); {"',), {}, "<equation>: equation:"),
    ],
)
def test_bad_input_is_one_line(args, params, message):
    with pytest.raises(UserError) as err:
        implgen.show(*args, **params)
    assert message in str(err.value) and "\n" not in str(err.value)


def test_the_example_notebook_runs_and_keeps_its_pictures(tmp_path):
    """Executed by nbclient in a real kernel: every code cell runs without error, each widget's output holds the
    widget view and the kernel's PNG (what a saved or converted notebook shows)."""
    import nbclient
    import nbformat

    nb = nbformat.read(NOTEBOOK, as_version=4)
    assert all(not c.get("outputs") for c in nb.cells if c.cell_type == "code"), "the example is saved without outputs"
    client = nbclient.NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": str(NOTEBOOK.parent)}}
    )
    client.execute()
    shown = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs if "image/png" in o.get("data", {})]
    assert len(shown) == 3
    for out in shown:
        assert "application/vnd.jupyter.widget-view+json" in out["data"]
        assert Image.open(io.BytesIO(base64.b64decode(out["data"]["image/png"]))).size == (480, 360)
    assert "[1.0, 0.5]" in str(nb.cells[5].outputs[0]["data"]["text/plain"])
    nbformat.write(nb, tmp_path / "tour.ipynb")
    assert Path(tmp_path / "tour.ipynb").stat().st_size > 10_000
