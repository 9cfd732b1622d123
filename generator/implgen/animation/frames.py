"""An animated scene: one scene file, a validated Scene for each frame, and one frame rendered to PNG bytes.

`load_frames(path)` reads the file once and checks EVERY frame before anything renders: each keyed value
at each frame goes through the same range checks as a still value, and the checks that combine values
(a transform that must stay invertible, a camera that must not look along its up vector) hold on every
frame. A still scene (no keyed value, no orbit) is parsed once and is its own single frame.

The set of shapes is the same on every frame (keyed values are numbers only), so the scene library is
built once (scene/build.py) and each frame only hands its numbers to the tracer. The frames validated up
front are kept (within KEEP_OBJECT_FRAMES), so the render does not parse them again. `render_frame_png`
renders one frame (or tile) alone; the chunks of a run (chunks.py) give the same bytes.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

from implgen.errors import UserError
from implgen.imagefile import encode_png, to_uint8
from implgen.scene.build import BuildResult, build_scene
from implgen.scene.keys import contains_keyed
from implgen.scene.load import parse_scene
from implgen.scene.model import Leaf, Node, Scene
from implgen.scene.render import render
from implgen.yamlfile import read_yaml

# Checked up front: objects x frames (an object with no keyed value is parsed once and looked up on later
# frames), and keyed objects x frames (parsed and validated anew on every frame, ~50 us each).
MAX_OBJECT_FRAMES = 10_000_000
MAX_KEYED_OBJECT_FRAMES = 100_000
# Frames validated up front are kept for the render (not parsed again) while (keyed objects + 1) x frames is
# at most this: a kept frame holds its camera and its keyed objects, about 1 kB each (20 MB at most).
KEEP_OBJECT_FRAMES = 20_000


@dataclass
class Frames:
    """Every frame of one scene file; frame 0 is `first`."""

    source: str
    data: dict
    first: Scene
    memo: dict = field(default_factory=dict)
    params_vary: bool = False  # some shape param changes from frame to frame
    kept: list[Scene] = field(default_factory=list)  # every frame as validated, when few enough to keep

    @property
    def count(self) -> int:
        return self.first.animation.frames

    @property
    def fps(self) -> float:
        return self.first.animation.fps

    @property
    def animated(self) -> bool:
        """Whether any value changes from frame to frame (a still scene is the same on every frame)."""
        return bool(self.first.keyed)

    def scene(self, frame: int) -> Scene:
        if frame == 0 or not self.animated:
            return self.first
        if self.kept:
            return self.kept[frame]
        return parse_scene(self.data, self.source, frame=frame, memo=self.memo)

    def digest(self) -> str:
        """What every frame's pixels depend on in the scene: its YAML as read (comments and layout aside;
        keyed values as written) and the generated code of each shape it uses (spec files, their params and
        implgen's own code: Spec.spec_key). The resume manifest compares it (frameout.Made)."""
        h = hashlib.sha256()
        try:
            text = json.dumps(self.data, default=repr, separators=(",", ":"))
        except (TypeError, ValueError):  # a key JSON cannot write (a validated scene has none)
            text = repr(self.data)
        h.update(text.encode())
        for key in sorted({leaf.spec.spec_key for leaf in self.first.leaves()}):
            h.update(b"\0" + key.encode())
        return h.hexdigest()


def frames_from_data(data: dict, source: str | Path = "<scene>") -> Frames:
    """Validate every frame of a scene mapping (see the module docstring)."""
    memo: dict = {}
    first = parse_scene(data, source, frame=0, memo=memo)
    fr = Frames(source=first.source, data=data, first=first, memo=memo)
    if not fr.animated:
        return fr
    leaves0 = first.leaves()
    keyed_mats = contains_keyed(data.get("materials"), fr.source, "materials")
    keyed = sum(
        _count_leaves(node)
        for i, (node, raw) in enumerate(zip(first.objects, data["objects"]))
        if keyed_mats or contains_keyed(raw, fr.source, f"objects[{i}]")
    )
    for n, limit, what in ((len(leaves0), MAX_OBJECT_FRAMES, ""), (keyed, MAX_KEYED_OBJECT_FRAMES, "keyed ")):
        if n * fr.count > limit:
            raise UserError(
                fr.source,
                f"animation.frames: {fr.count} frames of {n} {what}objects is more than {limit:,} {what}"
                "object-frames to check; split the animation into several scene files",
            )
    keep = (keyed + 1) * fr.count <= KEEP_OBJECT_FRAMES
    kept = [first]
    for f in range(1, fr.count):
        try:
            sc = parse_scene(data, source, frame=f, memo=memo)
        except UserError as err:
            raise UserError(err.source, f"{err.message} (at frame {f})") from None
        for a, b in zip(leaves0, sc.leaves()):
            assert a.spec is b.spec  # keyed values are numbers: the shapes are the same objects
            fr.params_vary |= a.params != b.params
        if keep:
            kept.append(sc)
    fr.kept = kept if keep else []
    return fr


def _count_leaves(node: Node) -> int:
    return 1 if isinstance(node, Leaf) else _count_leaves(node.left) + _count_leaves(node.right)


def load_frames(path: str | Path) -> Frames:
    path = Path(path)
    return frames_from_data(read_yaml(path, what="scene"), path)


def parse_range(text: str, count: int, option: str = "--frames") -> range:
    """`A:B` (both included), `A:`, `:B` or `A`: frames of an animation of `count` frames."""
    parts = text.split(":")
    digits = all(p.strip().isdecimal() or not p.strip() for p in parts)
    if len(text) > 40 or len(parts) > 2 or not digits or not text.strip(":"):
        raise UserError(option, f"{text[:40]!r} is not a frame range (A:B, A:, :B or A; frames count from 0)")
    if len(parts) == 1:
        parts = [parts[0], parts[0]]
    lo = int(parts[0]) if parts[0].strip() else 0
    hi = int(parts[1]) if parts[1].strip() else count - 1
    if not 0 <= lo <= hi < count:
        raise UserError(option, f"{text[:40]}: frames must satisfy 0 <= A <= B <= {count - 1} (the last frame)")
    return range(lo, hi + 1)


@dataclass(frozen=True)
class FrameOptions:
    """What every frame or tile of one run shares (validated by the command)."""

    width: int
    height: int
    spp: int
    max_depth: int
    threads: int | None = None  # None: all cores of the machine that renders
    seed: int = 0


def render_frame_png(
    scene: Scene, opts: FrameOptions, rows: tuple[int, int] | None = None, built: BuildResult | None = None
) -> bytes:
    """One frame (or the band of rows [y0, y1) of it) as PNG bytes. Without `built`, the scene library comes
    from the content-hash cache (compiled on this machine the first time)."""
    img = render(
        scene,
        width=opts.width,
        height=opts.height,
        spp=opts.spp,
        max_depth=opts.max_depth,
        threads=opts.threads,
        seed=opts.seed,
        rows=rows,
        built=built if built is not None else build_scene(scene),
    )
    return encode_png(to_uint8(img))
