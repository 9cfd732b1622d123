"""The shared page: one HTML file holding a shape's GLSL, the GLSL runtime and the page's script and style.

The page's files are package data in static/: `surface.js` (IgSurface: the renderer, no page in it, meant to
be reused), `orbit.js` (IgOrbit: the camera and its pointer controls), `page.js` (this page's controls),
`page.css` and `page.html.j2`. Everything that comes from the user reaches the page in one of two ways:

- as HTML text or attribute values through Jinja2 with autoescaping (the equation re-printed from the parsed
  tree, the name and params -- validated identifiers --, the description, the file's name);
- inside the JSON block <script type="application/json" id="ig-data">, written by `script_json`, which escapes
  `<`, `>`, `&` and U+2028/2029 so no text can close the <script> element or be read as markup.

The page's own scripts and style are ours, inserted as they are; a Content-Security-Policy with their SHA-256
hashes lets nothing else run and nothing be fetched (default-src 'none').
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
from dataclasses import dataclass
from functools import cache, lru_cache
from pathlib import Path
from typing import Any

import jinja2

from implgen import __version__
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.emit import generate
from implgen.spec.model import Spec

STATIC = Path(__file__).resolve().parent / "static"
SCRIPTS = ("surface.js", "orbit.js", "page.js")  # in this order: page.js uses the other two
CLIPS = ("none", "sphere", "box")
MAX_DESCRIPTION = 400  # characters of the spec's description shown on the page
# the shape's Phong material, both sides: the shared page's and the viewer's (view/document.py, its GPU preview)
MATERIAL = {"ambient": 0.12, "diffuse": 0.75, "specular": 0.45, "shininess": 40.0}


@dataclass(frozen=True)
class Slider:
    name: str
    value: float
    lo: float
    hi: float


@dataclass(frozen=True)
class Look:
    """How the page starts: the clip and the colours (RGB in [0, 1]); the viewer's defaults."""

    clip: str = "sphere"
    clip_size: float = 3.0
    cut: bool = False  # False: the surface inside the clip, cut open (the viewer's default); True: the cut solid
    outside: tuple[float, float, float] = (0.95, 0.75, 0.3)
    inside: tuple[float, float, float] = (0.35, 0.55, 0.95)
    background: tuple[float, float, float] = (0.12, 0.12, 0.14)


def script_json(value: Any) -> str:
    """JSON that can stand inside a <script> element: nothing in it can end the element, open a comment or be
    read as markup (`<`, `>`, `&` as \\u escapes), and it is ASCII (U+2028 and U+2029 escaped too)."""
    text = json.dumps(value, ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    for ch in "<>&\u2028\u2029":
        text = text.replace(ch, f"\\u{ord(ch):04x}")
    return text


@cache
def static_text(name: str) -> str:
    """One of the page's own files. Scripts and the style are inserted raw, so they must not hold what would end
    their element early (a bug in implgen, not bad input)."""
    text = (STATIC / name).read_text(encoding="utf-8")
    lowered = text.lower()
    if name != "page.html.j2" and ("</script" in lowered or "</style" in lowered or "<!--" in lowered):
        raise RuntimeError(f"{name} holds a closing tag or a comment opener; the page would break")
    return text


@lru_cache(maxsize=1)
def _environment() -> jinja2.Environment:
    return jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(STATIC)),
        autoescape=True,
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
    )


def default_range(value: float) -> tuple[float, float]:
    """A slider's range when none is given: the value +- max(1, |value|), as the viewer's."""
    span = max(1.0, abs(value))
    return value - span, value + span


def slider(name: str, value: float, ranges: dict[str, tuple[float, float]]) -> Slider:
    """A param's slider over the spec's own range (`ranges`), widened to hold the value, else default_range."""
    if name not in ranges:
        return Slider(name, value, *default_range(value))
    lo, hi = ranges[name]
    return Slider(name, value, min(lo, value), max(hi, value))


def framing(
    spec: Spec, values: dict[str, float], clip_size: float | None = None, clip: str = "sphere"
) -> tuple[dict, float]:
    """The orbit that shows the shape's box whole, and a clip size just outside it; a shape without a finite box
    gets a view of the clip (`clip_size`, else a sphere of radius 3: the viewer's default)."""
    box = spec.box(values) if spec.params else spec.box()
    orbit = {"yaw": 30.0, "pitch": 25.0, "distance": 6.0, "target": [0.0, 0.0, 0.0], "fov": 40.0}
    if box is not None and all(math.isfinite(v) for v in box) and all(lo <= hi for lo, hi in zip(box[:3], box[3:])):
        radius = 0.5 * math.dist(box[:3], box[3:])
        orbit["target"] = [0.5 * (lo + hi) for lo, hi in zip(box[:3], box[3:])]
        orbit["distance"] = max(1e-3, radius / math.sin(math.radians(orbit["fov"] / 2)) * 1.1)
        clip_size = max(1e-3, round(radius * 1.2 + float(math.dist(orbit["target"], (0, 0, 0))), 3))
    else:
        clip_size = clip_size or 3.0  # the viewer's default
        radius = clip_size * (math.sqrt(3.0) if clip == "box" else 1.0)  # the clip's bounding sphere
        orbit["distance"] = radius / math.sin(math.radians(orbit["fov"] / 2)) * 1.1
    return orbit, clip_size


def _hex(rgb: tuple[float, float, float]) -> str:
    return "#" + "".join(f"{math.floor(max(0.0, min(1.0, c)) * 255 + 0.5):02x}" for c in rgb)


def _number(v: float) -> str:
    """A float as HTML takes it in an attribute (repr: shortest round trip; always finite here)."""
    return repr(float(v))


def _csp_hash(text: str) -> str:
    return "'sha256-" + base64.b64encode(hashlib.sha256(text.encode("utf-8")).digest()).decode("ascii") + "'"


def _box_text(box: list[float] | None) -> str:
    if box is None:
        return ""
    parts = []
    for axis, lo, hi in zip("xyz", box[:3], box[3:]):
        if math.isfinite(lo) or math.isfinite(hi):
            parts.append(f"{axis} {lo:.4g}..{hi:.4g}")
    return ", ".join(parts)


def _page_data(spec: Spec, sliders: list[Slider], look: Look, orbit: dict) -> dict:
    """The page's JSON block: what its script draws (the shape's GLSL, the runtime, the view)."""
    return {
        "name": spec.name,
        "glsl_name": glsl_name(spec.name),  # the prefix of the shape's GLSL identifiers
        "shape": generate(spec, ("glsl",))[f"{spec.name}.glsl"],
        "runtime": runtime_text(),
        "header": HEADERS["es"],
        "params": [{"name": s.name, "value": s.value, "min": s.lo, "max": s.hi} for s in sliders],
        "orbit": orbit,
        "clip": {"kind": look.clip, "size": look.clip_size, "cut": look.cut},
        "material": MATERIAL,
    }


def _csp(scripts: list[str], css: str) -> str:
    """The page's Content-Security-Policy: nothing but its own inline scripts and style, by their hashes."""
    return "; ".join(
        (
            "default-src 'none'",
            "script-src " + " ".join(_csp_hash(s) for s in scripts),
            "style-src " + _csp_hash(css),
            "img-src data:",
            "base-uri 'none'",
            "form-action 'none'",
        )
    )


def slider_step(lo: float, hi: float) -> float:
    """A slider's step: a power of ten, a thousandth of its span or finer, as the viewer's page (app.js) takes it,
    so that the decimal values between its ends (0.45 of 0.004..1) are values it can take."""
    span = hi - lo
    if not (math.isfinite(span) and span > 0):
        return span / 1000
    return 10.0 ** (math.floor(math.log10(span)) - 3)


def _slider_fields(s: Slider) -> dict:
    """A slider as the template writes its input: numbers as the page parses them, the ends as shown."""
    return {
        "name": s.name,
        "value": _number(s.value),
        "min": _number(s.lo),
        "max": _number(s.hi),
        "step": _number(slider_step(s.lo, s.hi)),
        "min_text": f"{s.lo:.6g}",
        "max_text": f"{s.hi:.6g}",
    }


def render_page(spec: Spec, sliders: list[Slider], look: Look, source_name: str, orbit: dict | None = None) -> str:
    """The page as text. `sliders` in the spec's param order; `orbit` (yaw, pitch, distance, target, fov) defaults
    to a view of the shape's box."""
    values = {s.name: s.value for s in sliders}
    if orbit is None:
        orbit, _ = framing(spec, values)
    data = _page_data(spec, sliders, look, orbit)
    scripts = [static_text(name) for name in SCRIPTS]
    css = static_text("page.css")
    description = " ".join(spec.description.split())
    if len(description) > MAX_DESCRIPTION:
        description = description[: MAX_DESCRIPTION - 3] + "..."
    box = spec.box(values) if spec.params else spec.box()
    return (
        _environment()
        .get_template("page.html.j2")
        .render(
            version=__version__,
            csp=_csp(scripts, css),
            name=spec.name,
            equation=spec.as_written if "=" in spec.as_written else f"{spec.as_written} = 0",  # as written
            degree=spec.degree,
            box=_box_text(box),
            description=description,
            params=[_slider_fields(s) for s in sliders],
            clips=CLIPS,
            clip=look.clip,
            clip_size=_number(look.clip_size),
            cut=look.cut,
            outside=_hex(look.outside),
            inside=_hex(look.inside),
            background=_hex(look.background),
            source=source_name,
            css=css,
            data=script_json(data),
            scripts=scripts,
        )
    )
