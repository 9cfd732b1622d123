"""A whole GLSL program from plain strings: version line, precision, the runtime, the shapes, the caller's code.

A generated `<name>.glsl` has no #version line, so one file serves WebGL2 (GLSL ES 3.00) and desktop GLSL
4.50. A page does the same concatenation in JavaScript: the strings below, in this order (docs/glsl.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

from implgen.resources import GLSL_RUNTIME_SOURCES, runtime_glsl_dir

HEADERS = {
    "es": "#version 300 es\nprecision highp float;\nprecision highp int;\n",
    "450": "#version 450\n",
}


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
