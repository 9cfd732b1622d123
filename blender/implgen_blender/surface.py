"""What the add-on does outside Blender: the operator's fields read, the equation written as a spec, `implgen
mesh` run on it, and the OBJ it writes read back. No bpy here, so plain Python tests it (tests/test_blender_addon.py).

The equation and the params reach implgen only as data: a spec document written with json.dumps (JSON is YAML,
so implgen reads it as any spec), params parsed here into numbers. Whatever implgen refuses comes back as its
one line, without the temporary file's path.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
TIME_LIMIT = 300  # seconds `implgen mesh` may mesh (its --time-limit); Blender waits for it
MAX_PARAMS_TEXT = 4096
NOT_FOUND = "implgen not found on PATH: pip install implgen, or set its path in the add-on's preferences"


class SurfaceError(Exception):
    """One line for Blender's report."""


def parse_params(text: str) -> dict[str, float]:
    """'a=1, b=0.3' (each item as `implgen mesh --param` takes it) -> {'a': 1.0, 'b': 0.3}."""
    if len(text) > MAX_PARAMS_TEXT:
        raise SurfaceError(f"params: longer than {MAX_PARAMS_TEXT} characters")
    params: dict[str, float] = {}
    for item in (part.strip() for part in text.split(",")):
        if not item:
            continue
        name, sep, value = (s.strip() for s in item.partition("="))
        if not sep or not NAME.match(name):
            raise SurfaceError(f"params: {item!r} is not NAME=VALUE")
        try:
            number = float(value)
        except ValueError:
            raise SurfaceError(f"params: {name}: {value!r} is not a number") from None
        if not math.isfinite(number):
            raise SurfaceError(f"params: {name}: {value!r} is not a finite number")
        if name in params:
            raise SurfaceError(f"params: {name} is given twice")
        params[name] = number
    return params


def find_implgen(setting: str) -> str:
    """The `implgen` command: the path set in the add-on's preferences, else the one on PATH."""
    if setting.strip():
        path = Path(setting.strip()).expanduser()
        if not (path.is_file() and os.access(path, os.X_OK)):
            raise SurfaceError(f"implgen: {str(path)!r} (the add-on's preferences) is not a program")
        return str(path)
    found = shutil.which("implgen")
    if found is None:
        raise SurfaceError(NOT_FOUND)
    return found


def command(implgen: str, spec: Path, out: Path, cells: int, clip: str) -> list[str]:
    cmd = [implgen, "mesh", str(spec), "-o", str(out), "--cells", str(cells), "--time-limit", str(TIME_LIMIT)]
    return cmd + (["--clip", clip.strip()] if clip.strip() else [])


def one_line(stderr: str, spec: Path) -> str:
    """implgen's error line, without its prefix and the temporary spec's path."""
    lines = [line for line in stderr.splitlines() if line.strip()]
    line = lines[-1] if lines else "implgen mesh failed without a message"
    line = line.removeprefix("implgen: error: ")
    return line.replace(f"{spec}: ", "").replace(str(spec), "the equation")


def mesh(implgen: str, equation: str, params: str, cells: int, clip: str) -> tuple[list, list]:
    """The closed mesh of f(x, y, z) = 0: (vertices, triangles), as `implgen mesh` makes it."""
    values = parse_params(params)
    if not equation.strip():
        raise SurfaceError("equation: empty")
    with tempfile.TemporaryDirectory(prefix="implgen-blender-") as tmp:
        spec, out = Path(tmp) / "surface.yaml", Path(tmp) / "surface.obj"
        spec.write_text(json.dumps({"name": "surface", "equation": equation, "params": values}))
        try:
            proc = subprocess.run(
                command(implgen, spec, out, cells, clip), capture_output=True, text=True, timeout=TIME_LIMIT + 60
            )
        except subprocess.TimeoutExpired:
            raise SurfaceError(f"implgen mesh took longer than {TIME_LIMIT + 60} s") from None
        except OSError as err:
            raise SurfaceError(f"cannot run {implgen!r}: {err.strerror or err}") from None
        if proc.returncode != 0 or not out.is_file():
            raise SurfaceError(one_line(proc.stderr, spec))
        return read_obj(out)


def read_obj(path: Path) -> tuple[list[tuple[float, float, float]], list[tuple[int, ...]]]:
    """Vertices and faces of an OBJ file as implgen writes it ('v x y z', 'f a//a b//b c//c', 1-based)."""
    verts: list[tuple[float, float, float]] = []
    faces: list[tuple[int, ...]] = []
    with open(path) as fh:
        for line in fh:
            parts = line.split()
            if parts[:1] == ["v"]:
                x, y, z = map(float, parts[1:4])
                verts.append((x, y, z))
            elif parts[:1] == ["f"]:
                faces.append(tuple(int(p.split("/")[0]) - 1 for p in parts[1:]))
    if not faces or any(not 0 <= i < len(verts) for face in faces for i in face):
        raise SurfaceError(f"{path.name}: not a mesh implgen wrote")
    return verts, faces
