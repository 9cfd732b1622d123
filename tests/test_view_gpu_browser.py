"""The viewer's GPU preview in real headless Chromium (WebGL2 on SwiftShader, a CPU emulation: small canvases).
While the view moves the page draws the picture itself with the shape's GLSL, at rest the server's frame
replaces it; the GPU's picture is checked against the double-precision tracer's (docs/viewer.md, "The GPU
preview"); a slider only sets uniforms; "compare with server" paints the differing and the not-sure pixels;
without WebGL2 or with a shader the browser refuses the server draws every frame, and the page says so; a
scene file is drawn by its GLSL program, at rest too, the server fixing the pixels it flags. Frame rates:
bench/view_gpu.py. Needs Debian's chromium and chromium-driver.
"""

from __future__ import annotations

import base64
import io
import os
import shutil
import time
from pathlib import Path
from urllib.parse import urlencode

import numpy as np
import pytest
import yaml
from PIL import Image

from implgen.imagefile import to_uint8
from implgen.measure.glslcases import chmutov
from implgen.measure.webgl import FLAGS
from implgen.scene.render import render
from implgen.view import protocol
from implgen.view.command import document_factory
from implgen.view.protocol import RANGES
from view_fixtures import view_process

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")
SIZE = (160, 120)  # the canvas: SwiftShader is a CPU
WAIT = 120  # seconds; generous (a busy machine), nothing here is a timing
NO_WEBGL2 = """
const original = HTMLCanvasElement.prototype.getContext;
HTMLCanvasElement.prototype.getContext = function (kind, ...rest) {
  return kind === "webgl2" ? null : original.call(this, kind, ...rest);
};
"""
REFUSE_SHADERS = """
const original = WebGL2RenderingContext.prototype.getShaderParameter;
WebGL2RenderingContext.prototype.getShaderParameter = function (shader, what) {
  return what === this.COMPILE_STATUS ? false : original.call(this, shader, what);
};
WebGL2RenderingContext.prototype.getShaderInfoLog = function () { return "ERROR: 0:1: refused by the test"; };
"""
A_GPU = """
const original = WebGL2RenderingContext.prototype.getParameter;
WebGL2RenderingContext.prototype.getParameter = function (what) {
  const e = this.getExtension("WEBGL_debug_renderer_info");
  return e && what === e.UNMASKED_RENDERER_WEBGL ? "ANGLE (a hardware GPU, said the test)" : original.call(this, what);
};
"""
GLASS = {"color": [1, 1, 1], "ambient": 0, "diffuse": 0, "specular": 0.8, "shininess": 200, "transparency": 1.0}
# two balls (the right one glass) either side of a CSG solid, on a floor: the camera on the z axis
GPU_SCENE = {
    "image": {"width": 64, "height": 48, "max_depth": 4},
    "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "fov": 40},
    "lights": [{"position": [0, 5, 5], "color": [1, 1, 1]}],
    "objects": [
        {"equation": "y + 2", "name": "floor"},
        {"equation": "(x + 2)^2 + y^2 + z^2 - 1", "name": "left"},
        {"equation": "(x - 2)^2 + y^2 + z^2 - 1", "name": "right", "material": {**GLASS, "ior": 1.5}},
        {"difference": [{"equation": "x^2 + y^2 + z^2 - 1"}, {"equation": "x^2 + (y - 0.8)^2 + z^2 - 0.36"}]},
    ],
}


# A shape called MAX_LIGHTS_ball (the page's main once had MAX_LIGHTS replaced in it) whose params are named as
# Object.prototype's members: its file is in the fuzz corpus.
PROTOTYPE_SPEC = Path(__file__).resolve().parent / "fuzz_corpus" / "object-prototype-param-names.yaml"
PROTOTYPE_NAMES = ["constructor", "toString", "valueOf", "hasOwnProperty"]
CATCH_ERRORS = "window.pageErrors = []; addEventListener('error', (e) => window.pageErrors.push(String(e.message)));"
SLIDERS = (
    "return [...document.querySelectorAll('input[type=range][data-name]')].map((s) => [s.dataset.name, +s.value]);"
)


@pytest.fixture(scope="module")
def torus_server():
    with view_process() as url:
        yield url


@pytest.fixture(scope="module")
def driver():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in FLAGS:
        opts.add_argument(arg)
    opts.add_argument("--force-device-scale-factor=1")
    d = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    d.set_script_timeout(WAIT)
    yield d
    d.quit()


def js(d, script: str, *args):
    return d.execute_script(script, *args)


def until(d, what, message: str):
    deadline = time.monotonic() + WAIT
    while True:
        got = what(d)
        if got:
            return got
        assert time.monotonic() < deadline, message
        time.sleep(0.05)


def view_state(d) -> dict:
    return js(
        d,
        "const v = document.getElementById('view'), g = document.getElementById('gpu-view');"
        "return {seq: +(v.dataset.seq ?? -1), kind: v.dataset.kind || '', frames: +(v.dataset.frames || 0),"
        " path: v.dataset.path, shown: v.dataset.shown || '', gl_frames: +(g.dataset.frames || 0), gl_hidden: g.hidden,"
        " note: document.getElementById('gpu-note').textContent};",
    )


def open_page(d, url: str, script: str | None = None, gpu: bool = True) -> dict:
    """Load the page at a SIZE canvas and wait for its refined picture; tick GPU preview (off by default on a
    software renderer); `script` runs before the page's own."""
    added = None
    if script is not None:
        added = d.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": script})["identifier"]
    try:
        d.get(url)
        until(d, lambda d: view_state(d)["kind"] == "full", "no picture")
    finally:
        if script is not None:
            d.execute_cdp_cmd("Page.removeScriptToEvaluateOnNewDocument", {"identifier": added})
    js(
        d,
        "const s = document.getElementById('stage'); s.style.flex = 'none';"
        "s.style.width = arguments[0] + 'px'; s.style.height = arguments[1] + 'px';",
        *SIZE,
    )
    size = "const c = document.getElementById('view'); return [c.width, c.height]"
    until(d, lambda d: js(d, size) == list(SIZE), "the canvas did not take its size")
    seq = view_state(d)["seq"]
    until(d, lambda d: view_state(d)["seq"] > seq and view_state(d)["kind"] == "full", "no picture at the new size")
    if gpu and js(d, "return !document.getElementById('gpu').disabled"):
        if not js(d, "return document.getElementById('gpu').checked"):
            d.find_element("id", "gpu").click()
    return view_state(d)


def png(d, element_id: str, mode: str = "RGB") -> np.ndarray:
    url = js(d, f"return document.getElementById('{element_id}').toDataURL('image/png');")
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert(mode)).astype(int)


def gl_pixels(d, what: str = "readPixels") -> np.ndarray:
    """The GPU renderer's drawing buffer (or its status pass), RGBA, top row first."""
    b64 = js(
        d,
        f"const p = implgenGpu.renderer().{what}(); let s = '';"
        "for (let i = 0; i < p.length; i += 32768) s += String.fromCharCode.apply(null, p.subarray(i, i + 32768));"
        "return btoa(s);",
    )
    w, h = SIZE
    return np.frombuffer(base64.b64decode(b64), np.uint8).reshape(h, w, 4)[::-1].astype(int)


def drag(d, steps: int = 6, dx: int = 12, during=None) -> list:
    """A mouse drag across the picture, `during(d)` called after each step (the button still down)."""
    from selenium.webdriver.common.action_chains import ActionChains

    seen = []
    canvas = d.find_element("id", "view")
    # every kind of frame the server draws during the drag (a pointer held still DRAG_REST ms is refined, so a
    # sample after each step may find the refined one)
    js(
        d,
        "const v = document.getElementById('view'); window.drawnWhileDragging = [];"
        "window.dragWatch = new MutationObserver(() => window.drawnWhileDragging.push(v.dataset.kind));"
        "window.dragWatch.observe(v, {attributes: true, attributeFilter: ['data-seq', 'data-kind']});",
    )
    ActionChains(d).move_to_element(canvas).click_and_hold().move_by_offset(5, 0).perform()
    for _ in range(steps):
        ActionChains(d).move_by_offset(dx, 2).perform()
        time.sleep(0.15)
        if during:
            seen.append(during(d))
    ActionChains(d).release().perform()
    js(d, "window.dragWatch.disconnect();")
    return seen


def drawn_while_dragging(d) -> list:
    """The kinds of the server frames drawn during the last `drag`, in order."""
    return js(d, "return window.drawnWhileDragging;")


def reference(d) -> np.ndarray:
    """The double-precision tracer's picture of the page's view at 1 sample a pixel (the pixel's centre, as the
    GPU's): the page's orbit, options and param values, the starter torus."""
    state = js(d, "return window.implgenState()")
    doc = document_factory(None)()
    doc.orbit = protocol.parse_orbit(state["orbit"])
    doc.options = protocol.parse_options(state["options"])
    doc.values = protocol.parse_values(state["values"], doc.spec)
    return to_uint8(render(doc.scene(*SIZE, 1), threads=2)).astype(int)


def neighbours(img: np.ndarray) -> np.ndarray:
    """The 3x3 neighbourhood of each pixel, stacked on a new first axis (edges repeated)."""
    h, w = img.shape[:2]
    pad = np.pad(img, ((1, 1), (1, 1)) + ((0, 0),) * (img.ndim - 2), mode="edge")
    return np.stack([pad[y : y + h, x : x + w] for y in range(3) for x in range(3)])


def edges(img: np.ndarray, background: np.ndarray) -> np.ndarray:
    """Pixels on an edge of the picture: a silhouette (the 3x3 neighbourhood holds the background and something
    else) or a shadow's edge (the neighbourhood's colours span more than 32 levels)."""
    bg = neighbours((img == background).all(axis=2))
    near = neighbours(img)
    return (bg.any(axis=0) & ~bg.all(axis=0)) | ((near.max(axis=0) - near.min(axis=0)).max(axis=2) > 32)


def envelope_excess(mine: np.ndarray, server: np.ndarray) -> np.ndarray:
    """How far each pixel is outside the range of the server's 3x3 neighbourhood (max over channels)."""
    stack = neighbours(server)
    lo, hi = stack.min(axis=0), stack.max(axis=0)
    return np.maximum(np.maximum(lo - mine, mine - hi), 0).max(axis=2)


def test_the_gpu_draws_while_dragging_and_the_server_at_rest(torus_server, driver) -> None:
    d = driver
    driver.get(torus_server)
    until(d, lambda d: view_state(d)["kind"] == "full", "no picture")
    first = view_state(d)
    assert "software renderer" in first["note"] and not js(d, "return document.getElementById('gpu').checked")
    assert first["path"] == "server"  # SwiftShader: off unless ticked
    before = open_page(d, torus_server)
    until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start")
    assert "drawing: the GPU while the view moves" in view_state(d)["note"]
    resting = png(d, "view")
    drawn = view_state(d)["gl_frames"]

    seen = drag(d, during=lambda d: (view_state(d), gl_pixels(d)[..., :3]))
    moving = [s for s, _ in seen]
    assert all(s["shown"] == "gpu" and not s["gl_hidden"] for s in moving), [(s["shown"], s["kind"]) for s in moving]
    assert moving[-1]["gl_frames"] > drawn  # the GPU drew during the drag
    assert {s["frames"] for s in moving} == {before["frames"]}  # and the server sent nothing meanwhile
    live = seen[-1][1]
    assert np.abs(live - resting).mean() > 2  # the view turned

    until(d, lambda d: view_state(d)["shown"] == "server" and view_state(d)["kind"] == "full", "no server frame")
    after = view_state(d)
    assert after["gl_hidden"] and after["seq"] > before["seq"]
    server = png(d, "view")
    # the last live picture (coarse blocks on SwiftShader, maybe) is the view the server drew at rest
    assert np.abs(live - server).mean() < 6, np.abs(live - server).mean()
    assert js(d, "return document.querySelector('#overlay').textContent") == ""


@pytest.mark.parametrize("clip,size,cut,lights", [("sphere", 1.1, False, "studio"), ("box", 0.9, True, "top")])
def test_the_gpu_picture_is_the_server_s_and_compare_shows_the_difference(
    torus_server, driver, clip, size, cut, lights
):
    """The torus, zoomed in and cut by the clip (SURFER's open cut, the inside showing; or the cut solid), under
    the studio lights (moving with the camera) or the top light (fixed in the world), at the page's view: the
    GPU's full frame against the tracer's at 1 sample a pixel (the same rays) and against the server's refined
    frame (4 samples); the compare overlay paints exactly the pixels that differ."""
    d = driver
    open_page(d, torus_server)
    until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start")
    d.find_element("id", "compare").click()
    seq = view_state(d)["seq"]
    js(
        d,
        "const $ = (id) => document.getElementById(id);"
        "$('clip').value = arguments[0]; $('clip-size').value = arguments[1]; $('cut').checked = arguments[2];"
        "$('lights').value = arguments[3];"
        "for (let i = 0; i < 3; ++i) $('view').dispatchEvent(new WheelEvent('wheel', {deltaY: -250}));"
        "for (const id of ['clip', 'clip-size', 'cut', 'lights']) $(id).dispatchEvent(new Event('change'));",
        clip,
        size,
        cut,
        lights,
    )
    until(d, lambda d: view_state(d)["seq"] > seq and view_state(d)["kind"] == "full", "no refined frame")
    shown = "const o = document.getElementById('compare-view'); return o.hidden ? null : o.dataset.seq"
    until(d, lambda d: js(d, shown) == str(view_state(d)["seq"]), "no compare overlay of the last frame")
    mine = gl_pixels(d)[..., :3]
    unsure = gl_pixels(d, "statusPixels")[..., 1] > 127
    server = png(d, "view")
    ref = reference(d)
    state = js(d, "return window.implgenState()")
    assert state["options"]["clip"] == clip and state["options"]["cut"] == cut and state["options"]["lights"] == lights
    background = to_uint8(np.array(state["options"]["background"])).astype(int)
    edge = edges(ref, background) | edges(mine, background)

    assert (~(ref == background).all(axis=2)).mean() > 0.3  # the torus fills a good part of the frame
    # the inside colour (blue: 2.7 times as much blue as red, lit or not): through the opening, or the cut face
    bluish = ref[..., 2] > 1.8 * ref[..., 0] + 5
    assert bluish.mean() > 0.02 and (bluish == (mine[..., 2] > 1.8 * mine[..., 0] + 5)).mean() > 0.99
    off = np.abs(mine - ref).max(axis=2)
    assert (off > 3).mean() < 0.01, (off > 3).mean()  # the same picture, float against double
    assert ((off > 24) & ~edge & ~unsure).sum() == 0  # a clear difference only on an edge or flagged
    assert (off > 24).sum() <= 0.005 * off.size  # and few of those

    excess = envelope_excess(mine, server)
    differ = excess > 8
    assert differ.mean() < 0.01 and (differ & ~edge & ~unsure).sum() == 0
    overlay = png(d, "compare-view", "RGBA")
    shown = overlay[..., 3] > 0
    assert (shown == (differ | unsure)).all()
    red = (overlay[..., :3] == (255, 48, 48)).all(axis=2)
    cyan = (overlay[..., :3] == (0, 230, 255)).all(axis=2)
    assert (red == (differ & ~unsure)).all() and (cyan == (unsure & ~differ)).all()
    counts = js(d, "const o = document.getElementById('compare-view').dataset; return [+o.differ, +o.unsure];")
    assert counts == [int(differ.sum()), int(unsure.sum())]
    assert js(d, "return document.getElementById('gpu-note').textContent").startswith("compare: ")
    d.find_element("id", "compare").click()
    assert js(d, "return document.getElementById('compare-view').hidden")


def test_a_slider_sets_uniforms_only(torus_server, driver) -> None:
    d = driver
    open_page(d, torus_server)
    until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start")
    js(
        d,
        "const r = implgenGpu.renderer(); window.builds = 0; const f = r.setEquationProgram.bind(r);"
        "r.setEquationProgram = (...a) => { window.builds += 1; return f(...a); }; window.prog = r.prog;",
    )
    before = view_state(d)
    # a hand on the slider: an input event every 50 ms (the page's rest timer, 180 ms, never fires meanwhile)
    log = d.execute_async_script(
        "const done = arguments[arguments.length - 1], s = document.querySelector('input[type=range][data-name=b]');"
        "const v = document.getElementById('view'), g = document.getElementById('gpu-view'), log = [];"
        "let i = 0; const t = setInterval(() => {"
        "  s.value = 0.35 + 0.01 * ++i; s.dispatchEvent(new Event('input'));"
        "  log.push([v.dataset.shown, +(g.dataset.frames || 0), +(v.dataset.frames || 0), g.hidden]);"
        "  if (i === 15) { clearInterval(t); done(log); } }, 50);"
    )
    first = next(i for i, (shown, _, _, _) in enumerate(log) if shown == "gpu")  # from the first GPU picture on
    assert all(shown == "gpu" and not hidden for shown, _, _, hidden in log[first:])
    assert log[-1][1] > log[0][1] and {server for _, _, server, _ in log} == {before["frames"]}
    until(d, lambda d: abs(js(d, "return implgenGpu.renderer().params[1]") - 0.5) < 1e-6, "the uniform did not change")
    assert js(d, "return window.builds === 0 && implgenGpu.renderer().prog === window.prog")
    js(d, "implgenGpu.renderer().draw({});")  # the whole frame at once (the page's may be in bands)
    thick = gl_pixels(d)[..., :3]
    js(d, "implgenGpu.renderer().setParams([1.0, 0.35]); implgenGpu.renderer().draw({});")
    thin = gl_pixels(d)[..., :3]
    background = thin[0, 0]
    assert (thick != background).any(axis=2).sum() > 1.1 * (thin != background).any(axis=2).sum()  # a thicker tube
    js(d, "document.querySelector('input[type=range][data-name=b]').dispatchEvent(new Event('change'));")
    until(d, lambda d: view_state(d)["shown"] == "server" and view_state(d)["kind"] == "full", "no server frame")
    assert js(d, "return window.implgenState().values.b") == pytest.approx(0.5)


@pytest.mark.parametrize(
    "script,says", [(NO_WEBGL2, "this browser has no WebGL2"), (REFUSE_SHADERS, "the shader did not compile")]
)
def test_without_webgl2_or_a_shader_the_server_draws_as_before(torus_server, driver, script, says) -> None:
    d = driver
    before = open_page(d, torus_server, script=script)
    until(d, lambda d: says in view_state(d)["note"], f"the page did not say: {says}")
    assert view_state(d)["path"] == "server"
    kinds = drag(d, during=lambda d: view_state(d))
    assert "coarse" in drawn_while_dragging(d), "no coarse server frames while dragging"
    assert all(k["gl_hidden"] and k["gl_frames"] == 0 for k in kinds)
    until(d, lambda d: view_state(d)["kind"] == "full" and view_state(d)["seq"] > before["seq"], "no refined frame")


def test_with_a_hardware_gpu_the_preview_is_on_from_the_start(torus_server, driver) -> None:
    """The renderer's name is not a software one: the box is ticked and the first drag is the GPU's."""
    d = driver
    before = open_page(d, torus_server, script=A_GPU, gpu=False)
    assert js(d, "return document.getElementById('gpu').checked")
    until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start")
    assert "a hardware GPU, said the test" in view_state(d)["note"]
    moving = drag(d, steps=3, during=lambda d: view_state(d))
    assert all(s["shown"] == "gpu" for s in moving) and moving[-1]["gl_frames"] > 0
    until(d, lambda d: view_state(d)["shown"] == "server" and view_state(d)["seq"] > before["seq"], "no server frame")


def scene_reference(d, path: Path) -> np.ndarray:
    """The double-precision tracer's picture of the page's view of a scene file at 1 sample a pixel."""
    from implgen.scene.load import load_scene
    from implgen.view.document import Document

    state = js(d, "return window.implgenState()")
    doc = Document.for_scene(load_scene(path))
    doc.orbit = protocol.parse_orbit(state["orbit"])
    doc.options = protocol.parse_options(state["options"])
    return to_uint8(render(doc.scene(*SIZE, 1), threads=2)).astype(int)


def fixed_state(d) -> tuple[int, int]:
    """(the seq of the last rest the page fixed, how many pixels the server gave it)."""
    return tuple(
        js(d, "const v = document.getElementById('view').dataset; return [+(v.fixSeq ?? -1), +(v.fixed ?? -1)];")
    )


def test_a_scene_is_drawn_on_the_gpu_and_the_server_fixes_its_flagged_pixels(tmp_path, driver) -> None:
    """A scene file with CSG, glass and several shapes: the GPU draws it at rest (once its program has come) and
    while dragging (no server frame meanwhile); at rest the page keeps the GPU's picture and puts in the server's
    double-precision pixels where the GLSL flagged "not sure" -- and, to test the compositing whatever the GPU
    flags, every 9th pixel flagged as well by a wrapped status pass: those pixels are exactly the tracer's at one
    sample, the others the GPU's. A click on a ball still picks it (its equation in the box), and the same scene's
    program is not compiled again."""
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(GPU_SCENE))
    d = driver
    more_flags = (
        "window.addEventListener('load', () => { const f = IgSceneRenderer.prototype.statusPixels;"
        "IgSceneRenderer.prototype.statusPixels = function (...a) { const s = f.apply(this, a);"
        "for (let i = 0; i < s.length / 4; i += 9) s[4 * i + 1] = 255; return s; }; });"
    )
    with view_process(str(path)) as url:
        open_page(d, url, script=more_flags)
        until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU did not take the scene")
        assert "the scene (5 shapes, CSG, glass), the GPU while the view moves" in view_state(d)["note"]
        until(d, lambda d: view_state(d)["shown"] == "fixed", "no fixed picture at rest")
        frames = view_state(d)["frames"]
        js(d, "const r = implgenGpu.renderer(); window.prog = r.prog; r.draw({});")
        gpu_picture, status = gl_pixels(d)[..., :3], gl_pixels(d, "statusPixels")
        flagged = status[..., 1] > 127
        picture, ref = png(d, "view"), scene_reference(d, path)
        assert fixed_state(d)[1] == flagged.sum() and flagged.mean() > 0.1
        assert (picture[flagged] == ref[flagged]).all()  # the server's pixels, exactly
        assert (picture[~flagged] == gpu_picture[~flagged]).all()  # the GPU's elsewhere
        hits = status[..., 0] > 127
        assert hits.mean() > 0.3 and (np.abs(gpu_picture - ref).max(axis=2) > 24).mean() < 0.02  # and it is the scene

        before = fixed_state(d)[0]
        moving = drag(d, during=lambda d: view_state(d))
        assert all(s["shown"] == "gpu" and not s["gl_hidden"] for s in moving), [s["shown"] for s in moving]
        assert moving[-1]["gl_frames"] > moving[0]["gl_frames"] and drawn_while_dragging(d) == []
        until(d, lambda d: fixed_state(d)[0] > before, "no fixed picture after the drag")
        assert view_state(d)["frames"] == frames  # no server frame: only pixels

        from selenium.webdriver.common.action_chains import ActionChains

        js(d, "implgenGpu.renderer().setSceneProgram = () => 'compiled again';")  # the same program: not compiled
        ActionChains(d).move_to_element_with_offset(d.find_element("id", "view"), -33, 0).click().perform()
        until(d, lambda d: js(d, "return document.getElementById('equation').value").startswith("(x + 2)"), "no pick")
        until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU did not take the scene back after the pick")
        assert js(d, "return implgenGpu.renderer().prog === window.prog")

        # an edit of the picked ball: a new program, compiled, and the GPU draws the smaller ball
        js(d, "delete implgenGpu.renderer().setSceneProgram;")  # the prototype's again
        js(
            d,
            "const e = document.getElementById('equation'); e.value = '(x + 2)^2 + y^2 + z^2 - 0.25';"
            "e.dispatchEvent(new KeyboardEvent('keydown', {key: 'Enter'}));",
        )
        edited = "return implgenGpu.renderer().prog !== window.prog && window.implgenGpu.active()"
        until(d, lambda d: js(d, edited), "no new program for the edited scene")
        assert "(x + 2)^2 + y^2 + z^2 - 0.25" not in js(d, "return implgenGpu.renderer().fragment")  # as numbers
        until(d, lambda d: view_state(d)["shown"] == "fixed", "no fixed picture of the edited scene")
        js(d, "implgenGpu.renderer().draw({});")
        hits = gl_pixels(d, "statusPixels")[..., 2]  # the object + 1 of each pixel's camera ray
        assert (hits == 2).sum() < 0.5 * (status[..., 2] == 2).sum()  # the left ball (object 1) is smaller


def test_past_the_glsl_budget_a_scene_is_the_server_s_and_the_page_says_so(tmp_path, driver) -> None:
    """A scene holding Chmutov's degree-12 surface typed expanded in its box, under a 0.01 s GLSL budget: its
    program is not done in time, the page says so, and the server draws every frame, a drag's coarse ones too."""
    spec = chmutov(12, nested=False)
    bounds = {a: [float(lo), float(hi)] for a, (lo, hi) in spec.bounds.items()}
    scene = {**GPU_SCENE, "objects": [*GPU_SCENE["objects"][:2], {"equation": spec.equation, "bounds": bounds}]}
    path = tmp_path / "slow.yaml"
    path.write_text(yaml.safe_dump(scene))
    d = driver
    with view_process(str(path), env={**os.environ, "IMPLGEN_VIEW_GLSL_BUDGET": "0.01"}) as url:
        open_page(d, url)
        said = "the scene's GLSL was not done within the 0.01 s GLSL budget"
        until(d, lambda d: said in view_state(d)["note"], "the page did not say why")
        assert view_state(d)["path"] == "server"
        kinds = drag(d, during=lambda d: view_state(d))
        assert "coarse" in drawn_while_dragging(d) and all(k["gl_frames"] == 0 for k in kinds)


def test_past_the_glsl_budget_the_page_says_the_gpu_draws_the_tree(tmp_path, driver) -> None:
    """The GLSL derivation and Export page have a budget (IMPLGEN_VIEW_GLSL_BUDGET); past it the shader
    evaluates f's tree as written, and the page says so beside the GPU preview and after Export page. Chmutov's
    degree-12 surface typed expanded in its box, whose Chebyshev form needs more than 0.01 s."""
    spec = chmutov(12, nested=False)
    bounds = {a: [float(lo), float(hi)] for a, (lo, hi) in spec.bounds.items()}
    path = tmp_path / "power.yaml"
    path.write_text(yaml.safe_dump({"name": "power", "equation": spec.equation, "bounds": bounds}))
    d = driver
    with view_process(str(path), env={**os.environ, "IMPLGEN_VIEW_GLSL_BUDGET": "0.01"}) as url:
        open_page(d, url)
        until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start")
        note = view_state(d)["note"]
        assert "the GLSL evaluates f as written" in note and "0.01 s GLSL budget" in note, note
        d.find_element("id", "export-page").click()
        said = "const m = document.getElementById('message').textContent;"
        said += "return m.startsWith('saved power.html: ') && m.includes(\"; the exported page's shader: \");"
        until(d, lambda d: js(d, said), "Export page said nothing")


def test_params_named_as_object_prototype_s_members(driver) -> None:
    """constructor, toString, valueOf and hasOwnProperty as params, from a spec file and from a share link whose
    values name __proto__ too: a slider for each, the server's picture, the GPU's (its shader compiles, and the
    constructor slider sets its uniform), no script error; the link's value reaches its slider."""
    d = driver
    with view_process(str(PROTOTYPE_SPEC)) as url:
        open_page(d, url, script=CATCH_ERRORS)
        assert js(d, SLIDERS) == [[n, v] for n, v in zip(PROTOTYPE_NAMES, [1.0, 1.0, 0.5, 0.5])]
        picture = png(d, "view")
        assert (np.abs(picture - picture[0, 0]).max(axis=2) > 8).mean() > 0.05  # the ball, not the background
        until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start")
        drawn = view_state(d)["gl_frames"]
        js(
            d,
            "const s = document.querySelector('input[type=range][data-name=constructor]');"
            "s.value = 1.3; s.dispatchEvent(new Event('input'));",
        )
        until(d, lambda d: abs(js(d, "return implgenGpu.renderer().params[0]") - 1.3) < 1e-6, "no uniform set")
        until(d, lambda d: view_state(d)["gl_frames"] > drawn, "the GPU drew nothing")
        assert js(d, "return window.pageErrors") == []

        values = "constructor:1.2,toString:1,valueOf:0.5,hasOwnProperty:0.5,__proto__:3"
        params = ", ".join(f"{n} = {v}" for n, v in zip(PROTOTYPE_NAMES, [1, 1, 0.5, 0.5]))
        eq = "x^2 + y^2 + z^2 - constructor*toString + valueOf*hasOwnProperty"
        link = {"v": "1", "eq": eq, "name": "MAX_LIGHTS_ball", "params": params, "values": values}
        d.get("about:blank")
        open_page(d, f"{url}#{urlencode(link)}", script=CATCH_ERRORS)
        until(d, lambda d: js(d, "return window.implgenState().values.constructor") == 1.2, "the link's value")
        decoded = (
            "return Object.keys(implgenLink.decode(arguments[0], arguments[1]).view.values)"  # the server's ranges
        )
        ranges = {k: list(v) for k, v in RANGES.items()}
        assert js(d, decoded, "#" + urlencode(link), ranges) == [*PROTOTYPE_NAMES, "__proto__"]  # a key like any other
        shown = dict(js(d, SLIDERS))
        assert sorted(shown) == sorted(PROTOTYPE_NAMES) and shown["constructor"] == 1.2
        assert js(d, "return document.getElementById('message').textContent") == ""
        until(d, lambda d: view_state(d)["path"] == "gpu", "the GPU preview did not start from the link")
        assert js(d, "return window.pageErrors") == []
