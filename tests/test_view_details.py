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
