"""`implgen share SCENE.yaml`'s page: the whole scene drawn by the browser's WebGL2 with the GLSL scene tracer
(share/scenegpu.py), turned and zoomed by the orbit camera, from disk, with no server and no network.

Built as the shape's page is (share/page.py): one HTML file from a Jinja2 template with autoescaping, the
scripts inserted as they are and allowed by their hashes in the page's Content-Security-Policy, the data in a
JSON block escaped for a <script>. The scene's name on the page is its file's name, shown as text.
"""

from __future__ import annotations

import math

import numpy as np

from implgen import __version__
from implgen.codegen.backends.glsl.program import HEADERS
from implgen.codegen.backends.glsl.scene import scene_program
from implgen.scene.model import Scene
from implgen.share.page import _csp, _environment, script_json, static_text
from implgen.share.scenegpu import scene_tables

SCRIPTS = ("surface.js", "orbit.js", "scenerender.js", "scene.js")  # in this order: each uses those before it


def scene_orbit(scene: Scene) -> dict:
    """The orbit (yaw about +y, pitch, distance, target, fov: share/static/orbit.js) that starts at the scene's
    camera; the orbit keeps +y up."""
    cam = scene.camera
    target = np.asarray(cam.look_at, float)
    v = np.asarray(cam.position, float) - target
    distance = float(np.sqrt(v @ v)) or 1.0
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, v[1] / distance))))
    yaw = math.degrees(math.atan2(v[0], v[2]))
    return {
        "yaw": yaw,
        "pitch": max(-89.0, min(89.0, pitch)),
        "distance": distance,
        "target": list(target),
        "fov": float(cam.fov),
    }


def render_scene_page(scene: Scene, source_name: str) -> str:
    """The scene's page as text."""
    tables = scene_tables(scene)
    program = scene_program(tables, "es")
    header = HEADERS["es"]
    data = {"header": header, "program": program[len(header) :], "orbit": scene_orbit(scene)}
    scripts = [static_text(name) for name in SCRIPTS]
    css = static_text("page.css")
    return (
        _environment()
        .get_template("scene_page.html.j2")
        .render(
            version=__version__,
            csp=_csp(scripts, css),
            name=source_name,
            objects=len(tables.objects),
            shapes=len(tables.shapes),
            lights=len(tables.lights),
            depth=tables.max_depth,
            source=source_name,
            css=css,
            data=script_json(data),
            scripts=scripts,
        )
    )
