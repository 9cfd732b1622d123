"""Khronos' reference compiler on a fragment shader, and the fragment shader a shared page compiles.

`glslang_problems(text, path)`: glslangValidator's errors and warnings on `text` (written to `path`, a .frag
file), or '' when it has none. A warning counts: glslangValidator only warns about an identifier that holds
`__`, which GLSL reserves and WebGL refuses.

`page_fragment(driver, html)`: the fragment shader of a page `implgen share` wrote, as the page puts it
together: the page's own surface.js, run in the browser `driver` drives, its `fragmentSource` called with what
page.js passes it from the page's data (`glsl_name`, `shape`, `runtime`, `header`). No copy of how the shader
is assembled. `shared_pages(folder)`: every such page under a folder.
"""

from __future__ import annotations

import json
import subprocess
from html.parser import HTMLParser
from pathlib import Path

# page.js: r.setEquationProgram({name: data.glsl_name, shape: data.shape, runtime: data.runtime, header: ...})
ASSEMBLE = "\nconst d = arguments[0];\nreturn IgSurface.fragmentSource(d.glsl_name, d.shape, d.runtime, d.header);"


class _Scripts(HTMLParser):
    """Each <script>'s attributes and text."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.scripts: list[tuple[dict, str]] = []
        self._open: dict | None = None

    def handle_starttag(self, tag, attrs):
        if tag == "script":
            self._open = dict(attrs)
            self.scripts.append((self._open, ""))

    def handle_endtag(self, tag):
        self._open = None

    def handle_data(self, data):
        if self._open is not None:
            attrs, text = self.scripts[-1]
            self.scripts[-1] = (attrs, text + data)


def page_parts(html: str) -> tuple[str, dict]:
    """(the page's surface.js, the page's data) from a shared page's text."""
    parser = _Scripts()
    parser.feed(html)
    data = [json.loads(text) for attrs, text in parser.scripts if attrs.get("id") == "ig-data"]
    surface = [text for attrs, text in parser.scripts if "const IgSurface = " in text]
    assert len(data) == 1 and len(surface) == 1, "not a page implgen share writes"
    return surface[0], data[0]


def page_fragment(driver, html: str) -> str:
    surface, data = page_parts(html)
    return driver.execute_script(surface + ASSEMBLE, data)


def glslang_problems(text: str, path: Path) -> str:
    path.write_text(text, encoding="utf-8")
    proc = subprocess.run(["glslangValidator", str(path)], capture_output=True, text=True, timeout=300)
    out = proc.stdout + proc.stderr
    flagged = [line for line in out.splitlines() if line.startswith(("ERROR", "WARNING"))]
    return out if proc.returncode != 0 or flagged else ""


def shared_pages(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*.html") if 'id="ig-data"' in p.read_text(encoding="utf-8"))


def plain_chromium():
    """Headless Chromium without WebGL work to do: it only runs the pages' scripts' functions."""
    import shutil

    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = shutil.which("chromium")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service(shutil.which("chromedriver")), options=opts)
    driver.get("about:blank")
    return driver


class LazyChromium:
    """plain_chromium(), started on the first call and kept; quit() ends it."""

    def __init__(self) -> None:
        self.driver = None

    def __call__(self):
        if self.driver is None:
            self.driver = plain_chromium()
        return self.driver

    def quit(self) -> None:
        if self.driver is not None:
            self.driver.quit()
            self.driver = None
