"""Where the package data (templates, C and GLSL runtime sources, the gallery's shape specs) lives once
installed, and which runtime sources make which library.

The lists are explicit: a scene library links the solvers, the shape layer and the tracer -- never the
benchmark timing code, which only the solver library behind `implgen.roots` carries. A test checks that every
C file in runtime_c/ is in exactly one list.
"""

from __future__ import annotations

from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent
_TREE = _PACKAGE_DIR.parent.parent  # the repository, when run from the source tree (generator/implgen/)

SOLVER_SOURCES = (
    "roots.c",
    "roots_common.c",
    "roots_refine.c",
    "roots_closed.c",
    "roots_sturm.c",
    "roots_bracket.c",
    "roots_bernstein.c",
)
BENCH_SOURCES = ("roots_bench.c",)  # clock_gettime around every solve: `implgen bench solvers`
SHAPE_SOURCES = ("shape.c", "shape_batch.c")
MESH_SOURCES = ("mesh_kernels.c",)  # the mesh's dual vertices and triangles: plain arrays, no shape
TRACER_SOURCES = (
    "tracer_scene.c",
    "tracer_hit.c",
    "tracer_csg.c",
    "tracer_shade.c",
    "tracer_render.c",
    "tracer_floor.c",
    "certify.c",  # the certify pass (docs/certify.md): runs only when asked for
    "certify_poly.c",
)
# The Embree 3 adapter (docs/embree.md): in no library implgen builds, so nothing here needs Embree; compiled by
# whoever links Embree (examples/embree/, tests/test_embree.py, bench/embree.py)
EMBREE_SOURCES = ("embree_shape.c",)
# The GLSL runtime, in the order a program concatenates it (before the generated shapes: docs/glsl.md)
GLSL_RUNTIME_SOURCES = ("raa.glsl", "clip.glsl", "ray.glsl", "camera.glsl", "shade.glsl")


def templates_dir() -> Path:
    """Folder holding the Jinja2 templates (`c/`, `python/`, `scene/`)."""
    return _PACKAGE_DIR / "templates" if (_PACKAGE_DIR / "templates").is_dir() else _TREE / "templates"


def runtime_dir() -> Path:
    """Folder holding the hand-written C runtime sources (`*.c`, `*.h`)."""
    return _PACKAGE_DIR / "runtime_c" if (_PACKAGE_DIR / "runtime_c").is_dir() else _TREE / "runtime_c"


def runtime_glsl_dir() -> Path:
    """Folder holding the hand-written GLSL runtime (`*.glsl`, concatenated in GLSL_RUNTIME_SOURCES order)."""
    return _PACKAGE_DIR / "runtime_glsl" if (_PACKAGE_DIR / "runtime_glsl").is_dir() else _TREE / "runtime_glsl"


def gallery_dir() -> Path:
    """Folder holding the gallery's shape specs: the repository's examples/shapes/, installed as
    `implgen.gallery` (one copy: pyproject maps the folder into the package)."""
    installed = _PACKAGE_DIR / "gallery"
    return installed if installed.is_dir() else _TREE / "examples" / "shapes"


def surface_js() -> Path:
    """The WebGL2 drawing code (`IgSurface`): the shared page's and the viewer's renderer, and the compile step of
    the GLSL browser harness (implgen.measure.webgl). Package data of implgen.share."""
    return _PACKAGE_DIR / "share" / "static" / "surface.js"


def runtime_sources(*groups: tuple[str, ...]) -> list[Path]:
    """Paths of the runtime sources in the given groups (e.g. SOLVER_SOURCES, SHAPE_SOURCES), in order."""
    return [runtime_dir() / name for group in groups for name in group]
