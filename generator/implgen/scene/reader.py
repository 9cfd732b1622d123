"""Reading one frame of a scene file: the reader (the file, the frame, what was met so far) and the numbers,
vectors and colours read through it -- any of them may be keyed (scene/keys.py), every one is checked against
its documented range, and every error names the file and the key at fault.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from implgen import validate
from implgen.errors import UserError
from implgen.scene import keys
from implgen.spec.model import Spec

MAX_SHAPES = 256  # distinct shapes (spec files and inline equations) in one scene
COLOR_MAX = 100.0  # colour components; lengths and positions use validate.MAX_COORDINATE


class Reader(keys.FrameKeys):
    """Reading one frame of one scene file: what keyed values need (keys.FrameKeys), and the specs, shapes and
    objects met so far."""

    def __init__(self, path: Path, frame: int, memo: dict | None):
        memo = {} if memo is None else memo  # shared by the frames of one animation: specs are read once
        super().__init__(source=str(path), frame=frame, keyed_cache=memo.setdefault("keyed", {}))
        self.path = path
        self.spec_cache: dict[Path, Spec] = memo.setdefault("specs", {})
        self.resolved: dict[str, Path] = memo.setdefault("paths", {})  # `shape:` text -> spec file
        self.inline_specs: dict[str, Spec] = memo.setdefault("inline", {})
        self.inline_count = 0
        self.leaves = 0
        self.static: dict[int, tuple] = memo.setdefault("static", {})  # objects the same on every frame
        self.reused: set[int] = set()  # objects[i] taken from `static` on this frame

    def resolve(self, key: str, raw: Any) -> Any:
        """A part of the scene made only of numbers (a transform), with keyed values at this frame."""
        return keys.resolve(self, key, raw)

    def fail(self, key: str, msg: str) -> UserError:
        return UserError(self.source, f"{key}: {msg}")

    def count_shape(self, key: str) -> None:
        if self.inline_count + len(self.spec_cache) >= MAX_SHAPES:
            raise self.fail(key, f"more than {MAX_SHAPES} distinct shapes in one scene")

    def mapping(self, key: str, value: Any, allowed: tuple[str, ...]) -> dict:
        return validate.mapping(self.source, key, value, allowed)

    def num(
        self,
        key: str,
        value: Any,
        lo: float = -validate.MAX_COORDINATE,
        hi: float = validate.MAX_COORDINATE,
        lo_open: bool = False,
    ) -> float:
        """A number that may be keyed, in [lo, hi] (or (lo, hi] with lo_open) at this frame."""

        def check(k: str, v: Any) -> float:
            return validate.number(self.source, k, v, lo, hi, lo_open=lo_open)

        return keys.number_at(self, key, value, check)

    def whole(self, key: str, value: Any, lo: int, hi: int) -> int:
        """A whole number that is the same on every frame."""
        if keys.is_keyed(value):
            raise self.fail(key, "cannot be keyed (it is the same on every frame)")
        return validate.whole(self.source, key, value, lo, hi)

    def vec(
        self, key: str, value: Any, lo: float = -validate.MAX_COORDINATE, hi: float = validate.MAX_COORDINATE
    ) -> tuple[float, float, float]:
        """Three numbers, each of which may be keyed on its own."""
        if keys.is_keyed(value):
            raise self.fail(key, "key each of the three numbers on its own: [x, {keys: ...}, z]")
        if isinstance(value, (list, tuple)) and len(value) == 3:
            value = [self.num(f"{key}[{i}]", v, lo, hi) for i, v in enumerate(value)]
        return validate.vector(self.source, key, value, lo, hi)

    def color(self, key: str, value: Any) -> tuple[float, float, float]:
        return self.vec(key, value, 0.0, COLOR_MAX)


def given(raw: dict, key: str, default: Any) -> Any:
    """raw[key], or `default` when the key is left out or empty (`lights:`); `0` or `[]` where a mapping
    belongs is an error the caller reports, not a default."""
    value = raw.get(key)
    return default if value is None else value
