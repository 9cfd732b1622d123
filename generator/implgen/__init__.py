"""implgen: implicit surfaces f(x, y, z) = 0 turned into C and Python ray intersectors, and a C ray tracer.

The public Python API, stated once here (each name is imported from its module on first use, so
`import implgen` stays cheap):

    from implgen import load_spec, parse_spec, generate, derive      # spec -> generated code
    from implgen import real_roots, first_root                      # the C root solvers
    from implgen import load_scene, parse_scene, render, write_png   # scenes -> pictures
    from implgen import show                                         # a surface or scene in a notebook
    from implgen import UserError                                    # every bad input raises this
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

_API: dict[str, str] = {
    "Spec": "implgen.spec.model",
    "load_spec": "implgen.spec.entry",
    "parse_spec": "implgen.spec.entry",
    "derive": "implgen.codegen.derive",
    "generate": "implgen.codegen.emit",
    "real_roots": "implgen.roots.solvers",
    "first_root": "implgen.roots.solvers",
    "real_roots_batch": "implgen.roots.solvers",
    "first_root_batch": "implgen.roots.solvers",
    "Scene": "implgen.scene.model",
    "load_scene": "implgen.scene.load",
    "parse_scene": "implgen.scene.load",
    "render": "implgen.scene.render",
    "RenderInfo": "implgen.scene.render",
    "write_png": "implgen.imagefile",
    "show": "implgen.notebook.widget",
    "UserError": "implgen.errors",
}
__all__ = sorted(_API)


def __getattr__(name: str) -> Any:
    if name not in _API:
        raise AttributeError(f"module 'implgen' has no attribute {name!r}")
    value = getattr(importlib.import_module(_API[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_API])
