"""Keyed values: a number in a scene that changes from frame to frame, and the `animation` block.

    fov: {keys: {0: 30, 47: 55}, ease: smooth}    # frame -> value; ease: linear (default) or smooth
    animation: {frames: 48, fps: 24}

Between two keys the value moves from one to the other by the ease: `linear` is a + (b - a) s, `smooth` the
cubic a + (b - a) s^2 (3 - 2 s), where s = (frame - f0) / (f1 - f0). Before the first key and after the last
the value holds. At a key frame the value is the key's number itself (not recomputed), so a keyed value is
exact at its keys. Both eases stay between their two keys, so a value whose keys are inside a range stays
inside it on every frame.

The range of each number is checked where it is used (scene/reader.py), on every frame; this module only
checks the shape of a keyed mapping. The format is documented in docs/formats.md#keyed-values.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from implgen import validate
from implgen.errors import UserError

MAX_FRAMES = 10_000  # frames in one animation (every frame is validated before anything renders)
MAX_FPS = 1000.0
DEFAULT_FPS = 24.0
EASES = ("linear", "smooth")
KEYED_KEYS = ("keys", "ease")
ANIMATION_KEYS = ("frames", "fps")
ORBIT_KEYS = ("center", "radius", "height", "turns")
MAX_TURNS = 1000
# Lists and mappings inside each other that a walk over raw YAML follows. A valid scene nests about 70 deep
# at most (32 CSG levels of a mapping and a list each, then a leaf's transform or material), so 100 refuses
# nothing valid, and a walk stops there, long before Python's recursion limit, whatever the reader checks later.
MAX_NESTING = 100


@dataclass
class FrameKeys:
    """What reading keyed values needs: the file, the frame being read, the animation's frame count (None
    without an `animation` block), the key paths of the keyed values met so far, and the parsed keyed
    mappings of a load (shared by its frames). The scene reader is one (scene/reader.py)."""

    source: str
    frame: int = 0
    frames: int | None = None
    keyed: list[str] = field(default_factory=list)
    keyed_cache: dict | None = None


@dataclass(frozen=True)
class Animation:
    frames: int = 1
    fps: float = DEFAULT_FPS


@dataclass(frozen=True)
class Keyed:
    """A keyed number: frames in increasing order, their values, and the ease between them."""

    frames: tuple[int, ...]
    values: tuple[Any, ...]  # as written (checked as numbers where used, against that key's range)
    ease: str = "linear"

    def at(self, frame: int) -> Any:
        """The value at `frame`: exactly a key's value at its frame, held outside the keys."""
        fs, vs = self.frames, self.values
        if frame <= fs[0]:
            return vs[0]
        if frame >= fs[-1]:
            return vs[-1]
        i = bisect.bisect_left(fs, frame)  # fs[i - 1] < frame <= fs[i]: a long key list costs log n per frame
        if fs[i] == frame:
            return vs[i]
        a, b = float(vs[i - 1]), float(vs[i])
        s = (frame - fs[i - 1]) / (fs[i] - fs[i - 1])
        if self.ease == "smooth":
            s = s * s * (3.0 - 2.0 * s)
        return a + (b - a) * s


def is_keyed(value: Any) -> bool:
    """Whether a raw YAML value is written as a keyed value (a mapping with `keys`)."""
    return isinstance(value, dict) and "keys" in value


def parse_animation(source: str, raw: Any) -> Animation:
    if raw is None:
        return Animation()
    validate.mapping(source, "animation", raw, ANIMATION_KEYS, ("frames",), "'frames' (and optionally 'fps')")
    frames = validate.whole(source, "animation.frames", raw["frames"], 1, MAX_FRAMES)
    fps = validate.number(source, "animation.fps", raw.get("fps", DEFAULT_FPS), 0.0, MAX_FPS, lo_open=True)
    return Animation(frames=frames, fps=fps)


def parse_keyed(source: str, key: str, raw: dict, frames: int | None) -> Keyed:
    """Check a keyed mapping's form. `frames` is the animation's frame count (None: the scene has no
    `animation` block, where a keyed value has no meaning)."""
    if frames is None:
        raise UserError(source, f"{key}: a keyed value needs an 'animation' block at the top level")
    validate.mapping(source, key, raw, KEYED_KEYS)
    ease = raw.get("ease", "linear")
    if ease not in EASES:
        raise UserError(source, f"{key}.ease: {validate.describe(ease)} is not one of {', '.join(EASES)}")
    keys = raw["keys"]
    if not isinstance(keys, dict) or not keys:
        raise UserError(source, f"{key}.keys: expected a mapping frame -> number, with at least one key")
    items = []
    for f, v in keys.items():
        if isinstance(f, bool) or not isinstance(f, int):
            raise UserError(source, f"{key}.keys: a key is a frame number, not {validate.describe(f)}")
        if not 0 <= f < frames:
            raise UserError(
                source, f"{key}.keys: frame {validate.describe(f)} is outside the animation's frames [0, {frames - 1}]"
            )
        if is_keyed(v):
            raise UserError(source, f"{key}.keys.{f}: a key's value is a number, not another keyed value")
        validate.number(source, f"{key}.keys.{f}", v)  # finite; its own range is checked where it is used
        items.append((f, v))
    items.sort()
    return Keyed(frames=tuple(f for f, _ in items), values=tuple(v for _, v in items), ease=ease)


def _cached(ctx: FrameKeys, key: str, raw: dict) -> Keyed:
    """parse_keyed once per key path and keyed mapping for all frames of a load (the cache lives that long and
    holds `raw`, so its id stays its own): checking 5,000 keys again on each of 10,000 frames took minutes."""
    cache = ctx.keyed_cache
    if cache is None:
        return parse_keyed(ctx.source, key, raw, ctx.frames)
    entry = cache.get((key, id(raw)))
    if entry is None or entry[0] is not raw:
        entry = cache[(key, id(raw))] = (raw, parse_keyed(ctx.source, key, raw, ctx.frames), [])
    return entry[1]


def too_deep(source: str, key: str) -> UserError:
    """The one-line error of a walk that met more than MAX_NESTING lists and mappings inside each other."""
    where = key if len(key) <= 80 else f"{key[:80]}..."
    return UserError(source, f"{where}: nested more than {MAX_NESTING} levels deep (lists and mappings)")


def resolve(ctx: FrameKeys, key: str, raw: Any, depth: int = 0) -> Any:
    """`raw` with every keyed value inside it replaced by its value at this frame (for parts of a scene where
    every leaf is a number, such as a transform). The key paths of the keyed values found go to `ctx.keyed`.
    `depth` counts the containers above `raw`: past MAX_NESTING the walk stops with one line."""
    if is_keyed(raw):
        ctx.keyed.append(key)
        return _cached(ctx, key, raw).at(ctx.frame)
    if isinstance(raw, (dict, list)) and depth >= MAX_NESTING:
        raise too_deep(ctx.source, key)
    if isinstance(raw, dict):
        return {k: resolve(ctx, f"{key}.{validate.key_name(k)}", v, depth + 1) for k, v in raw.items()}
    if isinstance(raw, list):
        return [resolve(ctx, f"{key}[{i}]", v, depth + 1) for i, v in enumerate(raw)]
    return raw


def number_at(ctx: FrameKeys, key: str, raw: Any, check: Callable[[str, Any], float]) -> float:
    """A number that may be keyed, at this frame, through `check(key, value)` (its range): each key's value is
    checked under its own name (`camera.fov.keys.47`), then the value at this frame."""
    if not is_keyed(raw):
        return check(key, raw)
    ctx.keyed.append(key)
    keyed = _cached(ctx, key, raw)
    checked = ctx.keyed_cache[(key, id(raw))][2] if ctx.keyed_cache is not None else []
    if not checked:  # the keys are the same on every frame: checked against this key's range once
        for f, v in zip(keyed.frames, keyed.values):
            check(f"{key}.keys.{f}", v)
        checked.append(True)
    return check(key, keyed.at(ctx.frame))


def inline_params(ctx: FrameKeys, key: str, raw: Any) -> tuple[Any, dict]:
    """An inline equation's `params` as (the shape's defaults, the keyed ones to pass per frame): a keyed
    param's default is its first key, so the shape is the same on every frame and only the value moves."""
    if not isinstance(raw, dict):
        return raw, {}  # the spec parser says what is wrong with it
    keyed = {k: v for k, v in raw.items() if is_keyed(v)}
    first = {k: _cached(ctx, f"{key}.{validate.key_name(k)}", v).values[0] for k, v in keyed.items()}
    return {**raw, **first}, keyed


def contains_keyed(raw: Any, source: str, key: str, depth: int = 0) -> bool:
    """Whether a keyed value appears anywhere in the raw YAML value `raw` of `key` in `source`. It runs before
    the reader has checked anything, so it bounds its own depth: past MAX_NESTING containers, one line."""
    if is_keyed(raw):
        return True
    if not isinstance(raw, (dict, list)):
        return False
    if depth >= MAX_NESTING:
        raise too_deep(source, key)
    values = raw.values() if isinstance(raw, dict) else raw
    return any(contains_keyed(v, source, key, depth + 1) for v in values)


def orbit_camera(ctx: FrameKeys, cam: dict) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """`camera.orbit` at this frame: (position, look_at). Its numbers may be keyed too."""
    source, frames = ctx.source, ctx.frames
    for k in ("position", "look_at"):
        if k in cam:
            raise UserError(source, f"camera.{k}: not with camera.orbit (the orbit sets it)")
    raw = cam["orbit"]
    validate.mapping(source, "camera.orbit", raw, ORBIT_KEYS, ("radius",), "'radius' (and center, height, turns)")

    def num(key: str, value: Any, lo: float, hi: float, lo_open: bool = False) -> float:
        def check(k: str, v: Any) -> float:
            return validate.number(source, k, v, lo, hi, lo_open=lo_open)

        return number_at(ctx, f"camera.orbit.{key}", value, check)

    big = validate.MAX_COORDINATE
    center = raw.get("center", [0, 0, 0])
    if isinstance(center, list) and len(center) == 3:
        center = [num(f"center[{i}]", v, -big, big) for i, v in enumerate(center)]
    c = validate.vector(source, "camera.orbit.center", center)
    radius = num("radius", raw["radius"], 0.0, big, lo_open=True)
    height = num("height", raw.get("height", 0.0), -big, big)
    turns = num("turns", raw.get("turns", 1.0), -MAX_TURNS, MAX_TURNS)
    if turns and frames is not None and frames > 1:
        ctx.keyed.append("camera.orbit")
    return orbit(c, radius, height, turns, ctx.frame, frames or 1), c


def orbit(
    center: tuple[float, float, float], radius: float, height: float, turns: float, frame: int, frames: int
) -> tuple[float, float, float]:
    """The camera position on an orbit at `frame`: `radius` from the vertical axis through `center`,
    `height` above it, `turns` full turns over the animation (counter-clockwise seen from above for
    turns > 0), starting on the +z side. Frame `frames` would be frame 0 again, so a one-turn loop is seamless."""
    angle = 2.0 * math.pi * turns * frame / frames
    return (
        center[0] + radius * math.sin(angle),
        center[1] + height,
        center[2] + radius * math.cos(angle),
    )
