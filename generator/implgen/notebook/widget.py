"""`implgen.show(spec_or_equation, **params)`: an anywidget drawing a surface with the shared page's renderer (the
generated GLSL, in the browser), orbit and zoom, a slider per param; or a scene, as frames from the kernel's C
tracer. Without WebGL2 in the browser the view says so and the kernel renders the pictures in double instead.
`_repr_png_` renders the kernel's picture too, so a saved or converted notebook still shows it.

The view's code is share/static/surface.js and orbit.js (the shared page's renderer, one copy) followed by
static/widget.js. What the kernel sends it is data in traitlets: the shape's GLSL as generated, the runtime,
the sliders, the orbit; the frames as PNG bytes.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import Any

from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import HEADERS, runtime_text
from implgen.codegen.emit import generate
from implgen.errors import UserError
from implgen.notebook import picture
from implgen.notebook.source import WHERE, Shown, read
from implgen.share.page import MATERIAL, framing, slider, static_text

STATIC = Path(__file__).resolve().parent / "static"
SIZE = (480, 360)  # the widget's drawing, in CSS pixels


@cache
def esm() -> str:
    """The view's module: the shared page's renderer and orbit, then the widget's own code."""
    return "\n".join([static_text("surface.js"), static_text("orbit.js"), (STATIC / "widget.js").read_text()])


def _anywidget():
    try:
        import anywidget
        import traitlets
    except ImportError:
        raise UserError(WHERE, "needs anywidget: pip install 'implgen[notebook]'") from None
    return anywidget, traitlets


def _shape_data(shown: Shown) -> tuple[dict, dict, float]:
    """The GPU's data (as the shared page's JSON block), the orbit, and the clip sphere's radius."""
    spec = shown.spec
    sliders = [slider(name, shown.values[name], spec.ranges) for name in spec.params]
    orbit, clip_size = framing(spec, shown.values)
    data = {
        "name": spec.name,
        "glsl_name": glsl_name(spec.name),
        "shape": generate(spec, ("glsl",))[f"{spec.name}.glsl"],
        "runtime": runtime_text(),
        "header": HEADERS["es"],
        "params": [{"name": s.name, "value": s.value, "min": s.lo, "max": s.hi} for s in sliders],
        "clip": {"kind": "sphere", "size": clip_size, "cut": False},
        "material": MATERIAL,
    }
    return data, orbit, clip_size


@cache
def widget_class():
    anywidget, traitlets = _anywidget()

    class Surface(anywidget.AnyWidget):
        """A surface or a scene; `mode` "gpu" draws in the browser, "frames" shows the kernel's pictures."""

        _esm = esm()
        mode = traitlets.Unicode("gpu").tag(sync=True)
        data = traitlets.Dict().tag(sync=True)
        values = traitlets.List(traitlets.Float()).tag(sync=True)
        orbit = traitlets.Dict().tag(sync=True)
        width = traitlets.Int(SIZE[0]).tag(sync=True)
        height = traitlets.Int(SIZE[1]).tag(sync=True)
        frame = traitlets.Bytes(b"").tag(sync=True)  # PNG: the kernel's picture, in "frames" mode
        webgl = traitlets.Unicode("").tag(sync=True)  # what the browser said: "" not yet, "yes", or why not
        error = traitlets.Unicode("").tag(sync=True)

        def __init__(self, shown: Shown, **kwargs: Any) -> None:
            self._shown = shown
            self._clip_size = 3.0
            if shown.scene is not None:
                self._camera = shown.scene.camera  # the scene's own, shown until the orbit moves
                self._home = picture.orbit_of(self._camera)
                super().__init__(mode="frames", orbit=self._home, **kwargs)
            else:
                data, orbit, self._clip_size = _shape_data(shown)
                values = [shown.values[n] for n in shown.spec.params]
                super().__init__(mode="gpu", data=data, orbit=orbit, values=values, **kwargs)
            if self.mode == "frames":
                self.frame = self.picture()
            self.observe(self._changed, names=["values", "orbit", "webgl", "width", "height"])

        def _changed(self, change) -> None:
            if change["name"] == "webgl" and change["new"] not in ("", "yes"):
                self.mode = "frames"  # no WebGL2 in this browser: the kernel draws
            if self.mode == "frames":
                self.frame = self.picture()

        def picture(self) -> bytes:
            """The kernel's picture (PNG) of what the widget shows now, in double."""
            size = (self.width, self.height)
            shown = self._shown
            if shown.scene is not None:
                moved = self.orbit != self._home
                shown.scene.camera = picture.orbit_camera(self.orbit) if moved else self._camera
                return picture.png(shown.scene, size)
            values = dict(zip(shown.spec.params, self.values))
            return picture.png(picture.surface_scene(shown.spec, values, self.orbit, self._clip_size, size))

        def _repr_png_(self) -> bytes:
            return self.picture()

    return Surface


def show(spec_or_equation: str | Path, **params: float):
    """A widget drawing a spec file (a Path, or text ending in .yaml), a scene file, or an equation in x, y, z
    whose params are given as keywords: `implgen.show("x^2 + y^2 + z^2 - r^2", r=1)`. Bad input raises
    UserError, one line."""
    widget = widget_class()  # first: without anywidget, say so before any parsing
    return widget(read(spec_or_equation, params))
