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
is the server's: the message says which of these it has.
"""

from __future__ import annotations

import logging
import threading

from implgen.codegen.backends.glsl import chebform
from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.emit import generate
from implgen.errors import UserError
from implgen.scene.model import Csg, Leaf, Node
from implgen.share.page import MATERIAL
from implgen.spec.model import Spec
from implgen.view.document import LIGHT_PRESETS, Document

log = logging.getLogger("implgen.view")


def hello_part() -> dict:
    """What every page gets once: the pieces of a GLSL program that do not depend on the shape."""
    presets = {
        k: [{**light, "at": list(light["at"]), "colour": list(light["colour"])} for light in v]
        for k, v in LIGHT_PRESETS.items()
    }
    return {"header": HEADERS["es"], "runtime": runtime_text(), "lights": presets, "material": dict(MATERIAL)}


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


def server_only(doc: Document) -> str | None:
    """Why the GLSL page main cannot draw this document's picture, or None when it can."""
    if doc.base is None:
        return None
    found: set[str] = set()
    for obj in doc.base.objects:
        _what(obj, found)
    parts = []
    if len(doc.base.leaves()) > 1:
        parts.append(f"{len(doc.base.leaves())} shapes")
    parts += sorted(found)
    what = ", ".join(parts) if parts else "its own lights, materials and transforms"
    return f"a scene file ({what}): the GLSL page draws one shape alone"


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


def program_message(doc: Document, budget: float | None = None, stop: threading.Event | None = None) -> dict:
    """The `glsl` message for the document's current shape (on the glsl pool, Work.derive_glsl: the derivation is
    SymPy), its Chebyshev step within `budget` seconds (None: unbounded); a `note` says when that cut it."""
    spec = doc.spec
    reason = server_only(doc)
    if reason is None:
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
