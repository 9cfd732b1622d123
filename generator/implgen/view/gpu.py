"""What the page's GPU preview needs (docs/viewer.md, "The GPU preview"): whether the GLSL target can draw the
document's picture, and if so the generated GLSL of the current parsed shape.

The page draws the live picture itself with WebGL2 (static/gpu.js, on the shared page's renderer
share/static/surface.js) while the view moves, and the server's double-precision frame replaces it at rest.
The page gets, once in its hello message, the GLSL ES header, the GLSL runtime, the light presets and the
material (`hello_part`); then, after every accepted shape, a `glsl` message (`program_message`): the shape's
generated GLSL, or why the server draws every frame. Everything sent is generated from the parsed spec; no
text the user typed is in it but through the GLSL printer.

The derivation runs on the viewer's glsl pool, beside the parse pool, under the GLSL budget (view/work.py):
past the budget the GLSL evaluates f's tree as written and the message's `note` says so.

The GLSL page main draws one shape, inside the viewer's clip (cut open or as a cut solid), with the viewer's
lights, material and shadows. A scene file (CSG, glass, mirrors, several objects, transforms, its own lights)
gets the scene's whole program instead (`scene_message`: the GLSL scene tracer, share/scenegpu.py, generated
from the scene the tracer would draw, its param values folded in), its lights and background left to the
page's uniforms: the page sets the scene's lights or a preset's and its background, and asks again when a
leaf's equation, values or clip change. Past the GLSL budget a scene is the server's, and the message says so.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Awaitable, Callable

import numpy as np

from implgen.codegen.backends.glsl import chebform
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.backends.glsl.scene import scene_program
from implgen.codegen.emit import generate
from implgen.errors import UserError
from implgen.scene.model import Csg, Leaf, Node
from implgen.share.page import MATERIAL
from implgen.share.scenegpu import scene_tables
from implgen.spec.model import Spec
from implgen.view.document import LIGHT_PRESETS, Document
from implgen.view.protocol import MAX_FIX_PARTS, MAX_FIX_PIXELS

log = logging.getLogger("implgen.view")
PRESET_LIGHTS = max(len(v) for v in LIGHT_PRESETS.values())  # a scene program's light slots: the most a preset has


def hello_part() -> dict:
    """What every page gets once: the pieces of a GLSL program that do not depend on the shape."""
    presets = {
        k: [{**light, "at": list(light["at"]), "colour": list(light["colour"])} for light in v]
        for k, v in LIGHT_PRESETS.items()
    }
    fixes = {"pixels": MAX_FIX_PIXELS, "parts": MAX_FIX_PARTS}  # a GPU-drawn scene's rest: what it may ask
    return {
        "header": HEADERS["es"],
        "runtime": runtime_text(),
        "lights": presets,
        "material": dict(MATERIAL),
        "fix": fixes,
    }


def _what(node: Node, found: set[str]) -> None:
    if isinstance(node, Csg):
        found.add("CSG")
        _what(node.left, found)
        _what(node.right, found)
        return
    assert isinstance(node, Leaf)
    m = node.material
    if m is not None:
        if m.transparency > 0:
            found.add("glass")
        if m.reflectivity > 0:
            found.add("mirrors")
        if m.checker_scale > 0:
            found.add("a checker")


def scene_what(doc: Document) -> str:
    """What a scene file holds, in words: its shapes, CSG, glass, mirrors, a checker."""
    found: set[str] = set()
    for obj in doc.base.objects:
        _what(obj, found)
    parts = []
    if len(doc.base.leaves()) > 1:
        parts.append(f"{len(doc.base.leaves())} shapes")
    parts += sorted(found)
    return ", ".join(parts) if parts else "its own lights, materials and transforms"


def budget_note(held: chebform.Budget) -> str | None:
    """What the page says when a GLSL derivation's budget ran out before its Chebyshev step ended, else None."""
    if not held.cut:
        return None
    if held.seconds is None or (held.stop is not None and held.stop.is_set()):
        return "the GLSL evaluates f as written: its Chebyshev form was stopped"
    return (
        f"the GLSL evaluates f as written: its Chebyshev form was not done within the {held.seconds:g} s GLSL "
        "budget (IMPLGEN_VIEW_GLSL_BUDGET)"
    )


def shape_glsl(spec: Spec, budget: float | None = None, stop: threading.Event | None = None) -> tuple[str, str | None]:
    """(the shape's generated GLSL, the page's note or None): with `budget` seconds (None: as long as it takes), a
    Chebyshev step past them or past `stop` is cut and the GLSL evaluates f's tree as written."""
    with chebform.budget(budget, stop) as held:
        shape = generate(spec, ("glsl",))[f"{spec.name}.glsl"]
    return shape, budget_note(held)


def scene_key(doc: Document) -> tuple:
    """What a scene document's program depends on: each leaf's spec, values, map and clip (equal keys, equal
    programs; the camera, lights and background are uniforms)."""
    leaves = doc.scene(16, 16, 1).leaves()
    return tuple(
        (id(leaf.spec), tuple(sorted(leaf.params.items())), np.asarray(leaf.matrix).tobytes(), leaf.clip)
        for leaf in leaves
    )


def scene_message(doc: Document, budget: float | None = None, stop: threading.Event | None = None) -> dict:
    """The `glsl` message of a scene file's document: its whole program (the shapes' derivation under the GLSL
    budget: past it, why the server draws) with light slots for the file's lights or a preset's, and the file's
    lights."""
    name = doc.scene_name()
    try:
        with chebform.budget(budget, stop) as held:
            tables = scene_tables(doc.scene(16, 16, 1))
    except UserError as err:
        return {"type": "glsl", "name": name, "reason": f"the GLSL target cannot draw this scene: {err.message}"}
    except Exception:  # a bug in the GLSL backend: the server's path still draws; the log says why
        log.exception("GLSL scene generation failed")
        return {"type": "glsl", "name": name, "reason": "the GLSL target failed on this scene"}
    if held.cut:
        seconds = "" if held.seconds is None else f" within the {held.seconds:g} s GLSL budget"
        why = f"the scene's GLSL was not done{seconds} (IMPLGEN_VIEW_GLSL_BUDGET): the server draws"
        return {"type": "glsl", "name": name, "reason": why}
    lights = doc.base.lights
    slots = max(1, PRESET_LIGHTS, len(lights))
    header = HEADERS["es"]
    program = scene_program(tables, "es", live_lights=slots)
    scene = {
        "header": header,
        "program": program[len(header) :],
        "slots": slots,
        "lights": [{"position": list(li.position), "colour": list(li.color)} for li in lights],
        "objects": len(tables.objects),
        "shapes": len(tables.shapes),
        "what": scene_what(doc),
    }
    return {"type": "glsl", "name": name, "scene": scene}


class LastScene:
    """The `glsl` messages of a page: a shape's derived each time; the scene program sent last kept by its
    scene_key, and an ask whose program would not differ answered from it."""

    def __init__(self) -> None:
        self.key: tuple | None = None
        self.msg: dict | None = None

    async def message(self, doc: Document, derive: Callable[..., Awaitable[dict]], ask: int | None) -> dict:
        """The `glsl` message of a document (derive(program_message, doc)); a scene's carries `ask` and is
        derived only when its key changed."""
        if doc.base is None:
            return await derive(program_message, doc)
        key = scene_key(doc)
        if key != self.key or self.msg is None:
            self.msg, self.key = await derive(program_message, doc), key
        return {**self.msg, "ask": ask}


def program_message(doc: Document, budget: float | None = None, stop: threading.Event | None = None) -> dict:
    """The `glsl` message for the document's current shape (on the glsl pool, Work.derive_glsl: the derivation is
    SymPy), its Chebyshev step within `budget` seconds (None: unbounded); a `note` says when that cut it. A scene
    file's document gets its scene's program (`scene_message`)."""
    if doc.base is not None:
        return scene_message(doc, budget, stop)
    spec = doc.spec
    try:
        shape, note = shape_glsl(spec, budget, stop)
    except UserError as err:
        reason = f"the GLSL target cannot draw this shape: {err.message}"
    except Exception:  # a bug in the GLSL backend: the server's path still draws; the log says why
        log.exception("GLSL generation failed")
        reason = "the GLSL target failed on this shape"
    else:
        prefix = glsl_name(spec.name)  # of the shape's GLSL identifiers
        msg = {"type": "glsl", "name": spec.name, "glsl_name": prefix, "shape": shape, "params": list(spec.params)}
        return {**msg, "note": note} if note else msg
    return {"type": "glsl", "name": spec.name, "reason": reason}
