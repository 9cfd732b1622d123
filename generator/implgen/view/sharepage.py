"""The viewer's "Export page": the view as the stand-alone page of `implgen share` (share/page.py), with the
shape, its param values, the camera, the clip and the colours the page shows now.

Sliders run over the page's own ranges (the user's, sent with the request), else the spec's `ranges`, else the
range spec/paramrange.py finds: the ones the viewer's sliders show.
A clip the shared page cannot draw (a scene file's own) falls back to its sphere.
"""

from __future__ import annotations

import threading
from dataclasses import asdict

from implgen.codegen.backends.glsl import chebform
from implgen.share.page import CLIPS, Look, render_page, slider
from implgen.spec.paramrange import param_ranges
from implgen.view import gpu
from implgen.view.document import Document


def page_text(
    doc: Document, budget: float | None = None, stop: threading.Event | None = None
) -> tuple[str, str, str | None]:
    """(file name, the page's HTML, a note for the viewer's page or None) for the document's current view; its GLSL
    derived under `budget` seconds (None: unbounded) as the GPU preview's is (gpu.shape_glsl)."""
    spec, o = doc.spec, doc.options
    ranges = {**param_ranges(spec), **doc.ranges}
    sliders = [slider(name, float(doc.values.get(name, default)), ranges) for name, default in spec.params.items()]
    clip = o.clip if o.clip in CLIPS else "sphere"
    look = Look(clip=clip, clip_size=o.clip_size, cut=o.cut, outside=o.color, inside=o.inside, background=o.background)
    orbit = asdict(doc.orbit)
    orbit["target"] = list(orbit["target"])
    with chebform.budget(budget, stop) as held:
        html = render_page(spec, sliders, look, f"implgen view: {spec.name}", orbit)
    note = gpu.budget_note(held)
    return f"{spec.name}.html", html, f"the exported page's shader: {note}" if note else None
