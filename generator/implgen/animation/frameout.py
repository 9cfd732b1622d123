"""Where rendered frames go: one PNG, a numbered PNG sequence, a video (.mp4, .webm) or a .gif.

    -o still.png              one frame (a still scene, or `--frames N` of an animation)
    -o frames/f_%04d.png      one PNG per frame; exactly one %d field (%d, %4d, %04d) in the file name
    -o film.mp4 | .webm       H.264 / VP9 through imageio-ffmpeg (its wheel carries the ffmpeg binary)
    -o loop.gif               an animated GIF (Pillow), looping

Every frame is a PNG written atomically (outputs.atomic_write) and flushed to disk before its rename, so a
frame file exists only once complete. A video or GIF is assembled from such PNGs kept in a sidecar folder
beside it (`film.mp4.frames/`), encoded to a temporary name and renamed into place at the end; the sidecar
is then removed (unless asked to keep it), so a crash before the end leaves the rendered frames to resume
from and no half-written video.

A rerun skips the frames already there (resume after a crash or an interrupt), but only frames made by the
same settings: a small manifest beside the frames (`.f_%04d.png.implgen.json`, `.film.mp4.implgen.json` in
the sidecar) records what made them, `Made`: the scene's digest (its YAML and the code of every shape it
uses) and the options that change pixels. Frames made otherwise, or with no manifest, are removed and
rendered again when the run covers them all; when some lie outside the run (`--frames`), a frame pattern is
refused in one line rather than left holding a mixed set. A sidecar is implgen's own: its stale frames are
simply removed.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import secrets
import shutil
import string
import struct
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from implgen.errors import UserError
from implgen.imagefile import decode_png, encode_png
from implgen.outputs import atomic_write, check_output_file, check_output_folder, staged

if TYPE_CHECKING:
    import numpy as np

VIDEO = (".mp4", ".webm")
GIF = ".gif"
STILL = ".png"
# The one printf integer field of a frame pattern: %d, %4d or %04d (no other % in the name).
_FIELD = re.compile(r"%(0?[1-9]?)d")
CODECS = {".mp4": "libx264", ".webm": "libvpx-vp9"}
# The frame rates each kind of output can carry (a scene's fps is (0, 1000]; frame PNGs have none). GIF stores a
# frame's delay in hundredths of a second in 16 bits: at most 655.35 s, so 0.002 fps (500 s) is the slowest
# round rate it holds. ffmpeg takes the rate as a fraction with a denominator of at most 10^6 (imageio-ffmpeg):
# 1e-5 fps breaks the .mp4 muxer, 1e-300 becomes 0; 0.001 fps (a frame every 1,000 s) to 1000 fps encode and
# decode frame for frame with both codecs, for 10,000 frames (tests/test_fps_ranges.py).
FPS_RANGES = {
    "gif": (0.002, 1000.0, "a GIF stores each frame's delay in hundredths of a second, at most 655.35 s"),
    "video": (0.001, 1000.0, "ffmpeg's .mp4 muxer fails below it; a frame shows 1,000 s at 0.001"),
}


MANIFEST_FORMAT = 1
_PNG_HEAD = b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR"  # signature, then the IHDR chunk's length and type


@dataclass(frozen=True)
class Made:
    """What a frame's pixels depend on: the scene (frames.Frames.digest) and the options that change pixels.
    Threads and tiles do not: a pixel's samples depend only on the pixel and the seed."""

    scene: str
    width: int
    height: int
    spp: int
    max_depth: int
    seed: int
    fold: bool

    def record(self) -> dict:
        return {"implgen_frames": MANIFEST_FORMAT, **asdict(self)}

    def differences(self, old: object) -> str:
        """How the manifest `old` (as read; anything) differs from this, for a message; '' when it does not."""
        if not isinstance(old, dict) or old.get("implgen_frames") != MANIFEST_FORMAT:
            return "no record of what made them"
        if old == self.record():
            return ""
        out = ["the scene or its shapes changed"] if old.get("scene") != self.scene else []
        for k, v in asdict(self).items():
            if k != "scene" and old.get(k) != v:
                out.append(f"{k} {old.get(k)!r}, now {v!r}")
        return ", ".join(out) or "other settings"


@dataclass
class Claim:
    """What `FrameOutput.claim` found: frames made otherwise and removed to be rendered again, and why."""

    replaced: list[int]
    why: str


def png_size(path: Path) -> tuple[int, int] | None:
    """(width, height) from a PNG file's header, or None when it is not a PNG (too short, another file)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(24)
    except OSError:
        return None
    if len(head) < 24 or not head.startswith(_PNG_HEAD):
        return None
    return struct.unpack(">II", head[16:24])


def _write_synced(fh, data: bytes) -> None:
    """Write and flush to the disk before the caller's rename: after a power loss, a name is never left
    pointing at a file whose bytes did not reach the disk (a frame that looks complete and is empty)."""
    fh.write(data)
    fh.flush()
    os.fsync(fh.fileno())


def _sync_folder(folder: Path) -> None:
    """Make the renames in `folder` durable (where the file system allows opening a folder)."""
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


@dataclass
class FrameOutput:
    """The output of one render command; `path(frame)` is where that frame's PNG goes."""

    target: Path  # what the user named
    kind: str  # "still" | "pattern" | "video" | "gif"
    folder: Path  # where the frame PNGs go
    name_format: str | None  # Python format of a frame's file name in `folder` (None for a still)

    def path(self, frame: int) -> Path:
        if self.kind == "still":
            return self.target
        assert self.name_format is not None
        return self.folder / self.name_format.format(frame)

    @property
    def manifest(self) -> Path | None:
        """The record of what made the frames (None for a still, which is never resumed)."""
        if self.kind == "still":
            return None
        name = f".{self.target.name}.implgen.json"
        if len(os.fsencode(name)) > 255:  # a pattern's name near the file system's limit: a short name instead
            name = f".implgen-{hashlib.sha256(os.fsencode(self.target.name)).hexdigest()[:16]}.json"
        return self.folder / name

    def done(self, frame: int, made: Made) -> bool:
        """A frame is complete when its file exists (files appear only by an atomic rename, after claim() has
        removed frames made otherwise) and is a PNG of this run's size."""
        return self.kind != "still" and png_size(self.path(frame)) == (made.width, made.height)

    def existing(self) -> dict[int, Path]:
        """The frame files in the folder now, by frame number: the names this output's format gives a number."""
        if self.name_format is None or not self.folder.is_dir():
            return {}
        parts = list(string.Formatter().parse(self.name_format))  # literal text (unescaped) and the one field
        name = "".join(re.escape(text) + (r" *(\d{1,9})" if field is not None else "") for text, field, _, _ in parts)
        pattern = re.compile(name + "$")
        found = {}
        for entry in os.scandir(self.folder):
            m = pattern.match(entry.name)
            if m and self.name_format.format(int(m.group(1))) == entry.name and not entry.is_dir():
                found[int(m.group(1))] = Path(entry.path)
        return found

    def claim(self, made: Made, todo: Iterable[int], option: str = "-o") -> Claim:
        """Before any frame is written: unless the manifest says the frames here were made by `made`, remove
        them to be rendered again -- or refuse in one line when a frame pattern holds some outside `todo`, as
        its set would be mixed -- and record `made`."""
        manifest = self.manifest
        if manifest is None:
            return Claim([], "")
        self.prepare()
        try:
            old = json.loads(manifest.read_bytes())
        except (OSError, ValueError):
            old = None
        why = made.differences(old)
        if not why:
            return Claim([], "")
        stale = self.existing()
        wanted = set(todo)
        outside = sorted(f for f in stale if f not in wanted)
        if outside and self.kind == "pattern":
            raise UserError(
                f"{option} {self.target}",
                f"{len(stale)} frame files there were made otherwise ({why}), and {len(outside)} of them are "
                f"outside the frames asked for (first {outside[0]}): remove them, render them all again "
                "(--frames), or choose another output, so that the set is not mixed",
            )
        data = json.dumps(made.record(), indent=1).encode() + b"\n"
        try:
            for path in stale.values():
                path.unlink(missing_ok=True)
            atomic_write(manifest, lambda fh: _write_synced(fh, data))
        except OSError as err:  # what the early checks could not foresee: a full disk, a folder removed
            name = err.filename or manifest
            raise UserError(f"{option} {self.target}", f"cannot replace {name}: {err.strerror or err}") from None
        _sync_folder(self.folder)
        return Claim(sorted(f for f in stale if f in wanted), why if stale else "")

    def check_fps(self, fps: float, source: str) -> None:
        """The scene's frame rate (animation.fps in `source`) fits this output, before any rendering."""
        if self.kind not in FPS_RANGES:
            return
        lo, hi, why = FPS_RANGES[self.kind]
        if not lo <= fps <= hi:
            raise UserError(
                source, f"animation.fps: {fps:g} is outside [{lo:g}, {hi:g}] for -o {self.target.name} ({why})"
            )

    def prepare(self) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)

    def stage(self, image: bytes | np.ndarray) -> Path:
        """A frame (PNG bytes, or 8-bit RGB encoded here) written to a temporary name in the folder and
        flushed to the disk: a complete file, for `commit` to rename into place (any thread may stage)."""
        png = image if isinstance(image, bytes) else encode_png(image)
        return staged(self.folder, lambda fh: _write_synced(fh, png))

    def commit(self, frame: int, tmp: Path) -> None:
        """A staged frame renamed into place: from now on it is frame `frame`, whole."""
        try:
            os.replace(tmp, self.path(frame))
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def finish(self, frames: Sequence[int], fps: float, keep_frames: bool = False) -> None:
        """Encode a video or GIF from the frame PNGs (all present), atomically; then drop the sidecar."""
        if self.kind in ("still", "pattern"):
            return
        paths = [self.path(f) for f in frames]
        tmp = self.target.parent / f".ig-{secrets.token_hex(6)}.tmp{self.target.suffix.lower()}"
        try:
            if self.kind == "gif":
                _write_gif(tmp, paths, fps)
            else:
                _write_video(tmp, paths, fps, CODECS[self.target.suffix.lower()])
            os.chmod(tmp, 0o666 & ~_umask())
            with open(tmp, "rb+") as fh:  # on the disk before the rename
                os.fsync(fh.fileno())
            os.replace(tmp, self.target)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        if not keep_frames:
            shutil.rmtree(self.folder, ignore_errors=True)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _gif_delay(fps: float) -> int:
    """Milliseconds a GIF frame shows: GIF counts hundredths of a second, and browsers show delays under
    20 ms as 100 ms, so 20 ms (50 fps) is the fastest that plays as written."""
    return max(20, 10 * round(100.0 / fps))


def _write_gif(path: Path, frames: list[Path], fps: float) -> None:
    from PIL import Image

    images = []
    for p in frames:
        with Image.open(p) as im:
            images.append(im.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT, dither=0))
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:], duration=_gif_delay(fps), loop=0)


def _write_video(path: Path, frames: list[Path], fps: float, codec: str) -> None:
    import imageio.v2 as iio

    # macro_block_size=1: never resize (sizes were checked to be even); yuv420p plays everywhere
    with iio.get_writer(
        path,
        format="FFMPEG",
        mode="I",
        fps=fps,
        codec=codec,
        quality=8,
        pixelformat="yuv420p",
        macro_block_size=1,
        ffmpeg_log_level="error",
    ) as writer:
        for p in frames:
            writer.append_data(decode_png(p.read_bytes()))


def plan_output(target: Path, nframes: int, last: int, width: int, height: int, option: str = "-o") -> FrameOutput:
    """Check an output before any work: its kind fits the number of frames, its folder is writable, the
    names it will create fit the file system, a video's size is even. `last` is the largest frame number."""
    target = Path(target)
    suffix = target.suffix.lower()
    label = f"{option} {target}"
    if "%" in target.name or "%" in str(target.parent):
        return _plan_pattern(target, last, label, option)
    if suffix == STILL:
        if nframes != 1:
            raise UserError(
                label,
                f"{nframes} frames to write: give a pattern like frames/f_%04d.png, a .mp4, .webm or .gif, "
                "or one frame with --frames N",
            )
        check_output_file(target, option, (STILL,))
        return FrameOutput(target=target, kind="still", folder=target.parent, name_format=None)
    check_output_file(target, option, (STILL, *VIDEO, GIF))
    if suffix in VIDEO and (width % 2 or height % 2):
        raise UserError(label, f"a video needs an even width and height (the image is {width}x{height})")
    sidecar = target.parent / f"{target.name}.frames"
    check_output_folder(sidecar, option)
    digits = max(4, len(str(last)))
    return FrameOutput(
        target=target,
        kind="gif" if suffix == GIF else "video",
        folder=sidecar,
        name_format=f"{{:0{digits}d}}.png",
    )


def _plan_pattern(target: Path, last: int, label: str, option: str) -> FrameOutput:
    if "%" in str(target.parent):
        raise UserError(label, "the %d field must be in the file name, not in a folder name")
    name = target.name
    m = _FIELD.search(name)
    if name.count("%") != 1 or m is None:
        raise UserError(label, "a frame pattern needs exactly one %d field (%d, %4d or %04d), e.g. f_%04d.png")
    if target.suffix.lower() != STILL:
        raise UserError(label, "a frame pattern must end in .png")

    def literal(text: str) -> str:
        return text.replace("{", "{{").replace("}", "}}")

    fmt = literal(name[: m.start()]) + f"{{:{m.group(1)}d}}" + literal(name[m.end() :])
    folder = target.parent if str(target.parent) else Path(".")
    check_output_folder(folder, option)
    if folder.is_dir():
        check_output_file(folder / fmt.format(last), option, (STILL,))
    return FrameOutput(target=target, kind="pattern", folder=folder, name_format=fmt)
