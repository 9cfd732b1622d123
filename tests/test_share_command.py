"""`implgen share`: the page file itself, without a browser (tests/test_share_browser.py opens it).

One self-contained file: the shape's GLSL and the runtime in a JSON block that decodes to exactly what
`implgen --lang glsl` writes, the page's own scripts and style inline under a Content-Security-Policy of their
hashes, nothing fetched (no URL, no src or href). Hostile text from a spec (its description, its file's name)
reaches the page only escaped: the HTML parses to the same elements whatever the text says. Bad options give one
line, exit status 2 and no file.
"""

from __future__ import annotations

import base64
import hashlib
import json
import re
from html.parser import HTMLParser

import pytest
import yaml

import needs_program
import page_shader
from conftest import ROOT, SHAPES_DIR
from implgen.cli import main
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.emit import generate
from implgen.share.page import script_json
from implgen.spec.entry import load_spec

SCENES_DIR = ROOT / "examples" / "scenes"
HOSTILE = (
    '</script><script>window.pwned=1</script><!-- "quotes\' & <img src=x onerror="window.pwned=2"> \u2028\u2029]]>'
)


class Elements(HTMLParser):
    """Every start tag with its attributes, and the text inside each <script> and <style>."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.tags: list[tuple[str, dict]] = []
        self.raw: dict[str, list[str]] = {"script": [], "style": []}
        self.text: list[str] = []
        self._in: str | None = None

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))
        self._in = tag if tag in self.raw else None

    def handle_endtag(self, tag):
        self._in = None

    def handle_data(self, data):
        if self._in:
            self.raw[self._in].append(data)
        else:
            self.text.append(data)


def share(tmp_path, *args: str, capsys=None) -> tuple[int, str]:
    code = main(["share", *args])
    err = capsys.readouterr().err if capsys else ""
    return code, err


@pytest.fixture(scope="module")
def browser():
    """Headless Chromium that runs the pages' own surface.js (started by the first test that needs it)."""
    lazy = page_shader.LazyChromium()
    yield lazy
    lazy.quit()


@pytest.fixture(autouse=True)
def every_page_s_shader_compiles(tmp_path, tmp_path_factory, browser):
    """After each test: every page it wrote has a fragment shader (as the page's JavaScript puts it together)
    that glslangValidator passes, warnings included. Where Chromium or glslangValidator is missing this is left
    out; the tests that write pages for this check say they need them (and fail under IMPLGEN_REQUIRE_ALL)."""
    yield
    pages = page_shader.shared_pages(tmp_path)
    if not pages or needs_program.missing(("glslangValidator", "chromium", "chromedriver")):
        return
    folder = tmp_path_factory.mktemp("frag")
    for page in pages:
        fragment = page_shader.page_fragment(browser(), page.read_text(encoding="utf-8"))
        problems = page_shader.glslang_problems(fragment, folder / "page.frag")
        assert not problems, f"{page.name}:\n{problems}"


def parse_page(path):
    html = path.read_text(encoding="utf-8")
    p = Elements()
    p.feed(html)
    p.close()
    return html, p


def page_data(p: Elements) -> dict:
    scripts = [t for t in p.tags if t[0] == "script"]
    assert scripts[0][1] == {"type": "application/json", "id": "ig-data"}
    return json.loads(p.raw["script"][0])


def test_a_page_holds_the_shape_and_runtime_and_fetches_nothing(tmp_path, capsys):
    out = tmp_path / "torus.html"
    code, _ = share(tmp_path, str(SHAPES_DIR / "torus_y.yaml"), "-o", str(out), capsys=capsys)
    assert code == 0
    assert [f.name for f in tmp_path.iterdir()] == ["torus.html"]  # one file, no temporary left
    html, p = parse_page(out)
    spec = load_spec(SHAPES_DIR / "torus_y.yaml")
    data = page_data(p)
    assert data["shape"] == generate(spec, ("glsl",))["torus_y.glsl"]
    assert data["runtime"] == runtime_text()
    assert data["name"] == "torus_y"
    assert [(q["name"], q["value"], q["min"], q["max"]) for q in data["params"]] == [
        ("a", 1.0, 0.25, 1.75),  # where the ring torus stays one (spec/paramrange.py, as the viewer's sliders)
        ("b", 0.25, 0.003, 1.0),
    ]
    # nothing from elsewhere: no URL, no element that loads anything
    assert not re.search(r"https?:|//[a-z0-9.-]+\.[a-z]{2,}/", html, re.I)
    for tag, attrs in p.tags:
        assert tag not in ("link", "img", "iframe", "object", "embed", "base", "form"), tag
        assert "src" not in attrs and "href" not in attrs, (tag, attrs)
    # every script but the data block runs only because the policy names its hash
    (csp,) = [a["content"] for t, a in p.tags if t == "meta" and a.get("http-equiv") == "Content-Security-Policy"]
    assert "default-src 'none'" in csp
    code_blocks = p.raw["script"][1:]
    assert len(code_blocks) == 3
    for block in code_blocks + p.raw["style"]:
        digest = base64.b64encode(hashlib.sha256(block.encode()).digest()).decode()
        assert f"'sha256-{digest}'" in csp
    # the line saying what was parsed: the equation printed back from the tree
    text = " ".join(" ".join(p.text).split())
    assert f"{spec.as_written} = 0" in text  # the equation as written, printed back from the parsed tree
    assert "degree 4" in text
    sliders = [a for t, a in p.tags if t == "input" and a.get("type") == "range"]
    assert [(a["aria-label"], a["min"], a["max"], a["value"]) for a in sliders] == [
        ("a", "0.25", "1.75", "1.0"),
        ("b", "0.003", "1.0", "0.25"),
    ]


def test_script_json_cannot_leave_its_element():
    text = script_json({"k": HOSTILE, HOSTILE: [HOSTILE]})
    assert not set(text) & set("<>&\u2028\u2029")
    assert text.isascii()
    assert json.loads(text) == {"k": HOSTILE, HOSTILE: [HOSTILE]}


def test_hostile_spec_text_reaches_the_page_only_escaped(tmp_path, capsys):
    """The description and the file's name are the spec's only free text (the name and params are identifiers,
    the equation is printed from its tree). Whatever they hold, the page parses to the same elements, the text
    reads back as written, and the raw text is nowhere in the file."""
    name = "<script>x=1<!--'&\"x.yaml"
    spec_file = tmp_path / name
    spec_file.write_text(
        f"name: evil\ndescription: {json.dumps(HOSTILE)}\nequation: x^2 + y^2 + z^2 - r^2\nparams: {{r: 1}}\n",
        encoding="utf-8",
    )
    plain = tmp_path / "plain.yaml"
    plain.write_text(
        "name: evil\ndescription: plain words\nequation: x^2 + y^2 + z^2 - r^2\nparams: {r: 1}\n", encoding="utf-8"
    )
    out, ref = tmp_path / "evil.html", tmp_path / "plain.html"
    assert share(tmp_path, str(spec_file), "-o", str(out), capsys=capsys)[0] == 0
    assert share(tmp_path, str(plain), "-o", str(ref), capsys=capsys)[0] == 0
    html, p = parse_page(out)
    ref_html, q = parse_page(ref)
    for raw in (HOSTILE, "<script>x", "<!--", "<img", "\u2028", "\u2029"):
        assert raw not in html
    assert html.lower().count("</script") == ref_html.lower().count("</script") == 4
    assert [t for t, _ in p.tags] == [t for t, _ in q.tags]  # no element more or less than the plain spec's
    text = "".join(p.text)
    assert " ".join(HOSTILE.split()) in " ".join(text.split())  # shown as text (whitespace collapsed)
    assert name in text
    shape, plain_shape = page_data(p)["shape"], page_data(q)["shape"]
    assert shape.split("\n", 1)[1] == plain_shape.split("\n", 1)[1]  # the first line names the file, escaped:
    assert "from U+003CscriptU+003Ex=1U+003CU+0021--" in shape.split("\n", 1)[0]


def test_params_ranges_and_clip_from_the_options(tmp_path, capsys):
    out = tmp_path / "t.html"
    args = ["--param", "b=0.4", "--range", "b=0.05:0.5", "--clip", "box", "--clip-size", "1.5", "-o", str(out)]
    assert share(tmp_path, str(SHAPES_DIR / "torus_y.yaml"), *args, capsys=capsys)[0] == 0
    _, p = parse_page(out)
    data = page_data(p)
    assert [(q["name"], q["value"], q["min"], q["max"]) for q in data["params"]] == [
        ("a", 1.0, 0.25, 1.75),
        ("b", 0.4, 0.05, 0.5),
    ]
    assert data["clip"] == {"kind": "box", "size": 1.5, "cut": False}  # the viewer's default: cut open
    (selected,) = [a["value"] for t, a in p.tags if t == "option" and "selected" in a]
    assert selected == "box"
    assert not [a for t, a in p.tags if t == "input" and a.get("id") == "ig-cut" and "checked" in a]
    assert share(tmp_path, str(SHAPES_DIR / "torus_y.yaml"), *args, "--cut", capsys=capsys)[0] == 0
    _, p = parse_page(out)
    assert page_data(p)["clip"] == {"kind": "box", "size": 1.5, "cut": True}
    assert [a for t, a in p.tags if t == "input" and a.get("id") == "ig-cut" and "checked" in a]


def test_a_slider_runs_over_the_spec_s_own_range(tmp_path, capsys):
    """The gallery's Kummer quartic names its range of mu (0.65 to 1.7): the slider runs over it, widened to
    hold a value given outside it."""
    out = tmp_path / "k.html"
    assert share(tmp_path, str(SHAPES_DIR / "kummer.yaml"), "-o", str(out), capsys=capsys)[0] == 0
    assert [(q["name"], q["min"], q["max"]) for q in page_data(parse_page(out)[1])["params"]] == [("mu", 0.65, 1.7)]
    assert share(tmp_path, str(SHAPES_DIR / "kummer.yaml"), "--param", "mu=1.8", "-o", str(out), capsys=capsys)[0] == 0
    assert [(q["min"], q["max"]) for q in page_data(parse_page(out)[1])["params"]] == [(0.65, 1.8)]


def test_an_object_of_a_scene_by_name(tmp_path, capsys):
    """The scene's torus: its params start the sliders, its material gives the outside colour."""
    out = tmp_path / "t.html"
    code, _ = share(
        tmp_path, str(SCENES_DIR / "torus_shadow.yaml"), "--object", "torus_y", "-o", str(out), capsys=capsys
    )
    assert code == 0
    _, p = parse_page(out)
    data = page_data(p)
    assert [(q["name"], q["value"]) for q in data["params"]] == [("a", 1.0), ("b", 0.3)]
    colours = {a["id"]: a["value"] for t, a in p.tags if t == "input" and a.get("type") == "color"}
    assert colours["ig-outside"] == "#d9734d"  # copper (0.85, 0.45, 0.3): 216.75, 114.75, 76.5, halves rounded up
    assert colours["ig-background"] == "#8cb3e6"  # the scene's (0.55, 0.7, 0.9)


BAD = [
    (["{torus}"], "-o"),  # no output: argparse's required option
    (["{torus}", "-o", "{tmp}/page.png"], "must end in .html or .htm"),
    (["{torus}", "-o", "{tmp}/missing/page.html"], "does not exist"),
    (["{torus}", "-o", "{tmp}"], "is a folder"),
    (["{tmp}/nothing.yaml", "-o", "{tmp}/missing/page.html"], "-o"),  # the output is checked first
    (["{tmp}/nothing.yaml", "-o", "{tmp}/page.html"], "not found"),
    (["{torus}", "--param", "c=1", "-o", "{tmp}/page.html"], "no param 'c'"),
    (["{torus}", "--param", "a", "-o", "{tmp}/page.html"], "expected NAME=VALUE"),
    (["{torus}", "--param", "a=abc", "-o", "{tmp}/page.html"], "finite number"),
    (["{torus}", "--param", "a=nan", "-o", "{tmp}/page.html"], "finite number"),
    (["{torus}", "--param", "a=1e99", "-o", "{tmp}/page.html"], "outside"),
    (["{torus}", "--param", "a=1", "--param", "a=2", "-o", "{tmp}/page.html"], "given twice"),
    (["{torus}", "--range", "a=2:1", "-o", "{tmp}/page.html"], "LOW must be below HIGH"),
    (["{torus}", "--range", "a=2", "-o", "{tmp}/page.html"], "expected NAME=LOW:HIGH"),
    (["{torus}", "--range", "a=2:3", "-o", "{tmp}/page.html"], "does not hold"),
    (["{torus}", "--clip", "cone", "-o", "{tmp}/page.html"], "invalid choice"),
    (["{torus}", "--clip-size", "0", "-o", "{tmp}/page.html"], "outside"),
    (["{torus}", "--clip-size", "x", "-o", "{tmp}/page.html"], "finite number"),
    (["{torus}", "--object", "torus_y", "-o", "{tmp}/page.html"], "is a shape spec, not a scene"),
    (["{scene}", "--param", "a=1", "-o", "{tmp}/page.html"], "applies to a shape"),
    (["{scene}", "--object", "cube", "-o", "{tmp}/page.html"], "no shape of that name"),
]


@pytest.mark.parametrize("argv,message", BAD, ids=[" ".join(a[1:])[:50] for a, _ in BAD])
def test_bad_input_is_one_line_and_writes_nothing(tmp_path, capsys, argv, message):
    values = {"torus": str(SHAPES_DIR / "torus_y.yaml"), "scene": str(SCENES_DIR / "torus_shadow.yaml")}
    argv = [a.format(tmp=tmp_path, **values) for a in argv]
    before = sorted(tmp_path.rglob("*"))
    code = main(["share", *argv])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("implgen: error: ") and message in err, err
    assert sorted(tmp_path.rglob("*")) == before


@pytest.mark.needs_program("glslangValidator", "chromium", "chromedriver")
@pytest.mark.parametrize("spec_path", sorted(SHAPES_DIR.glob("*.yaml")), ids=lambda p: p.stem)
def test_every_example_page_shader_compiles_as_es300(tmp_path, capsys, spec_path):
    """What the page compiles, for every example shape, through Khronos' reference compiler (the browser tests
    compile a few shapes in Chromium; this covers them all). The check itself is every_page_s_shader_compiles."""
    out = tmp_path / "page.html"
    assert share(tmp_path, str(spec_path), "-o", str(out), capsys=capsys)[0] == 0
    data = page_data(parse_page(out)[1])
    assert data["glsl_name"] == spec_path.stem and data["header"] == HEADERS["es"]  # the header's one source


# Names that make GLSL identifiers GLSL reserves (__, gl_, webgl_), that a page's text once held in its own
# (MAX_LIGHTS, SHAPE), that would hide the shape's own identifiers (shape k, param params), and JavaScript's own.
AWKWARD_NAMES = {
    "ball_": {"a__b": 1.0, "value_": 0.0},
    "MAX_LIGHTS_ball": {"MAX_LIGHTS": 1.0},
    "SHAPE_ball": {"SHAPE_hit": 1.0},
    "k": {"params": 1.0, "b": 1.0},
    "gl_ball": {"constructor": 1.0, "toString": 1.0, "valueOf": 0.0, "hasOwnProperty": 0.0},
    "webgl_ball": {"gl_x": 1.0},
}


@pytest.mark.needs_program("glslangValidator", "chromium", "chromedriver")
@pytest.mark.parametrize("name", AWKWARD_NAMES)
def test_a_page_for_names_glsl_or_the_page_would_misread(tmp_path, capsys, name):
    """Exit 0 and a page whose shader compiles (every_page_s_shader_compiles); the C backend takes these names
    too. The page's shape functions are the spelled ones (codegen/backends/glsl/printer.py glsl_name)."""
    params = AWKWARD_NAMES[name]
    terms = " + ".join(f"{p}*{p}" for p in params)
    spec = tmp_path / "awkward.yaml"
    spec.write_text(
        yaml.safe_dump({"name": name, "equation": f"x^2 + y^2 + z^2 - 1 + {terms}", "params": params}, sort_keys=False)
    )
    out = tmp_path / "page.html"
    assert share(tmp_path, str(spec), "-o", str(out), capsys=capsys)[0] == 0
    data = page_data(parse_page(out)[1])
    assert data["name"] == name and data["glsl_name"] == glsl_name(name)
    assert f"int {data['glsl_name']}_hit(" in data["shape"]
