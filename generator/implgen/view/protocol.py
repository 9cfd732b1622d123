"""The page's messages, parsed and checked: every number against a range, every equation through the spec parser.

A message is one JSON object of at most MAX_MESSAGE bytes with a `type`:

    {"type": "shape", "equation": "...", "params": {"a": 1.0}}        a new equation and its param defaults
                                                                      (optional "bounds" as in a spec; "object":
                                                                      a scene's leaf it is for, picked first)
    {"type": "render", "seq": 7, "refine": true, "width": 640, "height": 480,
     "values": {"a": 1.2}, "orbit": {...}, "options": {...},
     "gpu": false}                                                    the view to show (the newest wins); gpu:
                                                                      the page draws the live picture itself,
                                                                      so no coarse frames, only the refined
    {"type": "save_png", "width": 1920, "height": 1080, "spp": 16}    the current view through render()
    {"type": "save_yaml", "width": 640, "height": 480,
     "ranges": {"a": [0, 2]}}                                         the view as a scene file (its full frame),
                                                                      with the page's slider ranges
    {"type": "save_mesh", "cells": 128, "values": {...},
     "options": {...}}                                                the shape as a closed STL (meshsave.py)
    {"type": "stop_mesh"}                                             stop the mesh in progress
    {"type": "show_c"}                                                the generated C
    {"type": "export_page"}                                           the view as `implgen share`'s page
    {"type": "glsl", "ask": 3, "values": {...}}                       the GPU preview: the shape's GLSL, or a
                                                                      scene's program (its leaf at these values;
                                                                      the reply carries `ask` back) (gpu.py)
    {"type": "fix", "seq": 7, "width": 640, "height": 480,
     "values": {...}, "orbit": {...}, "options": {...},
     "part": 0, "pixels": [1234, ...]}                                a GPU-drawn scene at rest: these pixels
                                                                      (y * width + x) in double (fix.py)
    {"type": "pick", "x": 120, "y": 80, "width": 640, "height": 480}  a scene file: edit the object at a pixel
    {"type": "object", "index": 2}                                    a scene file: edit this leaf
    {"type": "clip", "clip": "sphere", "size": 2.5}                   a scene file: the picked (top-level)
                                                                      object's clip (none, sphere, box)

Bad values raise UserError naming the message field; the session sends the line back to the page. Every
error reply, whatever failed, is built here (`error`, `error_for`). An equation's parse (seconds of SymPy at
high degree) is remembered, refusal included, for the last PARSE_CACHE mappings of text, params and bounds: the
session runs it on its parse pool, never on the event loop.

    {"type": "error", "field": "equation" | "message", "message": "...",
     "position": 12}                                                  (an equation's: the character at fault)
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass
from typing import Any

from implgen import validate
from implgen.errors import UserError, out_of_files, out_of_files_error
from implgen.mesh.budget import MAX_CELLS, MIN_CELLS
from implgen.spec.entry import parse_spec
from implgen.spec.grammar import format_expression
from implgen.spec.parse import Spec, param_symbol
from implgen.view.document import CLIPS, LIGHTS, Options, Orbit

MAX_MESSAGE = 64 * 1024  # bytes of one message from the page
MAX_FRAME = (2048, 2048)  # the largest interactive frame
MAX_SAVE = (8192, 8192)  # the largest saved picture
MAX_SAVE_PIXELS = 8192 * 4608  # 8K at 16:9
MAX_SAVE_SPP = 64
MAX_FIX_PIXELS = 6000  # pixels one `fix` message may name (its JSON stays well below MAX_MESSAGE)
MAX_FIX_PARTS = 16  # fix messages one rest may send: a page with more flagged pixels asks for the frame (gpu.js)
MESH_TYPES = ("save_mesh", "stop_mesh")  # meshsave.py
TYPES = (
    "shape",
    "render",
    "save_png",
    "save_yaml",
    "show_c",
    "pick",
    "object",
    "clip",
    "export_page",
    "glsl",
    "fix",
    *MESH_TYPES,
)
PARSE_CACHE = 16  # parsed equations remembered (a degree-24 spec holds its SymPy expression: megabytes)
# The ranges of the view's numbers, stated once: the checks below use them, and the hello sends them to the page,
# whose share link (static/share.js) drops a number outside them instead of keeping a range of its own.
RANGES = {
    "value": (-validate.MAX_COORDINATE, validate.MAX_COORDINATE),  # a param's value (a slider)
    "yaw": (-1e6, 1e6),
    "pitch": (-89.0, 89.0),
    "distance": (1e-3, 1e6),
    "target": (-1e6, 1e6),
    "fov": (1.0, 150.0),
    "clip_size": (1e-3, 1e6),
}


@dataclass
class RenderRequest:
    seq: int
    refine: bool
    width: int
    height: int
    values: dict[str, float]
    orbit: Orbit
    options: Options
    gpu: bool = False  # the page draws the live frames (WebGL2): send the refined frames only


def decode(text: str | bytes) -> dict[str, Any]:
    """One message: a JSON object with a known `type`."""
    if len(text) > MAX_MESSAGE:
        raise UserError("message", f"longer than {MAX_MESSAGE} bytes")
    try:
        data = json.loads(text)
    except (ValueError, RecursionError):
        raise UserError("message", "not JSON") from None
    if not isinstance(data, dict) or data.get("type") not in TYPES:
        raise UserError("message", f"expected an object with type one of: {', '.join(TYPES)}")
    return data


def error(field: str, message: str) -> dict:
    """The one error reply: `field` says where the page shows it ("equation": beside the equation box;
    "message": the status line)."""
    return {"type": "error", "field": field, "message": message}


def error_for(err: Exception) -> dict:
    """The reply to a failure: bad input (UserError) as its line, the equation parser's beside the equation;
    anything else is a bug, named by its kind only (the server's log has the traceback), except running out of file
    descriptors, which is said as it is."""
    if out_of_files(err):
        err = out_of_files_error(None, err)
    if not isinstance(err, UserError):
        return error("message", f"internal error: {type(err).__name__}")
    if err.source == "equation":  # beside the equation box, a caret under the character at fault when known
        reply = error("equation", err.message)
        return reply if err.position is None else {**reply, "position": err.position}
    return error("message", str(err))


def _mapping(key: str, value: Any) -> dict:
    if not isinstance(value, dict):
        raise UserError(key, "expected a mapping")
    return value


def _bounds_text(spec: Spec) -> dict[str, list[str]] | None:
    """The spec's bounds printed back in the equation grammar (so they can be parsed again with new params)."""
    if spec.bounds is None:
        return None
    names = {param_symbol(p): p for p in spec.params}
    return {a: [format_expression(lo, names), format_expression(hi, names)] for a, (lo, hi) in spec.bounds.items()}


@functools.lru_cache(maxsize=PARSE_CACHE)  # thread-safe; a refusal is remembered as well
def _parse_text(key: str) -> Spec | UserError:
    try:
        return parse_spec(json.loads(key), "equation")
    except UserError as err:
        return err


def _parse(mapping: dict[str, Any]) -> Spec:
    """parse_spec(mapping, "equation"), remembered by the mapping's JSON text (the last PARSE_CACHE of them)."""
    hit = _parse_text(json.dumps(mapping, sort_keys=True))
    if isinstance(hit, UserError):
        raise UserError(hit.source, hit.message, hit.position)
    return hit


def _used(spec: Spec) -> set[str]:
    """The params the equation or the bounds use."""
    symbols = set(spec.f.free_symbols)
    for lo, hi in (spec.bounds or {}).values():
        symbols |= lo.free_symbols | hi.free_symbols
    return {p for p in spec.params if param_symbol(p) in symbols}


def _parse_used(mapping: dict[str, Any]) -> Spec:
    """_parse, and again without the params neither the equation nor the bounds use (no slider for them)."""
    spec = _parse(mapping)
    used = _used(spec)
    if len(used) < len(spec.params):
        mapping = {
            k: {p: v for p, v in mapping[k].items() if p in used} if k in ("params", "ranges") else v
            for k, v in mapping.items()
        }
        mapping = {k: v for k, v in mapping.items() if v or k not in ("params", "ranges")}
        spec = _parse(mapping)
    return spec


def parse_shape(data: dict, current: Spec) -> Spec:
    """A new equation, its name (the page sends `surface` for a typed one; the spec parser checks it) and param
    defaults, through the spec parser; params the equation does not use are dropped. Without a name the current
    shape's is kept, and its bounds while the equation stays the same (new defaults
    only): a box made for one surface would cut another one anywhere."""
    mapping: dict[str, Any] = {"name": data.get("name", current.name), "equation": data.get("equation")}
    if data.get("params"):
        mapping["params"] = _mapping("params", data["params"])
        if data.get("ranges"):  # a gallery spec's own slider ranges, checked by the spec parser
            mapping["ranges"] = _mapping("ranges", data["ranges"])
    if data.get("bounds") is not None:  # given: checked like a spec file's
        return _parse_used({**mapping, "bounds": data["bounds"]})
    spec = _parse_used(mapping)
    bounds = _bounds_text(current)
    if bounds is not None and spec.equation == current.equation:
        try:
            return _parse_used({**mapping, "bounds": bounds})
        except UserError:
            pass  # a param the bounds need was removed: unbounded
    return spec


def parse_values(raw: Any, spec: Spec) -> dict[str, float]:
    values = dict(spec.params)
    for name, v in _mapping("values", raw if raw is not None else {}).items():
        if name in spec.params:  # a stale slider of a param that is gone is ignored
            values[name] = validate.number("values", str(name), v, *RANGES["value"])
    return values


def parse_ranges(raw: Any, spec: Spec, values: dict[str, float]) -> dict[str, tuple[float, float]]:
    """The page's slider ranges (Save YAML keeps them): for the shape's params, low below high, widened to hold the
    value; a range at whose ends a coefficient would not stay a finite double is left out."""
    out = {}
    for name, pair in _mapping("ranges", raw if raw is not None else {}).items():
        if name not in spec.params:
            continue
        if not isinstance(pair, list) or len(pair) != 2:
            raise UserError("ranges", f"{name}: expected [low, high]")
        lo, hi = (validate.number("ranges", str(name), v, *RANGES["value"]) for v in pair)
        value = values.get(name, spec.params[name])
        lo, hi = min(lo, value), max(hi, value)
        if not lo < hi:
            continue
        try:
            spec.check_values({name: lo}, "ranges", name)
            spec.check_values({name: hi}, "ranges", name)
        except UserError:
            continue
        out[name] = (lo, hi)
    return out


def parse_clip(data: dict) -> tuple[str, float]:
    """A scene object's clip: (kind, size)."""
    kind = data.get("clip")
    if kind not in CLIPS:
        raise UserError("clip", f"expected one of {', '.join(CLIPS)}")
    return kind, validate.number("clip", "size", data.get("size"), *RANGES["clip_size"])


def parse_orbit(raw: Any) -> Orbit:
    raw = _mapping("orbit", raw)
    o = Orbit()
    o.yaw = validate.number("orbit", "yaw", raw.get("yaw", o.yaw), *RANGES["yaw"]) % 360.0
    o.pitch = validate.number("orbit", "pitch", raw.get("pitch", o.pitch), *RANGES["pitch"])
    o.distance = validate.number("orbit", "distance", raw.get("distance", o.distance), *RANGES["distance"])
    o.target = validate.vector("orbit", "target", raw.get("target", list(o.target)), *RANGES["target"])
    o.fov = validate.number("orbit", "fov", raw.get("fov", o.fov), *RANGES["fov"])
    return o


def _choice(key: str, value: Any, allowed: tuple[str, ...]) -> str:
    if value not in allowed:
        raise UserError("options", f"{key}: expected one of {', '.join(allowed)}")
    return value


def parse_options(raw: Any) -> Options:
    raw = _mapping("options", raw)
    o = Options()
    o.clip = _choice("clip", raw.get("clip", o.clip), CLIPS)
    o.clip_size = validate.number("options", "clip_size", raw.get("clip_size", o.clip_size), *RANGES["clip_size"])
    cut = raw.get("cut", o.cut)
    if not isinstance(cut, bool):
        raise UserError("options", "cut: expected true or false")
    o.cut = cut
    o.color = validate.vector("options", "color", raw.get("color", list(o.color)), 0.0, 1.0)
    o.inside = validate.vector("options", "inside", raw.get("inside", list(o.inside)), 0.0, 1.0)
    o.lights = _choice("lights", raw.get("lights", o.lights), LIGHTS)
    o.background = validate.vector("options", "background", raw.get("background", list(o.background)), 0.0, 1.0)
    return o


def parse_render(data: dict, spec: Spec) -> RenderRequest:
    return RenderRequest(
        seq=validate.whole("render", "seq", data.get("seq", 0), 0, 2**31 - 1),
        refine=bool(data.get("refine", True)),
        width=validate.whole("render", "width", data.get("width", 640), 16, MAX_FRAME[0]),
        height=validate.whole("render", "height", data.get("height", 480), 16, MAX_FRAME[1]),
        values=parse_values(data.get("values"), spec),
        orbit=parse_orbit(data.get("orbit", {})),
        options=parse_options(data.get("options", {})),
        gpu=data.get("gpu", False) is True,
    )


@dataclass
class FixRequest:
    view: RenderRequest  # its seq, size and view (refine and gpu unused)
    part: int  # which of the rest's fix messages this is (sent back in the reply's header)
    pixels: list[int]  # y * width + x, each at most once


def parse_fix(data: dict, spec: Spec, most: int = MAX_FIX_PIXELS, parts: int = MAX_FIX_PARTS) -> FixRequest:
    """A `fix` message: the view (as a render request's), its part number (below `parts`) and at most `most`
    distinct pixels of its frame."""
    view = parse_render({**data, "refine": False, "gpu": True}, spec)
    part = validate.whole("fix", "part", data.get("part", 0), 0, parts - 1)
    raw = data.get("pixels")
    if not isinstance(raw, list) or not 0 < len(raw) <= most:
        raise UserError("fix", f"pixels: expected a list of 1 to {most} pixel numbers")
    last = view.width * view.height - 1
    pixels = [validate.whole("fix", "pixels", v, 0, last) for v in raw]
    if len(set(pixels)) != len(pixels):
        raise UserError("fix", "pixels: each pixel at most once")
    return FixRequest(view, part, pixels)


def parse_ask(data: dict, spec: Spec) -> tuple[int, dict[str, float]]:
    """A `glsl` message's number (sent back with the reply) and the picked leaf's param values."""
    ask = validate.whole("glsl", "ask", data.get("ask", 0), 0, 2**31 - 1)
    return ask, parse_values(data.get("values"), spec)


def parse_size(data: dict, what: str) -> tuple[int, int]:
    """The page's full frame size (Save YAML writes it as the scene's image)."""
    w = validate.whole(what, "width", data.get("width", 640), 16, MAX_FRAME[0])
    h = validate.whole(what, "height", data.get("height", 480), 16, MAX_FRAME[1])
    return w, h


def parse_pick(data: dict) -> tuple[float, float, int, int]:
    """A pixel of the page's full frame: (x, y, width, height)."""
    w, h = parse_size(data, "pick")
    x = validate.number("pick", "x", data.get("x"), 0.0, w - 1)
    y = validate.number("pick", "y", data.get("y"), 0.0, h - 1)
    return x, y, w, h


def parse_save(data: dict) -> tuple[int, int, int]:
    w = validate.whole("save_png", "width", data.get("width", 1920), 1, MAX_SAVE[0])
    h = validate.whole("save_png", "height", data.get("height", 1080), 1, MAX_SAVE[1])
    if w * h > MAX_SAVE_PIXELS:
        k = math.sqrt(MAX_SAVE_PIXELS / (w * h))  # the same shape, within the bound
        raise UserError(
            "save_png",
            f"{w} × {h} is {w * h:,} pixels, more than the {MAX_SAVE_PIXELS:,} (8192 × 4608) a saved picture may "
            f"have: {int(w * k)} × {int(h * k)} would do",
        )
    spp = validate.whole("save_png", "spp", data.get("spp", 16), 1, MAX_SAVE_SPP)
    return w, h, spp


def parse_save_mesh(data: dict, spec: Spec) -> tuple[int, dict[str, float], Options]:
    """Save mesh: (cells along the longest side, the param values, the options: their clip) as the page shows them."""
    cells = validate.whole("save_mesh", "cells", data.get("cells", 128), MIN_CELLS, MAX_CELLS)
    return cells, parse_values(data.get("values"), spec), parse_options(data.get("options", {}))
