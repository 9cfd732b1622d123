"""Where rendered frames go: one PNG, a numbered PNG sequence, a video (.mp4, .webm) or a .gif.

    -o still.png              one frame (a still scene, or `--frames N` of an animation)
    -o frames/f_%04d.png      one PNG per frame; exactly one %d field (%d, %4d, %04d) in the file name
    -o film.mp4 | .webm       H.264 / VP9 through imageio-ffmpeg (its wheel carries the ffmpeg binary)
    -o loop.gif               an animated GIF (Pillow), looping

Every frame is a PNG written atomically (outputs.atomic_write), so a frame file exists only once complete and
a rerun skips the frames already there (resume after a crash or an interrupt). A video or GIF is assembled
from such PNGs kept in a sidecar folder beside it (`film.mp4.frames/`), encoded to a temporary name and
renamed into place at the end; the sidecar is then removed (unless asked to keep it), so a crash before the
end leaves the rendered frames to resume from and no half-written video.
"""

from __future__ import annotations

import os
import re
import secrets
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from implgen.errors import UserError
from implgen.outputs import atomic_write, check_output_file, check_output_folder

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

    def done(self, frame: int) -> bool:
        """A frame is complete when its file exists (files appear only by an atomic rename)."""
        return self.kind != "still" and self.path(frame).is_file()

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

    def write(self, frame: int, png: bytes) -> None:
        atomic_write(self.path(frame), lambda fh: fh.write(png))

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


def _read_png(path: Path):
    import numpy as np
    from PIL import Image

    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


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
            writer.append_data(_read_png(p))


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
