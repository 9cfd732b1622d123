"""A whole GLSL program from plain strings: version line, precision, the runtime, the shapes, the caller's code.

A generated `<name>.glsl` has no #version line, so one file serves WebGL2 (GLSL ES 3.00) and desktop GLSL
4.50. A page does the same concatenation in JavaScript: the strings below, in this order (docs/glsl.md).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from functools import lru_cache

from implgen.resources import GLSL_RUNTIME_SOURCES, runtime_glsl_dir

HEADERS = {
    "es": "#version 300 es\nprecision highp float;\nprecision highp int;\n",
    "450": "#version 450\n",
}
# A shape's functions are <prefix>_value, ... (templates/glsl/shape.glsl.j2; the prefix: backends/glsl/printer.py
# glsl_name). A main written once for any shape calls them as IG_SHAPE_VALUE, ..., IG_SHAPE_HIT: #defines of
# the program's one shape's (shape_defines), never text put into the main.
SHAPE_FUNCTIONS = ("value", "gradient", "normal", "bounds", "raa", "hit")
# what glsl_name gives: letters and digits in runs joined by single underscores, not gl_ or webgl_ first
_PREFIX = re.compile(r"(?!gl_|webgl_)[A-Za-z][A-Za-z0-9]*(?:_[A-Za-z0-9]+)*\Z", re.IGNORECASE)


@lru_cache(maxsize=1)
def runtime_text() -> str:
    """The GLSL runtime, its files concatenated in GLSL_RUNTIME_SOURCES order."""
    folder = runtime_glsl_dir()
    return "".join((folder / name).read_text(encoding="ascii") + "\n" for name in GLSL_RUNTIME_SOURCES)


def program(shapes: Sequence[str], main: str, target: str = "es", defines: dict[str, str] | None = None) -> str:
    """Version header, `#define`s (e.g. IG_MAX_DEPTH), the runtime, the shapes' texts, then `main`."""
    if target not in HEADERS:
        raise ValueError(f"target must be one of {sorted(HEADERS)}, not {target!r}")
    lines = [HEADERS[target]]
    lines += [f"#define {k} {v}\n" for k, v in (defines or {}).items()]
    return "".join(lines) + runtime_text() + "".join(s + "\n" for s in shapes) + main


def shape_defines(prefix: str) -> dict[str, str]:
    """IG_SHAPE_VALUE, ..., IG_SHAPE_HIT as the functions of the shape whose identifiers start `prefix`."""
    if not _PREFIX.match(prefix):
        raise ValueError(f"not the prefix of a shape's GLSL identifiers: {prefix!r}")
    return {f"IG_SHAPE_{s.upper()}": f"{prefix}_{s}" for s in SHAPE_FUNCTIONS}
