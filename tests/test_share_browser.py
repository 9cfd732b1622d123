"""`implgen share`'s page in a real browser: headless Chromium (WebGL2 on SwiftShader) opens the file from disk
(file://, no server) and is used as a person would: it draws, a slider moves the picture, a drag turns it, the
wheel zooms, the flagged pixels' marking switches on and off.

The reference is the GLSL test harness (implgen.measure.webgl, as in tests/test_glsl_browser.py): the shape's
generated GLSL and the runtime assembled by glslprogram.program with a main written here from docs/share.md's
description of the picture (camera, clip, two-sided shading, the key light), at the page's camera and params.
The page's canvas must equal it: colours within 2 of 255 on every pixel the reference did not flag, and on
flagged pixels the reference's colour or the magenta checker. 160 x 120 pixels: SwiftShader is a CPU.
With IMPLGEN_SHARE_SCREENSHOT=path set, a screenshot of a shared page is saved there (docs/gallery/share.png).
"""

from __future__ import annotations

import base64
import io
import math
import os
import time

import numpy as np
import pytest
import yaml
from PIL import Image

import needs_program
import page_shader
from conftest import SHAPES_DIR
from implgen.cli import main
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import program, shape_defines
from implgen.codegen.emit import generate
from implgen.spec.entry import load_spec, parse_spec

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")
SIZE = (160, 120)
WAIT = 300  # seconds; generous (a busy machine), nothing here is a timing
LIGHT = [-0.6, 0.8, 1.0]  # docs/share.md: towards the key light in the camera's right, up, back
MATERIAL = "0.12, 0.75, 0.45, 40.0"  # ambient, diffuse, specular, shininess

REFERENCE_MAIN = """
uniform vec2 size;
uniform vec3 eye;
uniform vec3 look;
uniform vec3 up;
uniform float fov;
uniform float clip_r;
uniform vec3 outside;
uniform vec3 inside;
uniform vec3 bg;
uniform vec3 light;
out vec4 ig_test_out;
void main()
{
    vec2 pixel = vec2(gl_FragCoord.x, size.y - gl_FragCoord.y);
    IgCamera cam = ig_camera(eye, look, up, fov, size);
    vec3 d = ig_camera_dir(cam, pixel, size);
    float t0 = 0.0, t1 = ig_inf(), t;
    vec3 n;
    int status = ig_clip_sphere(cam.eye, d, vec3(0.0), clip_r, t0, t1) ? IG_SHAPE_HIT(cam.eye, d, t0, t1, t, n) : 0;
    vec3 to_light = light.x * cam.u + light.y * cam.v + light.z * cam.w;
    vec3 rgb = (status & IG_HIT) != 0 ? ig_shade(IgMaterial(outside, inside, IG_TEST_MATERIAL), n, d, to_light) : bg;
    ig_test_out = vec4(clamp(rgb, 0.0, 1.0), float(status));
}
"""


@pytest.fixture(scope="module")
def gl():
    from implgen.measure.webgl import WebGL

    with WebGL(console_log=True) as browser:
        yield browser


def make_page(tmp_path, spec_path, *args: str):
    out = tmp_path / f"{spec_path.stem}.html"
    assert main(["share", str(spec_path), "-o", str(out), "-q", *args]) == 0
    return out


def wait_idle(d) -> None:
    deadline = time.monotonic() + WAIT
    while not d.execute_script("return !!(window.implgenShare && window.implgenShare.idle && implgenShare.idle());"):
        err = d.execute_script("return window.implgenShare && window.implgenShare.error;")
        assert not err, err
        assert time.monotonic() < deadline, "the page did not finish drawing"
        time.sleep(0.05)


def open_page(gl, path, size=SIZE):
    d = gl.driver
    d.get(path.as_uri())
    deadline = time.monotonic() + WAIT
    while not d.execute_script("return !!window.implgenShare;"):
        assert time.monotonic() < deadline, "the page did not start"
        time.sleep(0.05)
    err = d.execute_script("return window.implgenShare.error || '';")
    assert not err, err
    check_shader(d, path)
    d.execute_script("implgenShare.fixSize(arguments[0], arguments[1]);", *size)
    wait_idle(d)
    return d


def check_shader(d, path) -> None:
    """The fragment shader the page compiled is the one tests/page_shader.py reads from a page (which
    tests/test_share_command.py checks), and glslangValidator passes it, warnings included."""
    fragment = d.execute_script("return implgenShare.renderer.fragment;")
    assert fragment == page_shader.page_fragment(d, path.read_text(encoding="utf-8"))
    if not needs_program.missing(("glslangValidator",)):
        problems = page_shader.glslang_problems(fragment, path.with_suffix(".frag"))
        assert not problems, problems


def canvas(d) -> np.ndarray:
    """The canvas's pixels (h, w, 4) uint8, bottom row first (as gl.readPixels and the harness give them)."""
    b64 = d.execute_script(
        "const p = implgenShare.renderer.readPixels(); let s = '';"
        "for (let i = 0; i < p.length; i += 32768) s += String.fromCharCode.apply(null, p.subarray(i, i + 32768));"
        "return btoa(s);"
    )
    w, h = d.execute_script("return [implgenShare.renderer.width, implgenShare.renderer.height];")
    return np.frombuffer(base64.b64decode(b64), np.uint8).reshape(h, w, 4)


def shown(d) -> np.ndarray:
    """What the canvas shows, through canvas.toDataURL (a PNG), top row first."""
    url = d.execute_script("return document.getElementById('ig-canvas').toDataURL('image/png');")
    return np.asarray(Image.open(io.BytesIO(base64.b64decode(url.split(",", 1)[1]))).convert("RGBA"))


def page_state(d) -> dict:
    return d.execute_script(
        "const r = implgenShare.renderer;"
        "return {camera: r.camera, params: r.params, clip: r.clip, colours: r.colours, mark: r.markUnsure,"
        " orbit: {yaw: implgenShare.orbit.yaw, pitch: implgenShare.orbit.pitch,"
        " distance: implgenShare.orbit.distance, target: implgenShare.orbit.target, fov: implgenShare.orbit.fov}};"
    )


def orbit_camera(o: dict) -> dict:
    """The viewer's orbit (docs/viewer.md), computed here: yaw about +y, pitch above the x-z plane."""
    y, p = math.radians(o["yaw"]), math.radians(o["pitch"])
    back = np.array([math.cos(p) * math.sin(y), math.sin(p), math.cos(p) * math.cos(y)])
    right = np.array([math.cos(y), 0.0, -math.sin(y)])
    return {"eye": np.add(o["target"], o["distance"] * back), "up": np.cross(back, right)}


def reference(gl, spec, state: dict, size=SIZE) -> np.ndarray:
    """The harness's picture at the page's camera, params, clip sphere and colours: (h, w, 4) float32, bottom row
    first; channel 3 is the status (1 hit, 2 flagged)."""
    cam = state["camera"]
    want = orbit_camera(state["orbit"])
    assert np.allclose(cam["eye"], want["eye"], rtol=0, atol=1e-9) and np.allclose(cam["up"], want["up"], atol=1e-12)
    assert state["clip"]["kind"] == "sphere"
    uniforms = {
        "size": [float(size[0]), float(size[1])],
        "eye": cam["eye"],
        "look": cam["target"],
        "up": cam["up"],
        "fov": [cam["fov"]],
        "clip_r": [state["clip"]["size"]],
        "outside": state["colours"]["outside"],
        "inside": state["colours"]["inside"],
        "bg": state["colours"]["background"],
        "light": LIGHT,
    }
    prefix = glsl_name(spec.name)
    if spec.params:
        uniforms[f"{prefix}_params"] = state["params"]
    defines = {**shape_defines(prefix), "IG_TEST_MATERIAL": MATERIAL}
    frag = program([generate(spec, ("glsl",))[f"{spec.name}.glsl"]], REFERENCE_MAIN, defines=defines)
    gl.harness()
    out, _ = gl.run(frag, size, uniforms)
    return out


def compare(page: np.ndarray, ref: np.ndarray, background, marked: bool = True) -> dict:
    """The page equals the reference: colours within 2 of 255 where the reference did not flag; where it did, the
    reference's colour or (marked) the magenta checker on odd pixels."""
    h, w = ref.shape[:2]
    status = ref[..., 3].astype(int)
    flagged = (status & 2) != 0
    hit = (status & 1) != 0
    want = np.round(np.clip(ref[..., :3], 0, 1) * 255)
    diff = np.abs(page[..., :3].astype(int) - want).max(-1)
    assert (diff[~flagged] <= 2).all(), f"{(diff[~flagged] > 2).sum()} pixels differ, by up to {diff.max()}"
    rows, cols = np.indices((h, w))
    odd = (cols + (h - 1 - rows)) % 2 == 1  # the runtime's checker, in image coordinates (y down)
    magenta = (page[..., :3] == (255, 0, 255)).all(-1)
    if marked:
        assert (magenta[flagged & odd]).all() and (diff[flagged & ~odd] <= 2).all()
    else:
        assert (diff[flagged] <= 2).all()
    bg = np.round(np.asarray(background) * 255)
    page_hit = (np.abs(page[..., :3].astype(int) - bg) > 2).any(-1)
    assert (page_hit == hit)[~flagged].all()
    return {"hit": hit, "flagged": flagged, "page_hit": page_hit}


def test_the_page_draws_what_the_glsl_test_render_draws(gl, tmp_path):
    spec = load_spec(SHAPES_DIR / "torus_y.yaml")
    d = open_page(gl, make_page(tmp_path, SHAPES_DIR / "torus_y.yaml"))
    page = canvas(d)
    assert (shown(d)[::-1] == page).all()  # what readPixels gives is what the canvas shows
    state = page_state(d)
    assert state["params"] == [1.0, 0.25] and state["mark"] is True
    assert d.execute_script("return IgSurface.LIGHT;") == LIGHT
    r = compare(page, reference(gl, spec, state), state["colours"]["background"])
    hit = r["page_hit"]
    assert 0.1 < hit.mean() < 0.7  # the torus fills the middle of the picture
    rows, cols = np.nonzero(hit)
    assert abs(cols.mean() - SIZE[0] / 2) < 0.1 * SIZE[0] and abs(rows.mean() - SIZE[1] / 2) < 0.15 * SIZE[1]
    assert not hit[:, :5].any() and not hit[:, -5:].any()  # the box is framed whole
    severe = [e for e in d.get_log("browser") if e["level"] == "SEVERE"]
    assert not severe, severe

    shot = os.environ.get("IMPLGEN_SHARE_SCREENSHOT")
    if shot:  # the Chmutov octic at the window's size, for docs/share.md and the README (make screenshot)
        d.set_window_size(1000, 640)
        d.get(make_page(tmp_path, SHAPES_DIR / "chmutov8.yaml").as_uri())
        wait_idle(d)
        assert d.save_screenshot(shot)


def test_a_slider_moves_the_picture(gl, tmp_path):
    """b (the tube's radius) from 0.25 to 0.45 through the slider's own input and change events: the tube gets
    thicker, the value is shown, and the picture is the reference's at b = 0.45."""
    spec = load_spec(SHAPES_DIR / "torus_y.yaml")
    d = open_page(gl, make_page(tmp_path, SHAPES_DIR / "torus_y.yaml"))
    before = canvas(d)
    d.execute_script(
        "const s = document.querySelector('input[data-param=\"1\"]'); s.value = '0.45';"
        "s.dispatchEvent(new Event('input')); s.dispatchEvent(new Event('change'));"
    )
    wait_idle(d)
    assert d.execute_script("return document.getElementById('ig-value-1').textContent;") == "0.45"
    state = page_state(d)
    assert state["params"] == [1.0, 0.45]
    after = canvas(d)
    r = compare(after, reference(gl, spec, state), state["colours"]["background"])
    bg = np.round(np.asarray(state["colours"]["background"]) * 255)
    hit_before = (np.abs(before[..., :3].astype(int) - bg) > 2).any(-1)
    assert r["page_hit"].sum() > 1.3 * hit_before.sum()


def test_names_of_javascript_s_and_glsl_s_own_draw(gl, tmp_path):
    """A shape called ball_ (its GLSL functions would be ball__hit, reserved) with params named as
    Object.prototype's members and one with __: the page compiles (open_page checks its shader), draws the
    reference's picture, and the slider of `constructor` moves it."""
    params = {"constructor": 1.0, "toString": 0.81, "valueOf": 0.5, "hasOwnProperty": 0.2, "a__b": 0.1}
    spec_path = tmp_path / "ball_.yaml"
    equation = "x^2 + y^2 + z^2 - constructor*toString + valueOf*hasOwnProperty - a__b"
    box = {axis: [-1.5, 1.5] for axis in "xyz"}
    spec_path.write_text(
        yaml.safe_dump({"name": "ball_", "equation": equation, "params": params, "bounds": box}, sort_keys=False)
    )
    spec = load_spec(spec_path)
    d = open_page(gl, make_page(tmp_path, spec_path))
    labels = d.execute_script("return [...document.querySelectorAll('input[data-param]')].map((s) => s.ariaLabel);")
    assert labels == list(params)
    state = page_state(d)
    assert state["params"] == list(params.values())
    r = compare(canvas(d), reference(gl, spec, state), state["colours"]["background"])
    before = r["page_hit"].sum()
    assert before > 0.05 * r["page_hit"].size
    d = open_page(gl, spec_path.with_suffix(".html"))
    d.execute_script(
        "const s = document.querySelector('input[data-param=\"0\"]'); s.value = '1.5';"
        "s.dispatchEvent(new Event('input')); s.dispatchEvent(new Event('change'));"
    )
    wait_idle(d)
    state = page_state(d)
    assert state["params"][0] == 1.5
    r = compare(canvas(d), reference(gl, spec, state), state["colours"]["background"])
    assert r["page_hit"].sum() > 1.2 * before


def test_drag_turns_the_wheel_zooms_and_the_keys_turn(gl, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    spec = load_spec(SHAPES_DIR / "torus_y.yaml")
    d = open_page(gl, make_page(tmp_path, SHAPES_DIR / "torus_y.yaml"))
    before = canvas(d)
    yaw0, pitch0, dist0 = (page_state(d)["orbit"][k] for k in ("yaw", "pitch", "distance"))
    el = d.find_element(By.ID, "ig-canvas")
    ActionChains(d).move_to_element(el).click_and_hold().move_by_offset(25, 0).move_by_offset(
        25, 10
    ).release().perform()
    wait_idle(d)
    o = page_state(d)["orbit"]
    assert o["yaw"] == pytest.approx(yaw0 - 50 * 0.4) and o["pitch"] == pytest.approx(pitch0 + 10 * 0.4)
    turned = canvas(d)
    assert (np.abs(turned.astype(int) - before).max(-1) > 2).mean() > 0.05
    ActionChains(d).scroll_from_origin(ScrollOrigin.from_element(el), 0, 100).perform()
    time.sleep(0.3)  # the wheel's rest timer (180 ms) settles the frame
    wait_idle(d)
    state = page_state(d)
    assert state["orbit"]["distance"] == pytest.approx(dist0 * math.exp(100 * 0.002))
    el.send_keys(Keys.ARROW_LEFT, Keys.ARROW_UP)  # the keyboard: each arrow as a 12.5-pixel drag that way
    time.sleep(0.3)
    wait_idle(d)
    state = page_state(d)
    assert state["orbit"]["yaw"] == pytest.approx(yaw0 - 50 * 0.4 + 5)
    assert state["orbit"]["pitch"] == pytest.approx(pitch0 + 10 * 0.4 - 5)
    compare(canvas(d), reference(gl, spec, state), state["colours"]["background"])


def test_flagged_pixels_are_marked_and_the_mark_switches_off(gl, tmp_path):
    """z^2 = 0 touches the plane z = 0 with a double root: float cannot certify any crossing, so every ray that
    meets it is flagged, and the page draws the magenta checker there until the box is unticked."""
    spec_path = tmp_path / "double_plane.yaml"
    spec_path.write_text(
        "name: double_plane\nequation: z^2\nbounds: {x: [-1, 1], y: [-1, 1], z: [-1, 1]}\n", encoding="utf-8"
    )
    spec = load_spec(spec_path)
    d = open_page(gl, make_page(tmp_path, spec_path))
    state = page_state(d)
    marked = canvas(d)
    d.execute_script("document.getElementById('ig-unsure').click();")
    wait_idle(d)
    assert page_state(d)["mark"] is False
    unmarked = canvas(d)
    ref = reference(gl, spec, state)
    flagged = (ref[..., 3].astype(int) & 2) != 0
    assert flagged.mean() > 0.05
    compare(marked, ref, state["colours"]["background"], marked=True)
    compare(unmarked, ref, state["colours"]["background"], marked=False)
    assert (marked[..., :3] == (255, 0, 255)).all(-1).sum() > 0.3 * flagged.sum()
    assert not (unmarked[..., :3] == (255, 0, 255)).all(-1).any()


def test_the_page_works_offline_and_fetches_nothing(gl, tmp_path):
    d = gl.driver
    d.execute_cdp_cmd("Network.enable", {})
    d.execute_cdp_cmd(
        "Network.emulateNetworkConditions",
        {"offline": True, "latency": 0, "downloadThroughput": 0, "uploadThroughput": 0},
    )
    try:
        d = open_page(gl, make_page(tmp_path, SHAPES_DIR / "heart.yaml"))
        page = canvas(d)
        bg = np.round(np.asarray(page_state(d)["colours"]["background"]) * 255)
        assert (np.abs(page[..., :3].astype(int) - bg) > 2).any(-1).mean() > 0.05
        assert d.execute_script("return performance.getEntriesByType('resource').length;") == 0
        assert d.execute_script("return document.querySelectorAll('[src], [href], link, iframe, img').length;") == 0
        severe = [e for e in d.get_log("browser") if e["level"] == "SEVERE"]
        assert not severe, severe
    finally:
        d.execute_cdp_cmd(
            "Network.emulateNetworkConditions",
            {"offline": False, "latency": 0, "downloadThroughput": -1, "uploadThroughput": -1},
        )


def test_hostile_text_runs_nothing_and_reads_back_as_text(gl, tmp_path):
    hostile = '</script><script>window.pwned=1</script><img src=x onerror="window.pwned=2"> & \'q\' "q"'
    spec = parse_spec({"name": "ball", "equation": "x^2 + y^2 + z^2 - 1", "description": hostile})
    assert spec.description == hostile
    spec_path = tmp_path / "<b>ball'&\".yaml"
    spec_path.write_text(
        f"name: ball\ndescription: '{hostile.replace(chr(39), chr(39) * 2)}'\nequation: x^2 + y^2 + z^2 - 1\n"
        "bounds: {x: [-1, 1], y: [-1, 1], z: [-1, 1]}\n",
        encoding="utf-8",
    )
    d = open_page(gl, make_page(tmp_path, spec_path))
    assert d.execute_script("return window.pwned === undefined;")
    assert d.execute_script("return document.scripts.length;") == 4
    assert d.execute_script("return document.querySelectorAll('img, b').length;") == 0
    assert d.execute_script("return document.querySelector('.description').textContent;") == hostile
    assert "<b>ball'&\".yaml" in d.execute_script("return document.querySelector('.made').textContent;")


def _shade(front, back, n, d, to_light):
    """ig_shade (runtime_glsl/shade.glsl) in NumPy, per pixel: two-sided Lambert and Blinn-Phong."""
    ambient, diffuse, specular, shininess = (float(v) for v in MATERIAL.split(","))
    u = d / np.linalg.norm(d, axis=-1, keepdims=True)
    is_back = ~((n * u).sum(-1) < 0)
    nf = np.where(is_back[..., None], -n, n)
    base = np.where(is_back[..., None], back, front)
    lv = to_light / np.linalg.norm(to_light, axis=-1, keepdims=True)
    ndl = (nf * lv).sum(-1)
    hv = lv - u
    hv /= np.linalg.norm(hv, axis=-1, keepdims=True)
    ndh = np.maximum((nf * hv).sum(-1), 0)
    lit = diffuse * ndl[..., None] * base + specular * (ndh**shininess)[..., None]
    return ambient * base + np.where((ndl > 0)[..., None], lit, 0)


def test_a_clip_box_cuts_the_solid_and_shows_its_inside(gl, tmp_path):
    """The infinite cylinder x^2 + z^2 < 1 in the clip box [-0.8, 0.8]^3: where a ray enters the box inside the
    solid, the page shows the cut face, flat on the box, in the inside colour; where it misses the box, the
    background. Checked against the camera, the box and the shading computed here in double precision, away
    from the cut faces' edges. Unticking "cut solid" shows the surface cut open instead (the viewer's default):
    no cut face is painted."""
    spec_path = SHAPES_DIR / "cylinder.yaml"
    d = open_page(gl, make_page(tmp_path, spec_path, "--clip", "box", "--clip-size", "0.8", "--cut"))
    state = page_state(d)
    page = canvas(d)[::-1, :, :3].astype(int)  # top row first
    assert state["clip"] == {"kind": "box", "size": 0.8, "cut": True}
    cam = state["camera"]
    eye, look, up = (np.asarray(cam[k], float) for k in ("eye", "target", "up"))
    w_ = (eye - look) / np.linalg.norm(eye - look)
    u_ = np.cross(up, w_)
    u_ /= np.linalg.norm(u_)
    v_ = np.cross(w_, u_)
    tan_half = math.tan(math.radians(cam["fov"]) / 2)
    cols, rows = np.meshgrid(np.arange(SIZE[0]) + 0.5, np.arange(SIZE[1]) + 0.5)
    px = (2 * cols / SIZE[0] - 1) * tan_half * SIZE[0] / SIZE[1]
    py = (1 - 2 * rows / SIZE[1]) * tan_half
    d_ = px[..., None] * u_ + py[..., None] * v_ - w_
    s = 0.8
    with np.errstate(divide="ignore", invalid="ignore"):
        ta, tb = (-s - eye) / d_, (s - eye) / d_
    t0 = np.minimum(ta, tb).max(-1)
    t1 = np.maximum(ta, tb).min(-1)
    enters = (t0 < t1) & (t0 > 0)
    p = eye + t0[..., None] * d_
    r2 = p[..., 0] ** 2 + p[..., 2] ** 2
    axis = np.abs(p).argmax(-1)
    edge = np.sort(np.abs(p), -1)[..., 1] > s - 0.03  # near an edge of the box: the face is a pixel away
    cut = enters & (r2 < 1 - 0.03) & ~edge
    miss = ~(t0 < t1 + 0.05)
    n = np.zeros_like(p)
    np.put_along_axis(n, axis[..., None], np.sign(np.take_along_axis(p, axis[..., None], -1)), -1)
    to_light = LIGHT[0] * u_ + LIGHT[1] * v_ + LIGHT[2] * w_
    inside = np.asarray(state["colours"]["inside"])
    want = np.round(np.clip(_shade(inside, inside, n, d_, np.broadcast_to(to_light, d_.shape)), 0, 1) * 255)
    bg = np.round(np.asarray(state["colours"]["background"]) * 255)
    assert cut.mean() > 0.1 and miss.mean() > 0.1
    assert (np.abs(page - want).max(-1)[cut] <= 2).all()
    assert (np.abs(page - bg).max(-1)[miss] <= 2).all()
    for face in range(3):  # the picture shows cut faces on three sides of the box, each in its own shade
        assert (cut & (axis == face)).sum() > 50
    d.find_element("id", "ig-cut").click()
    wait_idle(d)
    assert page_state(d)["clip"]["cut"] is False
    opened = canvas(d)[::-1, :, :3].astype(int)
    assert (np.abs(opened - want).max(-1)[cut] <= 2).mean() < 0.05  # no cut face
    assert (np.abs(opened - bg).max(-1)[miss] <= 2).all()


def test_a_frame_drawn_in_bands_is_the_frame_drawn_at_once(gl, tmp_path):
    """The progressive redraw: with a tiny time budget the page draws a coarse frame, then the full frame a few
    rows at a time over many animation frames; the result is the frame drawn in one go, pixel for pixel. While
    something moves, only the coarse frame is drawn (blocks of equal pixels)."""
    d = open_page(gl, make_page(tmp_path, SHAPES_DIR / "torus_z.yaml"))
    at_once = canvas(d)
    d.execute_script(
        "const p = implgenShare.progressive; p.budget = 0.01; p.steps = 0; p.msPerPixel = 1; p.invalidate(false);"
    )
    wait_idle(d)
    steps = d.execute_script("return implgenShare.progressive.steps;")
    assert steps > SIZE[1] / 2  # a coarse frame, then a row or so at a time
    assert (canvas(d) == at_once).all()
    d.execute_script("const p = implgenShare.progressive; p.budget = 40; p.framePerPixel = 1; p.invalidate(true);")
    deadline = time.monotonic() + WAIT
    while d.execute_script("return implgenShare.progressive.steps;") == steps:
        assert time.monotonic() < deadline
        time.sleep(0.05)
    time.sleep(0.2)
    assert not d.execute_script("return implgenShare.idle();")  # moving: waits for the view to rest
    coarse = canvas(d)[::-1]  # top row first
    assert (coarse != at_once[::-1]).any()
    cw, ch = math.ceil(SIZE[0] / 16), math.ceil(SIZE[1] / 16)  # framePerPixel = 1: the coarsest frame, 1/16
    assert SIZE[0] % cw == 0 and SIZE[1] % ch == 0
    blocks = coarse.reshape(ch, SIZE[1] // ch, cw, SIZE[0] // cw, 4)
    assert (blocks == blocks[:, :1, :, :1]).all()  # each coarse pixel stretched over a block
    d.execute_script("implgenShare.progressive.settle();")
    wait_idle(d)
    assert (canvas(d) == at_once).all()
