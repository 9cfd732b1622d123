"""What the C runtime and the Python side share, read from the runtime's headers: nothing is copied by hand.

- every integer `#define` and enum value named IG_* or RT_* in `runtime_c/*.h` (limits such as IG_MAX_DEGREE
  and RT_MAX_CSG_DEPTH, root-method ids, CSG node kinds, ray-count slots);
- the field layout of `rt_material` (the packed doubles a material travels as) and of `rt_hit` (a ctypes
  Structure built from the header's field list).

The headers are small and read once, on first use. tests/test_abi.py compiles a probe against the same
headers that prints sizeof, offsetof and the values the compiler sees, and compares them with this module.

One shared fact is a figure in C code rather than a define: how much `ig_shape_prepare` (runtime_c/shape.c) grows
a shape's box before it clips a ray to it. grown_box() is its one Python statement (the NumPy ray caster, the
exact judge, the POV-Ray export's clip); tests/test_abi.py runs ig_shape_prepare on boxes and requires the same
doubles, bit for bit.
"""

from __future__ import annotations

import ctypes
import re
from functools import cache, lru_cache

import numpy as np

from implgen.resources import runtime_dir

_DEFINE = re.compile(r"^\s*#define\s+((?:IG|RT)_[A-Z0-9_]+)\s+\(?(-?\d+)\)?\s*(?:/\*.*)?$", re.M)
_ENUM = re.compile(r"\benum\b[^{;]*\{([^}]*)\}", re.S)
_ENUM_ITEM = re.compile(r"\b((?:IG|RT)_[A-Z0-9_]+)\s*=\s*(-?\d+)")
_COMMENT = re.compile(r"/\*.*?\*/", re.S)
_CTYPES = {"double": ctypes.c_double, "int": ctypes.c_int}


def _headers_text() -> str:
    return "\n".join(p.read_text() for p in sorted(runtime_dir().glob("*.h")))


@lru_cache(maxsize=1)
def constants() -> dict[str, int]:
    """{name: value} of every IG_*/RT_* integer define and enum value in the runtime headers."""
    text = _headers_text()
    found: dict[str, int] = {name: int(v) for name, v in _DEFINE.findall(text)}
    for body in _ENUM.findall(_COMMENT.sub(" ", text)):
        found.update({name: int(v) for name, v in _ENUM_ITEM.findall(body)})
    return found


def value(name: str) -> int:
    return constants()[name]


@cache
def struct_fields(struct: str) -> tuple[tuple[str, str, int], ...]:
    """(name, C type, count) of each field of `typedef struct <struct> { ... }` in the headers, in order."""
    text = _COMMENT.sub(" ", _headers_text())
    m = re.search(rf"typedef\s+struct\s+{struct}\s*\{{(.*?)\}}\s*{struct}\s*;", text, re.S)
    if m is None:
        raise LookupError(f"struct {struct} not found in the runtime headers")
    fields = []
    for decl in m.group(1).split(";"):
        decl = decl.strip()
        if not decl:
            continue
        ctype, rest = decl.split(None, 1)
        for item in rest.split(","):
            name, _, count = item.strip().partition("[")
            fields.append((name.strip(), ctype, int(count.rstrip("]")) if count else 1))
    return tuple(fields)


@cache
def ctypes_struct(struct: str) -> type[ctypes.Structure]:
    """A ctypes mirror of a header struct made of double and int fields (arrays allowed)."""
    fields = [
        (name, _CTYPES[ctype] * count if count > 1 else _CTYPES[ctype]) for name, ctype, count in struct_fields(struct)
    ]
    return type(struct, (ctypes.Structure,), {"_fields_": fields})


def material_fields() -> tuple[tuple[str, int], ...]:
    """(field, number of doubles) of rt_material, in the order a packed material lists them."""
    fields = struct_fields("rt_material")
    assert all(ctype == "double" for _, ctype, _ in fields), "rt_material travels as packed doubles"
    return tuple((name, count) for name, _, count in fields)


BOX_GROWTH = 1e-9  # of a box's finite extent: a surface that touches its own box keeps the root there


def grown_box(box) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi), each per axis, of a box {xmin, ymin, zmin, xmax, ymax, zmax} (a bound may be +-inf) grown as
    ig_shape_prepare grows it: each side by BOX_GROWTH times the larger finite |bound| of its axis."""
    box = np.asarray(box, dtype=float)
    lo, hi = box[:3], box[3:]
    scale = np.maximum(np.where(np.isfinite(lo), np.abs(lo), 0.0), np.where(np.isfinite(hi), np.abs(hi), 0.0))
    return lo - BOX_GROWTH * scale, hi + BOX_GROWTH * scale
