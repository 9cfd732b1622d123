"""What `implgen.show` is given, read: a spec file's path, a scene file's path, or the text of an equation in x,
y, z, with the params given as keywords. The equation is data: it becomes the `equation` of a spec mapping, parsed
by the one spec parser like any file's; the params' values are checked there too."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from implgen.errors import UserError
from implgen.scene.load import parse_scene
from implgen.scene.model import Scene
from implgen.spec.entry import parse_spec
from implgen.spec.model import Spec
from implgen.validate import describe
from implgen.yamlfile import read_yaml

WHERE = "implgen.show"
SUFFIXES = (".yaml", ".yml", ".json")
MAX_EQUATION = 10_000  # characters, as a spec file's equation (the parser has its own, tighter limits)


@dataclass
class Shown:
    """A spec with the param values to start from, or a scene (then spec is None)."""

    spec: Spec | None
    values: dict[str, float]
    scene: Scene | None = None


def _numbers(params: dict[str, Any]) -> dict[str, float]:
    out = {}
    for name, value in params.items():
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise UserError(WHERE, f"param {describe(name)}: expected a finite number, got {describe(repr(value))}")
        out[name] = float(value)
    return out


def _from_file(path: Path, params: dict[str, float]) -> Shown:
    data = read_yaml(path, what="spec or scene")
    if isinstance(data, dict) and "objects" in data:
        if params:
            raise UserError(WHERE, f"{path}: a scene takes no params (set them in the scene's objects)")
        return Shown(None, {}, parse_scene(data, path))
    if isinstance(data, dict) and params:
        declared = data.get("params") if isinstance(data.get("params"), dict) else {}
        unknown = [n for n in params if n not in declared]
        if unknown:
            known = ", ".join(map(str, declared)) or "none"
            raise UserError(WHERE, f"{path}: no param {describe(unknown[0])} (params: {known})")
        data = {**data, "params": {**declared, **params}}
    spec = parse_spec(data, str(path))
    return Shown(spec, dict(spec.params))


def read(source: str | Path, params: dict[str, Any]) -> Shown:
    """`source` as a file (a Path, or text ending in .yaml, .yml or .json) or as an equation."""
    values = _numbers(params)
    if isinstance(source, Path) or (isinstance(source, str) and source.strip().lower().endswith(SUFFIXES)):
        return _from_file(Path(source), values)
    if not isinstance(source, str):
        raise UserError(WHERE, f"expected a spec or scene file, or an equation as text, got {type(source).__name__}")
    if len(source) > MAX_EQUATION:
        raise UserError(WHERE, f"the equation is longer than {MAX_EQUATION} characters")
    spec = parse_spec({"name": "surface", "equation": source, "params": values}, "<equation>")
    return Shown(spec, dict(spec.params))
