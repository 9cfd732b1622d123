"""The viewer's "Export page": the view as the stand-alone page of `implgen share` (share/page.py), with the
shape, its param values, the camera, the clip and the colours the page shows now.

Sliders run over the spec's `ranges` where it names them, else the value +- max(1, |value|) as on the page.
A clip the shared page cannot draw (a scene file's own) falls back to its sphere.
"""

from __future__ import annotations

from dataclasses import asdict

from implgen.share.page import CLIPS, Look, render_page, slider
from implgen.view.document import Document


def page_text(doc: Document) -> tuple[str, str]:
    """(file name, the page's HTML) for the document's current view."""
    spec, o = doc.spec, doc.options
    sliders = [slider(name, float(doc.values.get(name, default)), spec.ranges) for name, default in spec.params.items()]
    clip = o.clip if o.clip in CLIPS else "sphere"
    look = Look(clip=clip, clip_size=o.clip_size, cut=o.cut, outside=o.color, inside=o.inside, background=o.background)
    orbit = asdict(doc.orbit)
    orbit["target"] = list(orbit["target"])
    return f"{spec.name}.html", render_page(spec, sliders, look, f"implgen view: {spec.name}", orbit)
