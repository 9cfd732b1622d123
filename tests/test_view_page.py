"""`implgen view` in real headless Chromium, what a SURFER user checks first: each defect once found, as a
person meets it. A drag keeps getting frames; the first run says the runtime is being compiled; errors clear,
wrap and say what they mean; the picture fills the window, sharp on high-DPI screens, and 800×600 needs no
sideways scroll. Frame rates are measured by bench/view_latency.py, not here: these tests only ask that frames
come at all. Needs Debian's chromium and chromium-driver (tests/needs_program.py).
"""

from __future__ import annotations

import math
import os
import shutil
import time

import numpy as np
import pytest
import yaml

from test_view_browser import canvas_pixels, frame_state, page_colour, wait, wait_full_after
from view_fixtures import BALLS_SCENE, view_process

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")
CHMUTOV12 = (
    "3 + 2048*(x^12 + y^12 + z^12) - 6144*(x^10 + y^10 + z^10) + 6912*(x^8 + y^8 + z^8) - 3584*(x^6 + y^6 + z^6)"
    " + 840*(x^4 + y^4 + z^4) - 72*(x^2 + y^2 + z^2)"
)


def chromium(width: int, height: int, scale: float = 1.0):
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"):
        opts.add_argument(arg)
    opts.add_argument(f"--window-size={width},{height}")
    opts.add_argument(f"--force-device-scale-factor={scale}")
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    return webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)


@pytest.fixture(scope="module")
def fresh_server(tmp_path_factory):
    """`implgen view` in its own process with an empty build cache (its first run) and room for one page."""
    cache = tmp_path_factory.mktemp("cache")
    env = dict(os.environ, IMPLGEN_CACHE=str(cache), IMPLGEN_VIEW_MAX_PAGES=str(PAGES))
    with view_process(env=env) as url:
        yield url


@pytest.fixture(scope="module")
def driver():
    d = chromium(1100, 700)
    yield d
    d.quit()


PAGES = 2


def open_page(driver, url: str) -> int:
    """Load the page and wait for its first refined picture; a page closed just before may still hold its place
    on the server until its work has stopped: then load it again."""
    for _ in range(20):
        driver.get(url)
        wait(driver, lambda d: frame_state(d)[0] >= 0 or text(d, "message").startswith("too many"), "no picture")
        if frame_state(driver)[0] >= 0:
            return wait_full_after(driver, -1)
        time.sleep(0.5)
    raise AssertionError("the page found no room")


def text(driver, element_id: str) -> str:
    return driver.execute_script(f"return document.getElementById('{element_id}').textContent")


def apply(driver, equation: str, params: str = "") -> None:
    from selenium.webdriver.common.keys import Keys

    p = driver.find_element("id", "params-text")
    p.clear()
    if params:
        p.send_keys(params)
    eq = driver.find_element("id", "equation")
    eq.clear()
    eq.send_keys(equation)
    eq.send_keys(Keys.ENTER)


def test_first_run_pages_and_favicon(fresh_server, driver) -> None:
    """The first run says the runtime is being compiled, with its progress, then draws; the icon is served;
    a page beyond the limit says "too many pages open" (and nothing about reloading)."""
    driver.get(fresh_server)
    seen = set()
    deadline = time.monotonic() + 120
    while frame_state(driver)[0] < 0:
        assert time.monotonic() < deadline, "no picture"
        seen.add(text(driver, "overlay"))
        time.sleep(0.05)
    compiling = [s for s in seen if s.startswith("compiling the runtime (first run only): ")]
    assert compiling and all(" of " in s for s in compiling), seen
    wait(driver, lambda d: text(d, "overlay") == "", "the overlay stayed after the first picture")
    status = driver.execute_script("return fetch('/favicon.ico').then(r => [r.status, r.headers.get('content-type')])")
    assert status == [200, "image/x-icon"]
    assert not [e for e in driver.get_log("browser") if "404" in e["message"]]

    first = driver.current_window_handle
    tabs = []
    try:
        for _ in range(PAGES):  # the second page fits, the third does not
            driver.switch_to.new_window("tab")
            tabs.append(driver.current_window_handle)
            driver.get(fresh_server)
        wait(driver, lambda d: text(d, "message"), "no word on the page beyond the limit")
        message = text(driver, "message")
        assert message.startswith("too many pages open") and "reload to reconnect" not in message, message
        assert text(driver, "overlay") == "too many pages open"
    finally:
        for tab in tabs:
            driver.switch_to.window(tab)
            driver.close()
        driver.switch_to.window(first)


def test_messages_clear_wrap_and_say_what_happened(fresh_server, driver) -> None:
    """Errors clear with the next picture; a field with no number is not answered with the last bad value;
    a 5,000-character error stays in the controls; an equation with no real points says so; the sliders of
    params the equation no longer uses go; a slider let go where it started gives a refined picture."""
    from selenium.webdriver.common.action_chains import ActionChains

    open_page(driver, fresh_server)
    size = driver.find_element("id", "clip-size")
    size.clear()
    size.send_keys("5000000\n")  # the server refuses it (at most 1e6)
    wait(driver, lambda d: "clip_size" in text(d, "message"), "no message for a clip size too large")
    size.clear()
    size.send_keys("abc\n")  # no number: the page says so itself, and sends the last good size
    wait(driver, lambda d: text(d, "message") == "clip size: expected a positive number", "no word on 'abc'")
    wait(driver, lambda d: frame_state(d)[1] == "full", "no picture")  # the last good size: nothing to refuse
    assert text(driver, "message") == "clip size: expected a positive number"
    size.clear()
    size.send_keys("2\n")
    wait(driver, lambda d: text(d, "message") == "", "the error stayed after the next picture")

    apply(driver, "x^2 + " + "y" * 5000)
    wait(driver, lambda d: len(text(d, "equation-error")) > 5000, "no message for the long equation")
    box = driver.execute_script(
        "const e = document.getElementById('equation-error'), c = document.getElementById('controls');"
        "const a = e.getBoundingClientRect(), b = c.getBoundingClientRect();"
        "return [e.scrollWidth <= e.clientWidth, a.right <= b.right + 1, a.height < 200,"
        " document.documentElement.scrollWidth <= document.documentElement.clientWidth]"
    )
    assert box == [True, True, True, True]

    seq = frame_state(driver)[0]
    apply(driver, "x^2 + y^2 + z^2 + 1")
    wait(driver, lambda d: text(d, "overlay") == "no real points in view", "no word on an empty picture")
    assert text(driver, "equation-error") == ""  # cleared by the accepted equation
    seq = wait_full_after(driver, seq)
    apply(driver, "x^2 + y^2 + z^2 - a", "a = 1")
    wait(driver, lambda d: text(d, "degree") == "degree 2" and text(d, "overlay") == "", "the sphere was not drawn")
    seq = wait_full_after(driver, seq)

    slider = driver.find_element("css selector", "input[type=range][data-name=a]")
    seq = frame_state(driver)[0]
    ActionChains(driver).click_and_hold(slider).move_by_offset(-40, 0).move_by_offset(40, 0).release().perform()
    wait_full_after(driver, seq)  # let go where it started: refined all the same (it used to stay coarse)

    apply(driver, "x^2 + y^2 + z^2 - a^2", "a = 1, b = 2")  # b is not in the equation
    wait(driver, lambda d: d.find_element("id", "params-text").get_attribute("value") == "a = 1", "b stayed")
    names = [e.get_attribute("data-name") for e in driver.find_elements("css selector", "input[type=range]")]
    assert names == ["a"]


def test_a_drag_on_a_costly_surface_keeps_getting_frames(fresh_server, driver) -> None:
    """A zoomed-in Chmutov 12: mouse moves every 16 ms for 3 s. Each coarse frame used to be thrown away by the
    next move (0 frames in 3 s); now frames keep coming while the drag lasts. The rate is the benchmark's."""
    first = open_page(driver, fresh_server)
    apply(driver, CHMUTOV12)
    wait(driver, lambda d: text(d, "degree") == "degree 12", "Chmutov 12 was not accepted")
    seq = wait_full_after(driver, first)
    driver.execute_script(  # zoom in: wheel steps towards the surface
        "const c = document.getElementById('view');"
        "for (let i = 0; i < 12; i++) c.dispatchEvent(new WheelEvent('wheel', {deltaY: -100, bubbles: true}));"
    )
    wait_full_after(driver, seq)
    frames = driver.execute_async_script(
        """const done = arguments[arguments.length - 1];
        const c = document.getElementById('view'), r = c.getBoundingClientRect();
        const at = (x) => ({clientX: r.left + x, clientY: r.top + r.height / 2, pointerId: 1, bubbles: true});
        c.dispatchEvent(new PointerEvent('pointerdown', at(100)));
        const start = Number(c.dataset.frames), t0 = performance.now(), times = [];
        let x = 100;
        const seen = new MutationObserver(() => times.push(performance.now() - t0));
        seen.observe(c, {attributes: true, attributeFilter: ['data-frames']});
        const timer = setInterval(() => {
          x += 2;
          c.dispatchEvent(new PointerEvent('pointermove', at(x)));
          if (performance.now() - t0 > 3000) {
            clearInterval(timer);
            seen.disconnect();
            c.dispatchEvent(new PointerEvent('pointerup', at(x)));
            done([Number(c.dataset.frames) - start, times]);
          }
        }, 16);"""
    )
    count, times = frames
    assert count >= 5, (count, times)
    gaps = [b - a for a, b in zip([0.0, *times], [*times, 3000.0])]
    assert max(gaps) < 1500, gaps  # frames all along the drag, not one at its end


def test_the_picture_fills_the_window_and_800x600_needs_no_sideways_scroll(fresh_server) -> None:
    """At 800×600 and 2 device pixels a CSS pixel: no sideways scroll, the canvas fills its box with one pixel
    a device pixel (sharp), the full-screen button is there; a wider window gives a wider picture."""
    d = chromium(800, 600, 2.0)
    try:
        open_page(d, fresh_server)
        got = d.execute_script(
            "const c = document.getElementById('view'), s = document.getElementById('stage');"
            "const root = document.documentElement;"
            "return [root.scrollWidth <= root.clientWidth, c.width, c.height, s.clientWidth, s.clientHeight,"
            " devicePixelRatio, document.getElementById('fullscreen').getBoundingClientRect().width > 0]"
        )
        no_scroll, cw, ch, sw, sh, dpr, button = got
        assert no_scroll and button and dpr == 2
        assert not d.find_element("id", "object-row").is_displayed()  # a spec has no objects to pick
        assert (cw, ch) == (min(2048, 2 * sw), min(2048, 2 * sh)) and sw > 300 and sh > 200
        seq = frame_state(d)[0]
        d.set_window_size(1400, 800)
        wait_full_after(d, seq)
        wide = d.execute_script("return document.getElementById('view').width")
        assert wide > cw
    finally:
        d.quit()


BARTH6 = "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - w^2)^2*w^2"
TANGLECUBE = "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + 11.8"


def background_share_in_ball(driver) -> float:
    """The share of background pixels inside the middle of the clip ball's outline on the canvas (the ball of
    the page's clip size about the origin, seen by the page's camera: its angular radius asin(r / distance))."""
    r = float(driver.find_element("id", "clip-size").get_attribute("value"))
    orbit = driver.execute_script("return window.implgenState().orbit")
    img = canvas_pixels(driver)
    h, w = img.shape[:2]
    half = math.tan(math.asin(min(1.0, r / orbit["distance"]))) / math.tan(math.radians(orbit["fov"] / 2)) * h / 2
    yy, xx = np.mgrid[:h, :w]
    inner = (xx - w / 2) ** 2 + (yy - h / 2) ** 2 < (0.8 * half) ** 2
    bg = np.round(np.array(page_colour(driver, "background")) * 255)
    return float(np.mean(np.abs(img[inner] - bg).max(axis=1) <= 2))


def test_clip_shows_the_surface_cut_open_and_fits_each_new_equation(fresh_server, driver) -> None:
    """A clip shows the surface inside the ball, cut open (Barth's sextic used to be a coloured ball: the cut
    solid's cap); the cut solid is an option. A new equation gets a clip fitted to its points (the torus's size
    used to carry over), and keeps the user's own size once the user has set one."""
    from selenium.webdriver.common.keys import Keys

    seq = open_page(driver, fresh_server)
    apply(driver, TANGLECUBE)
    wait(
        driver,
        lambda d: text(d, "degree") == "degree 4" and d.find_element("id", "clip-size").get_attribute("value") == "4",
        "the clip was not fitted to the tanglecube (its corners are 3.47 from the origin)",
    )
    seq = wait_full_after(driver, seq)

    apply(driver, BARTH6, "phi = 1.618033988749895, w = 1")
    wait(driver, lambda d: text(d, "degree") == "degree 6", "Barth's sextic was not accepted")
    seq = wait_full_after(driver, seq)
    assert driver.find_element("id", "clip-size").get_attribute("value") == "3"  # unbounded: the default ball
    open_share = background_share_in_ball(driver)
    assert open_share > 0.05, open_share  # the background shows through the surface cut open

    driver.find_element("id", "cut").click()  # the cut solid: the ball's cut face covers the middle
    seq = wait_full_after(driver, seq)
    assert background_share_in_ball(driver) < 0.01
    driver.find_element("id", "cut").click()
    seq = wait_full_after(driver, seq)

    size = driver.find_element("id", "clip-size")
    size.send_keys(Keys.CONTROL, "a")
    size.send_keys("2.5\n")  # the user's own size stays with the next equation
    seq = wait_full_after(driver, seq)
    apply(driver, TANGLECUBE)
    wait(driver, lambda d: text(d, "degree") == "degree 4", "the tanglecube was not accepted")
    wait_full_after(driver, seq)
    assert driver.find_element("id", "clip-size").get_attribute("value") == "2.5"


def test_save_yaml_is_a_scene_implgen_render_draws_as_the_page_does(fresh_server, driver, tmp_path) -> None:
    """Save YAML writes the whole view as a scene (it used to be only name, equation and params, which
    `implgen render` refused), rendered as the page's full frame; a typed shape is called `surface` in the YAML
    and in the generated C (it used to be `torus`)."""
    from PIL import Image

    from implgen.cli import main as cli_main

    seq = open_page(driver, fresh_server)
    apply(driver, TANGLECUBE)
    wait(driver, lambda d: text(d, "degree") == "degree 4", "the tanglecube was not accepted")
    seq = wait_full_after(driver, seq)
    time.sleep(0.5)
    wait_full_after(driver, frame_state(driver)[0] - 1)
    driver.execute_script(  # keep what the page hands to the download link
        "window.saved = []; const make = URL.createObjectURL;"
        "URL.createObjectURL = (b) => { window.saved.push(b); return make(b); };"
    )
    driver.find_element("id", "save-yaml").click()
    saved = driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "const look = () => window.saved.length ? window.saved[0].text().then(done) : setTimeout(look, 50);"
        "look();"
    )
    scene = yaml.safe_load(saved)
    assert scene["objects"][0]["name"] == "surface" and scene["objects"][0]["clip"] == {"sphere": 4}
    path = tmp_path / "surface.yaml"
    path.write_text(saved)
    assert cli_main(["render", str(path), "-o", str(tmp_path / "surface.png"), "-q"]) == 0
    rendered = np.asarray(Image.open(tmp_path / "surface.png").convert("RGB")).astype(int)
    shown = canvas_pixels(driver)
    assert rendered.shape == shown.shape and np.abs(rendered - shown).mean() < 1.0

    driver.find_element("id", "show-c").click()
    wait(driver, lambda d: "surface_coeffs(" in text(d, "code"), "the generated C is not named after the shape")
    assert "torus" not in text(driver, "code")
    driver.find_element("id", "close-code").click()


def test_a_share_link_reopens_the_same_view_and_a_bad_one_is_read_safely(fresh_server, driver) -> None:
    """The address carries the view: equation, name, params and slider values, camera, clip, colours. Opened
    in another tab it shows the same picture. A link is untrusted text: fields that do not read are left out
    and said so, nothing else happens."""
    from selenium.webdriver.support.ui import Select

    seq = open_page(driver, fresh_server)
    apply(driver, TANGLECUBE.replace("11.8", "c"), "c = 11.8")
    wait(driver, lambda d: text(d, "degree") == "degree 4", "the tanglecube was not accepted")
    seq = wait_full_after(driver, seq)
    Select(driver.find_element("id", "clip")).select_by_value("box")
    seq = wait_full_after(driver, seq)
    driver.execute_script(
        "const s = document.querySelector('input[type=range][data-name=c]'); s.value = 11.2;"
        "s.dispatchEvent(new Event('input')); s.dispatchEvent(new Event('change'));"
        "const c = document.getElementById('view');"
        "for (let i = 0; i < 3; i++) c.dispatchEvent(new WheelEvent('wheel', {deltaY: 100, bubbles: true}));"
    )
    seq = wait_full_after(driver, seq)
    time.sleep(0.6)  # the wheel's rest
    seq = max(seq, frame_state(driver)[0])
    wait(driver, lambda d: frame_state(d)[1] == "full", "the view did not rest")
    link = driver.current_url
    here = canvas_pixels(driver)
    state = driver.execute_script("return window.implgenState()")
    assert "#v=1&" in link and "clip=box" in link and abs(state["values"]["c"] - 11.2) < 0.03

    first = driver.current_window_handle
    driver.switch_to.new_window("tab")
    try:
        open_page(driver, link)
        wait(driver, lambda d: text(d, "degree") == "degree 4", "the link's equation was not applied")
        wait(
            driver,
            lambda d: (
                frame_state(d)[1] == "full"
                and d.execute_script("return window.implgenState().values.c") == state["values"]["c"]
            ),
            "the link's view was not drawn",
        )
        time.sleep(0.5)
        wait(driver, lambda d: frame_state(d)[1] == "full", "the link's view did not rest")
        there = driver.execute_script("return window.implgenState()")
        flat = lambda o: [o["yaw"], o["pitch"], o["distance"], *o["target"], o["fov"]]  # noqa: E731
        assert flat(there["orbit"]) == pytest.approx(flat(state["orbit"]), rel=1e-11)
        assert there["options"] == state["options"]
        assert driver.find_element("id", "shape-name").get_attribute("value") == "surface"
        assert np.abs(canvas_pixels(driver) - here).mean() < 1.0

        # links pasted into the address of this page (a new part after "#": no reload)
        equation = driver.find_element("id", "equation").get_attribute("value")
        driver.get(fresh_server + "#v=1&eq=" + "x" * 20000)  # too long: nothing of it is used
        wait(driver, lambda d: text(d, "message").startswith("share link:"), "no word on a bad link")
        assert "too long" in text(driver, "message")
        assert driver.find_element("id", "equation").get_attribute("value") == equation
        seq = frame_state(driver)[0]
        driver.get(fresh_server + "#v=1&cam=1,2,nope&color=zzzzzz&lights=<b>x</b>&clip=sphere:2")
        wait(driver, lambda d: "cam, color, lights" in text(d, "message"), "the bad fields were not named")
        wait_full_after(driver, seq)
        assert driver.find_element("id", "clip-size").get_attribute("value") == "2"  # what did read is used
    finally:
        driver.close()
        driver.switch_to.window(first)


@pytest.fixture(scope="module")
def balls_server(tmp_path_factory):
    """`implgen view` of a scene file: a floor and two balls, left and right of the camera's axis."""
    path = tmp_path_factory.mktemp("scene") / "balls.yaml"
    path.write_text(yaml.safe_dump(BALLS_SCENE))
    with view_process(str(path)) as url:
        yield url


def test_a_scene_s_object_is_picked_by_a_click_or_from_the_list(balls_server, driver) -> None:
    """With a scene file the equation box used to edit the first shape (the floor), whatever the user looked
    at: a click on an object picks it, and so does the list."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.support.ui import Select

    open_page(driver, balls_server)
    assert not driver.find_element("id", "object-row").get_attribute("hidden")
    assert driver.execute_script("return document.getElementById('gallery-row').hidden")  # shapes of the file
    chosen = Select(driver.find_element("id", "object"))
    assert [o.text.split(" ")[0] for o in chosen.options] == ["floor", "left", "right"]
    canvas = driver.find_element("id", "view")
    box = driver.execute_script(
        "const r = document.getElementById('view').getBoundingClientRect(); return [r.width, r.height]"
    )
    half = math.tan(math.radians(20)) * box[0] / box[1]  # where the camera shows x = 2 at distance 10
    dx = 2 / 10 / half * box[0] / 2
    ActionChains(driver).move_to_element_with_offset(canvas, round(dx), 0).click().perform()
    wait(driver, lambda d: "(x - 2)^2" in d.find_element("id", "equation").get_attribute("value"), "no pick")
    assert chosen.first_selected_option.text.startswith("right")
    assert driver.find_element("id", "shape-name").get_attribute("value") == "right"
    chosen.select_by_index(1)
    wait(driver, lambda d: "(x + 2)^2" in d.find_element("id", "equation").get_attribute("value"), "no list pick")


def test_the_gallery_picks_a_famous_surface_with_its_source(fresh_server, driver) -> None:
    """The gallery: at least 20 famous surfaces in the page's picker; picking one shows its equation,
    its name, a slider over the spec's own range and its source, and draws it."""
    from selenium.webdriver.support.ui import Select

    from implgen.spec import gallery

    seq = open_page(driver, fresh_server)
    picker = Select(driver.find_element("id", "gallery"))
    titles = [o.text for o in picker.options][1:]  # the first is the prompt
    assert titles == [e.title for e in gallery.entries()] and len(titles) >= 20
    kummer = gallery.entry("kummer")
    picker.select_by_visible_text(kummer.title)
    wait(driver, lambda d: text(d, "degree") == "degree 4", "the Kummer quartic was not accepted")
    seq = wait_full_after(driver, seq)
    assert driver.find_element("id", "shape-name").get_attribute("value") == "kummer"
    assert driver.find_element("id", "equation").get_attribute("value") == " ".join(kummer.data["equation"].split())
    lo, hi = driver.execute_script(
        "const r = document.querySelector('#sliders input[type=range]'); return [Number(r.min), Number(r.max)]"
    )
    assert (lo, hi) == (0.65, 1.7)
    assert "Kummer" in text(driver, "gallery-note") and "1864" in text(driver, "gallery-note")
    assert "no real points" not in text(driver, "message")
    assert driver.execute_script("return document.getElementById('gallery-row').hidden") is False
