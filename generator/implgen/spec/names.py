"""Names from a spec become C and Python identifiers: which ones are allowed.

A shape's name names its files (`<name>.c`, `.h`, `.py`) and its C symbols (`<name>_coeffs`, ...,
`<NAME>_DEGREE`); a param's name becomes `k_<name>` inside generated code. Both must be identifiers that are
not keywords, and a shape name must not collide with anything it shares a compiler, a linker or an import
with: the runtime's and the scene glue's names, the C headers on the include path, and Python's modules (a
generated `<name>.py` in a folder a script runs from is imported instead of the module of that name).
tests/test_codegen_hostile.py checks this against every symbol of a built scene library,
the headers generated code includes, the system headers' macros and libc/libm's exports.
"""

from __future__ import annotations

import keyword
import re
import sys
from typing import Any

from implgen import validate
from implgen.errors import UserError
from implgen.resources import runtime_dir

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}\Z")
# Words that cannot be names in the generated C or Python.
_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile "
    "while _Bool _Complex _Imaginary".split()
)
_RESERVED_SHAPE_NAMES = frozenset({"implgen", "roots", "shape", "raycast", "numpy", "math", "ig", "rt"})
# Names the C runtime and the scene glue own (functions, types, macros): a shape called `rt_scene` would
# define `rt_scene_shape`, which the glue defines too. Compared lower-cased: `<NAME>_DEGREE` is a macro.
_RESERVED_SHAPE_PREFIXES = ("ig_", "rt_", "implgen")
# Headers: `<name>.h` sits in a folder on the compiler's include path, so a shape called `math` would stand
# in for <math.h>. Every C99 header, the POSIX ones the runtime includes, and the runtime's own.
_C_HEADERS = frozenset(
    "assert complex ctype errno fenv float inttypes iso646 limits locale math setjmp signal stdarg stdbool "
    "stddef stdint stdio stdlib string tgmath time wchar wctype pthread unistd sched".split()
)

# Modules: `<name>.py` lands in the output folder, and Python imports from a script's own folder first, so a
# shape called `inspect`, `json` or `ctypes` would stand in for the module numpy or implgen imports. Every module
# of the standard library of the Python running implgen, and the top-level packages of implgen's dependencies
# (pyproject.toml's `dependencies`; tests/test_codegen_hostile.py checks the list against them).
DEPENDENCY_MODULES = frozenset(
    "numpy sympy isympy jinja2 yaml PIL matplotlib mpl_toolkits pylab tqdm dask distributed imageio imageio_ffmpeg "
    "starlette uvicorn websockets trimesh".split()
)
_PYTHON_MODULES = frozenset(m.lower() for m in sys.stdlib_module_names | DEPENDENCY_MODULES)


def check_identifier(source: str, key: str, name: Any) -> str:
    if not isinstance(name, str) or not _IDENT.match(name):
        raise UserError(
            source,
            f"{key}: {validate.describe(name)} is not an identifier (a letter, then letters, digits or _, at most 64)",
        )
    if keyword.iskeyword(name) or name in _C_KEYWORDS:
        raise UserError(source, f"{key}: {name!r} is a reserved word in C or Python")
    return name


def reserved_shape_name(name: str) -> str | None:
    """Why `name` cannot name a shape (it would collide with the runtime, a header or a module), or None."""
    low = name.lower()
    if low in _RESERVED_SHAPE_NAMES or low.startswith(_RESERVED_SHAPE_PREFIXES):
        return "is reserved by implgen (the C runtime's names start ig_, rt_, implgen)"
    if low in _C_HEADERS or low in {h.stem.lower() for h in runtime_dir().glob("*.h")}:
        return "is the name of a C header the generated code includes"
    if low in _PYTHON_MODULES:
        return "is the name of a Python module (the generated .py file would be imported in its place)"
    return None


def check_shape_name(source: str, key: str, name: Any) -> str:
    """A shape name: an identifier that no runtime symbol, header or module can collide with."""
    check_identifier(source, key, name)
    why = reserved_shape_name(name)
    if why:
        raise UserError(source, f"{key}: {name!r} {why}")
    return name
