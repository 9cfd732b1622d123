"""`implgen view` in headless Chromium: the details a SURFER user notices in the first five minutes, each once
found at 1280×800 or 800×600 and seen to fail on the code before its fix. Where layout is involved, the test
runs at both window sizes. Needs Debian's chromium and chromium-driver (tests/needs_program.py).
"""

from __future__ import annotations

import pytest

from test_view_browser import frame_state, wait, wait_full_after
from test_view_page import chromium, open_page, text
from view_fixtures import view_process

pytestmark = pytest.mark.needs_program("chromium", "chromedriver")
SIZES = [(800, 600), (1280, 800)]


@pytest.fixture(scope="module")
def server():
    """`implgen view` of the starter torus in its own process."""
    with view_process() as url:
        yield url


@pytest.fixture(scope="module", params=SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
def sized(request):
    """Chromium at each window size the page is checked at."""
    d = chromium(*request.param)
    yield d
    d.quit()


def in_view(driver, element_id: str) -> bool:
    """Whether the element shows on the screen as it is: inside the window, not scrolled away inside its own
    column, nothing else over it (the element at its middle is it)."""
    return driver.execute_script(
        "const e = document.getElementById(arguments[0]), r = e.getBoundingClientRect();"
        "if (r.width === 0 || r.height === 0) return false;"
        "const x = r.left + r.width / 2, y = r.top + Math.min(r.height / 2, 8);"
        "if (x < 0 || y < 0 || x > innerWidth || y > innerHeight) return false;"
        "const hit = document.elementFromPoint(x, y); return hit === e || e.contains(hit);",
        element_id,
    )


def keep_downloads(driver) -> None:
    """Downloads are noted (window.names) instead of saved."""
    driver.execute_script(
        "window.names = []; HTMLAnchorElement.prototype.click = function () { window.names.push(this.download); };"
    )


def downloaded(driver) -> list[str]:
    return driver.execute_script("return window.names")


def wheel(driver, steps: int = 1) -> None:
    driver.execute_script(
        "const c = document.getElementById('view');"
        f"for (let i = 0; i < {steps}; i++) c.dispatchEvent(new WheelEvent('wheel', {{deltaY: 60, bubbles: true}}));"
    )


def test_messages_are_where_the_eye_is_and_every_saved_file_is_said(server, sized) -> None:
    """The message line used to sit below the Save box, out of view at both sizes until the panel was scrolled:
    now it lies over the picture. Save YAML and Export page said nothing; now every action that writes a file
    names it there. A note such as "link copied" used to stay: it goes with the next action."""
    d = sized
    open_page(d, server)
    keep_downloads(d)
    width = d.find_element("id", "save-width")
    width.clear()
    width.send_keys("9000")
    d.find_element("id", "save-png").click()
    wait(d, lambda d: text(d, "message").startswith("save_png"), "no word on a picture too large")
    assert in_view(d, "message"), "the Save PNG error is out of view"

    d.find_element("id", "save-yaml").click()
    wait(d, lambda d: text(d, "message").startswith("saved torus.yaml"), "Save YAML said nothing")
    assert in_view(d, "message") and downloaded(d) == ["torus.yaml"]
    d.find_element("id", "export-page").click()
    wait(d, lambda d: text(d, "message").startswith("saved torus.html"), "Export page said nothing")
    assert in_view(d, "message") and downloaded(d) == ["torus.yaml", "torus.html"]

    d.find_element("id", "copy-link").click()
    wait(d, lambda d: text(d, "message").startswith(("link copied", "the link:")), "Copy link said nothing")
    seq = frame_state(d)[0]
    wheel(d)
    wait(d, lambda d: text(d, "message") == "", "the note on the copied link stayed after the view moved")
    wait_full_after(d, seq)


def saved_text(driver, button: str = "save-yaml") -> str:
    """Click `button` and return the text of the file the page hands to the browser."""
    driver.execute_script(
        "window.saved = []; const make = URL.createObjectURL;"
        "URL.createObjectURL = (b) => { window.saved.push(b); return make(b); };"
    )
    driver.find_element("id", button).click()
    return driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "const look = () => window.saved.length ? window.saved[0].text().then(done) : setTimeout(look, 50);"
        "look();"
    )


def set_field(driver, element_id: str, value) -> None:
    """A control set as a person sets it: the value, then its input and change events."""
    driver.execute_script(
        "const e = document.getElementById(arguments[0]); e.value = arguments[1];"
        "e.dispatchEvent(new Event('input')); e.dispatchEvent(new Event('change'));",
        element_id,
        value,
    )


def set_slider(driver, name: str, value: float) -> None:
    driver.execute_script(
        "const s = document.querySelector(`input[type=range][data-name=${arguments[0]}]`); s.value = arguments[1];"
        "s.dispatchEvent(new Event('input')); s.dispatchEvent(new Event('change'));",
        name,
        value,
    )


def page_look(driver) -> dict:
    """What the page shows of the view: mode, Look controls (and whether they can be used), sliders."""
    return driver.execute_script(
        "const v = (id) => document.getElementById(id).value, off = (id) => document.getElementById(id).disabled;"
        "const sliders = [...document.querySelectorAll('#sliders .slider')].map((row) => {"
        "  const [lo, s, hi] = row.querySelectorAll('input');"
        "  return [s.dataset.name, lo.value, hi.value, Number(s.value)]; });"
        "return {clip: v('clip'), size: v('clip-size'), cut: document.getElementById('cut').checked,"
        " color: v('color'), inside: v('inside'), background: v('background'), lights: v('lights'),"
        " disabled: ['clip', 'clip-size', 'cut', 'color', 'inside'].filter(off),"
        " gallery: !document.getElementById('gallery-row').hidden,"
        " objects: !document.getElementById('object-row').hidden, sliders,"
        " equation: v('equation'), name: v('shape-name')}"
    )


def test_a_saved_yaml_reopens_as_the_same_page(server, tmp_path) -> None:
    """Save YAML, then `implgen view FILE`: the picture was right, but the page opened in scene mode with the Look
    controls disabled, clip "none", size 3, a gold colour while the picture was box-clipped and red, the gallery
    hidden, a slider's span made anew around the saved value. Now the file reopens as the page it was saved from."""
    from test_view_browser import canvas_pixels

    d = chromium(1280, 800)
    try:
        seq = open_page(d, server)
        set_field(d, "clip", "box")
        set_field(d, "clip-size", "1.6")
        d.execute_script("document.getElementById('clip-size').dispatchEvent(new Event('input'))")
        set_field(d, "color", "#e02020")
        set_field(d, "background", "#203040")
        set_field(d, "lights", "headlight")
        set_slider(d, "a", 1.2345)
        seq = wait_full_after(d, seq)
        wheel(d, 2)
        import time

        time.sleep(0.6)  # the wheel's rest
        seq = wait_full_after(d, max(seq, frame_state(d)[0] - 1))
        before, shown = page_look(d), canvas_pixels(d)
        path = tmp_path / "torus.yaml"
        path.write_text(saved_text(d))
        with view_process(str(path)) as url:
            open_page(d, url)
            wait(d, lambda d: frame_state(d)[1] == "full", "the saved view was not drawn")
            after = page_look(d)
            assert after == before, (after, before)
            assert after["disabled"] == [] and after["gallery"] and not after["objects"]
            import numpy as np

            assert np.abs(canvas_pixels(d) - shown).mean() < 1.0
    finally:
        d.quit()


def caret_shown(driver) -> list:
    """The equation's error as shown: [message, the line at fault, the caret line, whether it all fits]."""
    return driver.execute_script(
        "const e = document.getElementById('equation-error'), pre = e.querySelector('pre');"
        "if (!pre) return [e.textContent];"
        "const [line, caret] = pre.textContent.split('\\n');"
        "return [e.firstChild.textContent, line, caret, pre.scrollWidth <= pre.clientWidth];"
    )


def test_a_syntax_error_says_where_with_a_caret_and_the_likely_fix(server, sized) -> None:
    """`x^2 + y^2 + (z^2 - 1` and `2x^2 + y^2` used to give only "syntax error in '...'": now the message says
    the column and the fix, and a caret under the equation's line points at the place, whole in the panel."""
    from test_view_page import apply

    d = sized
    open_page(d, server)
    apply(d, "x^2 + y^2 + (z^2 - 1")
    wait(d, lambda d: "column" in caret_shown(d)[0], "no place given for an unclosed '('")
    message, line, caret, fits = caret_shown(d)
    assert "syntax error at column 13: '(' is never closed" in message
    assert line == "x^2 + y^2 + (z^2 - 1" and caret == " " * 12 + "^" and fits
    apply(d, "2x^2 + y^2 + z^2 - 4*x*y*z + 2")
    wait(d, lambda d: "2x" in caret_shown(d)[0], "no fix named for 2x")
    message, line, caret, fits = caret_shown(d)
    assert "write 2*x for 2x" in message and caret == " ^" and fits
    long = "x^2 + y^2 + z^2 - 1 + " * 4 + "(x + y"
    apply(d, long)
    wait(d, lambda d: "never closed" in caret_shown(d)[0], "no place given in a long equation")
    message, line, caret, fits = caret_shown(d)
    assert fits and line[len(caret) - 1] == "(" and line.startswith("\u2026")  # a window about the place


def exported_ranges(html: str) -> dict[str, tuple[float, float]]:
    """The sliders of an exported page: name -> (min, max), as its inputs have them."""
    import re

    found = re.findall(r'<input type="range" data-param="\d+" min="([^"]+)" max="([^"]+)"[^>]*aria-label="(\w+)"', html)
    return {name: (float(lo), float(hi)) for lo, hi, name in found}


def shown_ranges(driver) -> dict[str, tuple[float, float]]:
    return {name: (float(lo), float(hi)) for name, lo, hi, _ in page_look(driver)["sliders"]}


def test_slider_ranges_stay_where_the_surface_keeps_its_kind_and_the_exported_page_agrees(server) -> None:
    """The torus's tube radius b ran -0.65..1.35 (a negative radius; past 1 a spindle), Barth's golden ratio 0..3.24,
    and Export page made its own ranges. Now a range is where the surface stays the same kind, and the exported
    page has the viewer's, the user's own edits included."""
    from test_view_page import BARTH6, apply

    d = chromium(1280, 800)
    try:
        open_page(d, server)
        lo, hi = shown_ranges(d)["b"]
        assert 0 <= lo < 0.35 < hi <= 1.0, (lo, hi)
        apply(d, BARTH6, "phi = 1.618033988749895, w = 1")
        wait(d, lambda d: text(d, "degree") == "degree 6", "Barth's sextic was not accepted")
        wait(d, lambda d: set(shown_ranges(d)) == {"phi", "w"}, "no sliders for Barth's params")
        lo, hi = shown_ranges(d)["phi"]
        assert 1.0 <= lo < 1.618 < hi <= 2.3, (lo, hi)  # between phi = 1 and its mirror: no sign change
        d.execute_script(
            "const min = document.querySelector('input[aria-label=\"w min\"]'); min.value = '0.5';"
            "min.dispatchEvent(new Event('change'));"
        )
        shown = shown_ranges(d)
        assert shown["w"][0] == 0.5
        exported = exported_ranges(saved_text(d, "export-page"))
        assert exported.keys() == shown.keys()
        assert all(exported[k] == pytest.approx(shown[k]) for k in shown), (exported, shown)
    finally:
        d.quit()


def clip_framing(driver) -> tuple[float, float]:
    """(the clip's bounding ball's angular radius, the picture's half-angle in its narrower direction), degrees,
    from the page's camera, clip and canvas."""
    import math

    size = float(driver.find_element("id", "clip-size").get_attribute("value"))
    kind = driver.find_element("id", "clip").get_attribute("value")
    orbit, w, h = driver.execute_script(
        "const c = document.getElementById('view'); return [window.implgenState().orbit, c.clientWidth, c.clientHeight]"
    )
    r = size * (math.sqrt(3) if kind == "box" else 1.0)
    off = math.dist(orbit["target"], (0, 0, 0))
    ball = math.degrees(math.asin(min(1.0, (r + off) / orbit["distance"])))
    half = math.degrees(math.atan(math.tan(math.radians(orbit["fov"] / 2)) * min(1.0, w / h)))
    return ball, half


def framed(driver) -> bool:
    ball, half = clip_framing(driver)
    return 0.7 * half < ball <= half


def test_the_camera_frames_the_clip_at_the_start_for_new_shapes_and_on_reset(server, sized) -> None:
    """The start torus's camera framed the torus's box, not its clip ball, which overflowed the picture; after a
    clip size set by hand (2.4) a new shape (Togliatti) overflowed it too, the camera left where it was; at
    800×600 the picture is taller than wide and a ball framed by the vertical angle overflowed sideways. Now the
    start, each new equation and Reset frame the clip in the picture's narrower direction."""
    from selenium.webdriver.support.ui import Select

    d = sized
    seq = open_page(d, server)
    assert framed(d), clip_framing(d)
    size = d.find_element("id", "clip-size")
    size.clear()
    size.send_keys("2.4\n")
    seq = wait_full_after(d, seq)
    Select(d.find_element("id", "gallery")).select_by_visible_text("Togliatti quintic")
    wait(d, lambda d: text(d, "degree") == "degree 5", "Togliatti's quintic was not accepted")
    seq = wait_full_after(d, seq)
    assert d.find_element("id", "clip-size").get_attribute("value") == "2.4"  # the user's own size stays
    assert framed(d), clip_framing(d)
    wheel(d, 6)  # zoom out, then back with Reset
    seq = wait_full_after(d, seq)
    assert not framed(d)
    d.find_element("id", "reset-view").click()
    wait_full_after(d, seq)
    assert framed(d), clip_framing(d)


def same_line(driver, first: str, second: str) -> bool:
    """Whether two elements (CSS selectors) sit on one line of their row."""
    return driver.execute_script(
        "const a = document.querySelector(arguments[0]).getBoundingClientRect(),"
        " b = document.querySelector(arguments[1]).getBoundingClientRect();"
        "return Math.abs((a.top + a.bottom) / 2 - (b.top + b.bottom) / 2) < 8;",
        first,
        second,
    )


def heading_in_view(driver) -> bool:
    return driver.execute_script(
        "const h = document.querySelector('#controls h1'), r = h.getBoundingClientRect();"
        "const hit = document.elementFromPoint(r.left + 4, r.top + r.height / 2); return hit === h;"
    )


def test_small_things_labels_dialog_names_and_messages(server, sized) -> None:
    """At 1280×800 the background swatch wrapped away from its label and Save PNG and Export page onto lines of
    their own; "Show generated C" scrolled the panel's header away and its dialog scrolled with the code; Save PNG
    was always implgen-view.png; a picture too large said "more than 37748736 pixels"; a cone with clip "none"
    was one flat colour with no hint."""
    d = sized
    seq = open_page(d, server)
    for control in ("color", "inside", "background", "clip", "clip-size", "lights", "save-spp"):
        assert same_line(d, f"label[for={control}]", f"#{control}"), control
    if d.get_window_size()["width"] >= 1280:
        assert same_line(d, "#save-width", "#save-png")
        assert same_line(d, "#save-yaml", "#export-page") and same_line(d, "#save-yaml", "#copy-link")

    d.find_element("id", "show-c").click()
    wait(d, lambda d: "torus_coeffs(" in text(d, "code"), "no generated C")
    d.execute_script("document.getElementById('code').scrollTop = 1e9")
    assert in_view(d, "close-code"), "the dialog's Close scrolled away with the code"
    d.find_element("id", "close-code").click()
    assert heading_in_view(d), "the panel's header scrolled away"

    keep_downloads(d)
    for field, value in (("save-width", "64"), ("save-height", "48"), ("save-spp", "1")):
        set_field(d, field, value)
    d.find_element("id", "save-png").click()
    wait(d, lambda d: text(d, "message").startswith("saved torus.png"), "Save PNG did not say its file")
    assert downloaded(d) == ["torus.png"]
    set_field(d, "save-width", "8192")
    set_field(d, "save-height", "8192")
    d.find_element("id", "save-png").click()
    wait(d, lambda d: "8192 × 8192 is 67,108,864 pixels" in text(d, "message"), "the size not said")
    assert "6144 × 6144 would do" in text(d, "message")

    from test_view_page import apply

    apply(d, "x^2 + y^2 - z^2")
    wait(d, lambda d: text(d, "degree") == "degree 2", "the cone was not accepted")
    seq = wait_full_after(d, seq)
    set_field(d, "clip", "none")
    wait(d, lambda d: "runs on without end" in text(d, "overlay"), "no hint on a cone without a clip")
    set_field(d, "clip", "sphere")
    wait(d, lambda d: text(d, "overlay") == "", "the hint stayed with a clip")


def test_the_first_picture_after_a_gallery_pick_is_not_a_blur(server) -> None:
    """The first frame after a gallery pick was an 84×71 blur stretched over the picture: now a new shape's first
    request waits a moment for its full-size picture before showing a coarse one."""
    from selenium.webdriver.support.ui import Select

    d = chromium(1280, 800)
    try:
        seq = open_page(d, server)
        d.execute_script(
            "window.drawn = []; const c = document.getElementById('view');"
            "new MutationObserver(() => window.drawn.push([Number(c.dataset.seq), c.dataset.kind]))"
            ".observe(c, {attributes: true, attributeFilter: ['data-frames']});"
        )
        Select(d.find_element("id", "gallery")).select_by_visible_text("Kummer quartic")
        wait(d, lambda d: text(d, "degree") == "degree 4", "the Kummer quartic was not accepted")
        wait_full_after(d, seq)
        drawn = [kind for s, kind in d.execute_script("return window.drawn") if s > seq]
        assert drawn and drawn[0] != "coarse", drawn
    finally:
        d.quit()


def test_a_scene_s_list_fits_the_panel_and_its_files_are_named_after_the_scene(tmp_path, sized) -> None:
    """The object drop-down ran past the panel; Save YAML was named after the picked object though it holds the
    whole scene. Now the list fits, and the scene's files are named after the scene file."""
    import yaml
    from selenium.webdriver.support.ui import Select

    scene = {
        "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "fov": 40},
        "lights": [{"position": [0, 5, 5], "color": [1, 1, 1]}],
        "objects": [
            {
                "difference": [
                    {"equation": "x^2 + y^2 + z^2 - 1", "name": "a_rather_long_shape_name_for_the_list"},
                    {"equation": "x^2 + (y - 0.8)^2 + z^2 - 0.36", "name": "another_long_shape_name_here"},
                ]
            }
        ],
    }
    path = tmp_path / "long_names.yaml"
    path.write_text(yaml.safe_dump(scene))
    d = sized
    with view_process(str(path)) as url:
        open_page(d, url)
        fits = d.execute_script(
            "const s = document.getElementById('object').getBoundingClientRect(),"
            " c = document.getElementById('controls');"
            "return s.right <= c.getBoundingClientRect().right + 1 && c.scrollWidth <= c.clientWidth;"
        )
        assert fits, "the object list runs past the panel"
        Select(d.find_element("id", "object")).select_by_index(1)
        pick = "another_long_shape_name_here"
        wait(d, lambda d: d.find_element("id", "shape-name").get_attribute("value") == pick, "no pick")
        keep_downloads(d)
        d.find_element("id", "save-yaml").click()
        wait(d, lambda d: text(d, "message").startswith("saved long_names.yaml"), "Save YAML named otherwise")
        assert downloaded(d) == ["long_names.yaml"]


def test_a_scene_s_link_reopens_the_same_view_of_the_same_scene(tmp_path) -> None:
    """In scene mode a link copied after an orbit reopened another view: the link's equation went to the file's
    first object (the floor became the picked ball). Now it names the picked object, and reopens the camera, that
    object and its edits; the note says what a link holds."""
    import time

    import numpy as np
    import yaml
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.support.ui import Select

    from test_view_browser import canvas_pixels
    from test_view_page import apply
    from view_fixtures import BALLS_SCENE

    path = tmp_path / "balls.yaml"
    path.write_text(yaml.safe_dump(BALLS_SCENE))
    d = chromium(1280, 800)
    try:
        with view_process(str(path)) as url:
            seq = open_page(d, url)
            Select(d.find_element("id", "object")).select_by_index(2)
            wait(d, lambda d: d.find_element("id", "shape-name").get_attribute("value") == "right", "no pick")
            apply(d, "(x - 2)^2 + y^2 + z^2 - r^2", "r = 0.6")
            wait(d, lambda d: set(shown_ranges(d)) == {"r"}, "the right ball's edit was not accepted")
            seq = wait_full_after(d, seq)
            canvas = d.find_element("id", "view")
            ActionChains(d).move_to_element(canvas).click_and_hold().move_by_offset(-60, 25).release().perform()
            wheel(d, 2)
            time.sleep(0.6)  # the wheel's rest
            seq = wait_full_after(d, max(seq, frame_state(d)[0] - 1))
            d.find_element("id", "copy-link").click()
            wait(d, lambda d: "the picked object and its edits" in text(d, "message"), "no word on what a link holds")
            link, here = d.current_url, canvas_pixels(d)
            assert "obj=2" in link
            first = d.current_window_handle
            d.switch_to.new_window("tab")
            open_page(d, link)
            wait(d, lambda d: d.find_element("id", "shape-name").get_attribute("value") == "right", "not the object")
            time.sleep(0.5)
            wait_full_after(d, frame_state(d)[0] - 1)
            assert Select(d.find_element("id", "object")).first_selected_option.text.startswith("right")
            assert np.abs(canvas_pixels(d) - here).mean() < 1.0
            d.close()
            d.switch_to.window(first)
    finally:
        d.quit()


def test_a_scene_object_that_runs_on_without_end_is_said_and_gets_a_clip(tmp_path) -> None:
    """An unbounded equation typed into a scene's object turned the picture to its material with no word, and
    Save mesh on the floor said the scene gives no clip with no way to give one. Now the page says so, and the
    Look's clip gives the picked object its own clip: the picture, Save YAML and Save mesh use it."""
    import yaml
    from selenium.webdriver.support.ui import Select

    from test_view_page import apply
    from view_fixtures import BALLS_SCENE

    path = tmp_path / "balls.yaml"
    path.write_text(yaml.safe_dump(BALLS_SCENE))
    d = chromium(1280, 800)
    try:
        with view_process(str(path)) as url:
            seq = open_page(d, url)
            Select(d.find_element("id", "object")).select_by_index(1)
            wait(d, lambda d: d.find_element("id", "shape-name").get_attribute("value") == "left", "no pick")
            apply(d, "(x + 2)^2 + y^2 - z^2")
            wait(d, lambda d: "left runs on without end" in text(d, "message"), "no word on an endless object")
            assert (
                d.find_element("id", "clip").is_enabled()
                and d.find_element("id", "clip").get_attribute("value") == "none"
            )
            seq = wait_full_after(d, seq)
            set_field(d, "clip-size", "1.5")
            set_field(d, "clip", "sphere")
            wait(d, lambda d: text(d, "message") == "", "the word stayed after the clip was given")
            seq = wait_full_after(d, seq)
            saved = yaml.safe_load(saved_text(d))
            assert saved["objects"][1]["clip"] == {"sphere": 1.5} and "clip" not in saved["objects"][0]

            Select(d.find_element("id", "object")).select_by_index(0)  # the floor: a plane
            wait(d, lambda d: d.find_element("id", "shape-name").get_attribute("value") == "floor", "no pick")
            wait(d, lambda d: d.find_element("id", "clip").get_attribute("value") == "none", "the floor's clip")
            set_field(d, "clip", "box")
            set_field(d, "clip-size", "3")  # the slab -3 < y < -2 of the cube
            keep_downloads(d)
            set_field(d, "mesh-cells", "64")
            d.find_element("id", "save-mesh").click()
            wait(d, lambda d: text(d, "message").startswith(("saved floor.stl", "save_mesh")), "no mesh")
            assert text(d, "message").startswith("saved floor.stl"), text(d, "message")
            Select(d.find_element("id", "object")).select_by_index(1)  # the left object keeps its clip
            wait(d, lambda d: d.find_element("id", "clip").get_attribute("value") == "sphere", "left's clip lost")
            assert d.find_element("id", "clip-size").get_attribute("value") == "1.5"
    finally:
        d.quit()


def test_equations_are_shown_as_the_user_wrote_them(server, tmp_path) -> None:
    """Saved specs and exported pages showed SymPy's order (`-k*(-x - y + z - 1)...` for `(x + y + z - 1)`), and
    so did the equation box of a reopened file: now the user's own tree, printed back."""
    import html as html_text

    import yaml

    from test_view_page import apply

    written = "4*(x^2 + y^2 + z^2 - 1) - k*(z - x)"  # SymPy: -k*(-x + z) + 4*x^2 + 4*y^2 + 4*z^2 - 4
    d = chromium(1280, 800)
    try:
        seq = open_page(d, server)
        apply(d, "4*(x^2+y^2+z^2-1) - k*(z-x)", "k = 0.5")
        wait(d, lambda d: text(d, "degree") == "degree 2", "the shape was not accepted")
        seq = wait_full_after(d, seq)
        saved = saved_text(d)
        assert yaml.safe_load(saved)["objects"][0]["equation"] == written
        page = html_text.unescape(saved_text(d, "export-page"))
        assert f"{written} = 0" in page
        path = tmp_path / "surface.yaml"
        path.write_text(saved)
        with view_process(str(path)) as url:
            open_page(d, url)
            assert d.find_element("id", "equation").get_attribute("value") == written
    finally:
        d.quit()


SHOTS = [(800, 600), (1280, 800), (1920, 1080)]


@pytest.mark.parametrize("size", SHOTS, ids=[f"{w}x{h}" for w, h in SHOTS])
def test_the_page_at_three_window_sizes(server, size) -> None:
    """Barth's sextic from the gallery at 800×600, 1280×800 and 1920×1080: no sideways scroll, the picture the
    larger part of the window, the controls' header and the gallery's line in view. With IMPLGEN_VIEW_SHOTS=DIR
    set (`make screenshot`), the page is saved as DIR/view-WxH.png (docs/viewer.md shows them)."""
    import os

    from selenium.webdriver.support.ui import Select

    d = chromium(*size)
    try:
        seq = open_page(d, server)
        Select(d.find_element("id", "gallery")).select_by_visible_text("Barth sextic")
        wait(d, lambda d: text(d, "degree") == "degree 6", "Barth's sextic was not accepted")
        wait_full_after(d, seq)
        import time

        time.sleep(1.0)
        wait(d, lambda d: frame_state(d)[1] == "full", "the picture did not rest")
        layout = d.execute_script(
            "const root = document.documentElement, s = document.getElementById('stage').getBoundingClientRect();"
            "return [root.scrollWidth <= root.clientWidth, s.width * s.height / (innerWidth * innerHeight)];"
        )
        assert layout[0] and layout[1] > 0.4, layout
        assert heading_in_view(d) and "Barth" in text(d, "gallery-note")
        shots = os.environ.get("IMPLGEN_VIEW_SHOTS")
        if shots:
            d.save_screenshot(os.path.join(shots, f"view-{size[0]}x{size[1]}.png"))
    finally:
        d.quit()
