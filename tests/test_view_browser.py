"""`implgen view` in a real browser: headless Debian Chromium driven by Selenium against the real server (uvicorn
on 127.0.0.1, a free port). Needs Debian's chromium and chromium-driver: `make test` installs them when it runs
as root; otherwise these tests are skipped, or fail with IMPLGEN_REQUIRE_ALL set (tests/needs_program.py).

The page is used as a person would: type an equation, wait for the picture, drag a slider, type a bad
equation, orbit with the mouse. The picture on the canvas is compared with render() of the same view.
With IMPLGEN_SCREENSHOT=path set, a screenshot of the page is saved there (the README's picture).
"""

from __future__ import annotations

import base64
import io
import os
import shutil
import threading
import time

import numpy as np
import pytest
from PIL import Image

from implgen.imagefile import to_uint8
from implgen.scene.render import render
from implgen.spec.entry import parse_spec
from implgen.view import protocol
from implgen.view.command import bind, document_factory, serve

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")
EQUATION = "x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + c"  # a tanglecube; c = 11.8 is the classic one
PARAMS = "c = 11.8"
BARTH6 = "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - w^2)^2*w^2"
WAIT = 120  # seconds: generous, the machine may be busy; nothing here is a timing


@pytest.fixture(scope="module")
def server():
    make = document_factory(None)
    sock = bind("127.0.0.1", 0)
    holder: dict = {}
    thread = threading.Thread(target=serve, args=(sock, make, 2, lambda s: holder.setdefault("server", s)), daemon=True)
    thread.start()
    deadline = time.monotonic() + 30
    while not getattr(holder.get("server"), "started", False):
        assert time.monotonic() < deadline and thread.is_alive(), "the server did not start"
        time.sleep(0.05)
    yield f"http://127.0.0.1:{sock.getsockname()[1]}/"
    holder["server"].should_exit = True
    thread.join(30)


@pytest.fixture(scope="module")
def driver():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1100,640"):
        opts.add_argument(arg)
    opts.add_argument("--force-device-scale-factor=1")
    d = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    yield d
    d.quit()


def wait(driver, what, message: str):
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, WAIT, poll_frequency=0.05).until(lambda d: what(d), message)


def frame_state(driver) -> tuple[int, str]:
    script = "const c = document.getElementById('view'); return [c.dataset.seq, c.dataset.kind];"
    seq, kind = driver.execute_script(script)
    return (int(seq) if seq is not None else -1, kind or "")


def wait_full_after(driver, seq: int) -> int:
    """Wait for a refined frame newer than `seq`, then until no newer request is on its way."""

    def done(d):
        s, kind = frame_state(d)
        return s if s > seq and kind == "full" else False

    return wait(driver, done, f"no refined frame after {seq}")


def canvas_pixels(driver) -> np.ndarray:
    url = driver.execute_script("return document.getElementById('view').toDataURL('image/png');")
    data = base64.b64decode(url.split(",", 1)[1])
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB")).astype(int)


def page_colour(driver, element_id: str) -> list[float]:
    hexa = driver.find_element("id", element_id).get_attribute("value")
    return [int(hexa[i : i + 2], 16) / 255 for i in (1, 3, 5)]


def reference(driver, values: dict) -> np.ndarray:
    """render() of the view the page shows: the page's camera, clip and colours, the typed shape."""
    doc = document_factory(None)()
    spec = protocol.parse_shape({"equation": EQUATION, "params": {"c": 11.8}}, doc.spec)
    doc.set_spec(spec)
    doc.values = dict(values)
    doc.options.color = tuple(page_colour(driver, "color"))
    doc.options.inside = tuple(page_colour(driver, "inside"))
    doc.options.background = tuple(page_colour(driver, "background"))
    doc.options.clip_size = float(driver.find_element("id", "clip-size").get_attribute("value"))
    orbit = driver.execute_script("return window.implgenState().orbit")
    doc.orbit = protocol.parse_orbit(orbit)
    w, h = driver.execute_script("const c = document.getElementById('view'); return [c.width, c.height];")
    return to_uint8(render(doc.scene(w, h, 4), threads=2)).astype(int)


def test_the_page_in_a_real_browser(server, driver) -> None:
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    driver.get(server)
    first = wait_full_after(driver, -1)  # the starter torus, refined
    assert canvas_pixels(driver).std() > 10

    # type an equation with a param; Enter applies it
    params = driver.find_element("id", "params-text")
    params.clear()
    params.send_keys(PARAMS)
    eq = driver.find_element("id", "equation")
    eq.clear()
    eq.send_keys(EQUATION)
    eq.send_keys(Keys.ENTER)
    wait(driver, lambda d: d.find_element("id", "degree").text == "degree 4", "the shape was not accepted")
    typed = wait_full_after(driver, first)
    time.sleep(0.5)
    typed = max(typed, frame_state(driver)[0])
    shown = canvas_pixels(driver)
    ref = reference(driver, {"c": 11.8})
    diff = np.abs(shown - ref)
    assert diff.mean() < 1.0 and np.mean(diff > 8) < 0.002, (diff.mean(), np.mean(diff > 8))
    assert driver.find_element("id", "equation-error").text == ""

    # drag the slider of c: the picture changes, and matches render() with the new value
    slider = driver.find_element("css selector", "input[type=range][data-name=c]")
    ActionChains(driver).click_and_hold(slider).move_by_offset(-60, 0).release().perform()
    moved = wait_full_after(driver, typed)
    time.sleep(0.5)
    moved = max(moved, frame_state(driver)[0])
    after = canvas_pixels(driver)
    assert np.abs(after - shown).mean() > 2
    c_now = float(slider.get_attribute("value"))
    assert c_now < 11.8
    assert np.abs(after - reference(driver, {"c": c_now})).mean() < 1.0

    # a bad equation: one line beside the field, the last good picture stays
    eq.clear()
    eq.send_keys("x^2 + * y")
    eq.send_keys(Keys.ENTER)
    wait(driver, lambda d: d.find_element("id", "equation-error").text, "no message for a bad equation")
    message, excerpt, caret = driver.find_element("id", "equation-error").text.split("\n")
    assert "syntax error at column 7: '*' has nothing before it" in message  # one line, then where: a caret
    assert excerpt == "x^2 + * y" and caret == "      ^"
    time.sleep(0.3)
    assert frame_state(driver)[0] == moved and np.array_equal(canvas_pixels(driver), after)
    params.clear()
    params.send_keys(PARAMS)  # back to c = 11.8 when the equation is next applied

    # orbit with the mouse: the server is still up and the view turns
    canvas = driver.find_element("id", "view")
    ActionChains(driver).move_to_element(canvas).click_and_hold().move_by_offset(40, 10).move_by_offset(
        40, 10
    ).release().perform()
    turned = wait_full_after(driver, moved)
    assert turned > moved and np.abs(canvas_pixels(driver) - after).mean() > 2

    shot = os.environ.get("IMPLGEN_SCREENSHOT")
    if shot:  # Barth's sextic in its clip ball, cut open as SURFER shows it, for the README
        driver.set_window_size(1280, 720)
        params.clear()
        params.send_keys("phi = 1.618033988749895, w = 1")
        eq.clear()
        eq.send_keys(BARTH6)
        eq.send_keys(Keys.ENTER)
        wait(driver, lambda d: d.find_element("id", "degree").text == "degree 6", "Barth's sextic was not accepted")
        wait_full_after(driver, turned)
        time.sleep(1.5)  # the window's new size, refined
        wait(driver, lambda d: frame_state(d)[1] == "full", "the picture did not rest")
        driver.save_screenshot(shot)
    assert parse_spec({"name": "t", "equation": EQUATION, "params": {"c": 11.8}}).degree == 4


# Every kind the canvas is marked with, in order: a MutationObserver keeps each old value of data-seq and data-kind
RECORD_KINDS = """
const c = document.getElementById('view');
window.seenKinds = [];
new MutationObserver((records) => {
  for (const r of records) window.seenKinds.push([r.attributeName, r.oldValue]);
}).observe(c, {attributes: true, attributeOldValue: true, attributeFilter: ['data-seq', 'data-kind']});
"""


def drawn_kinds(driver) -> list[tuple[int, str]]:
    """(seq, kind) of each frame the page drew since RECORD_KINDS ran (drawFrame sets data-seq, then data-kind)."""
    seen = driver.execute_script("return window.seenKinds")
    now = driver.execute_script("const c = document.getElementById('view'); return [c.dataset.seq, c.dataset.kind];")
    seqs = [old for name, old in seen if name == "data-seq"][1:] + [now[0]]
    kinds = [old for name, old in seen if name == "data-kind"][1:] + [now[1]]
    return list(zip(map(int, seqs), kinds))


def test_after_a_drag_the_page_draws_the_refinement_ladder_in_order(server, driver, monkeypatch) -> None:
    """The drag's frames kept under a quarter of the picture and the ladder forced into passes of one sample:
    after the release the page draws the half-size picture, the full size at 1 sample, at 2 and 3, then at 4,
    each better than the one before it, and its status line says which; the last is render()'s picture."""
    from selenium.webdriver.common.action_chains import ActionChains

    from implgen.view import ladder, pace

    monkeypatch.setattr(ladder, "REFINE_TARGET", 0.0)
    monkeypatch.setattr(ladder, "PASS_TARGET", 0.0)
    monkeypatch.setattr(pace, "MAX_DIVISOR", 3)  # coarse frames of at most a ninth of the picture
    driver.get(server)
    first = wait_full_after(driver, -1)
    driver.execute_script(RECORD_KINDS)
    canvas = driver.find_element("id", "view")
    ActionChains(driver).move_to_element(canvas).click_and_hold().move_by_offset(30, 5).move_by_offset(
        30, 5
    ).release().perform()
    last = wait_full_after(driver, first)
    drawn = drawn_kinds(driver)
    after_drag = drawn[max(i for i, (_, kind) in enumerate(drawn) if kind == "coarse") + 1 :]
    assert [kind for _, kind in after_drag][:5] == ["quarter", "one", "more", "more", "full"], drawn
    # (the pointer's rest before the release may have started the ladder: the release's request, for the same
    # view, renumbers the rest of it)
    seqs = [seq for seq, _ in after_drag]
    assert seqs == sorted(seqs) and after_drag[-1] == (last, "full"), drawn
    w, h = driver.execute_script("const c = document.getElementById('view'); return [c.width, c.height];")
    assert driver.find_element("id", "status").text.startswith(f"full {w} x {h} ")
    doc = document_factory(None)()
    doc.orbit = protocol.parse_orbit(driver.execute_script("return window.implgenState().orbit"))
    doc.options.clip_size = float(driver.find_element("id", "clip-size").get_attribute("value"))
    ref = to_uint8(render(doc.scene(w, h, 4), threads=2)).astype(int)
    assert np.abs(canvas_pixels(driver) - ref).mean() < 1.0


def test_beyond_loopback_the_page_works_through_its_token(driver) -> None:
    """A server listening on every address (as `--host 0.0.0.0`) asks for its token: the page opened with the
    link's token draws its picture (the page hands the token to its socket); without it, the page is refused.
    The browser reaches it on 127.0.0.1 only."""
    sock = bind("0.0.0.0", 0)
    holder: dict = {}
    token = "t0ken-for-the-test_0123456789"
    thread = threading.Thread(
        target=serve,
        args=(sock, document_factory(None), 2, lambda s: holder.setdefault("server", s)),
        kwargs={"token": token},
        daemon=True,
    )
    thread.start()
    deadline = time.monotonic() + 30
    while not getattr(holder.get("server"), "started", False):
        assert time.monotonic() < deadline and thread.is_alive(), "the server did not start"
        time.sleep(0.05)
    url = f"http://127.0.0.1:{sock.getsockname()[1]}/"
    try:
        driver.get(url)
        assert "token" in driver.find_element("tag name", "body").text
        driver.get(f"{url}?token={token}")
        wait_full_after(driver, -1)
        assert canvas_pixels(driver).std() > 10
    finally:
        holder["server"].should_exit = True
        thread.join(30)
