"""Frame rates each output can carry: a GIF's 16-bit delay in hundredths of a second, ffmpeg's rate as a
fraction. A rate outside an output's range is one line naming the scene file and animation.fps, before any
rendering; the ends of each range encode and decode frame for frame."""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import pytest
import yaml
from PIL import Image

from implgen.animation.frameout import FPS_RANGES
from implgen_proc import assert_one_line, implgen

ROOT = Path(__file__).resolve().parent.parent
SPHERE = str(ROOT / "examples" / "shapes" / "sphere.yaml")


def scene(tmp_path: Path, fps: float, frames: int = 2) -> Path:
    data = {
        "animation": {"frames": frames, "fps": fps},
        "image": {"width": 8, "height": 6, "spp": 1, "max_depth": 1},
        "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "fov": 40},
        "lights": [{"position": [3, 8, 4], "intensity": {"keys": {0: 1.0, frames - 1: 0.5}}}],
        "objects": [{"shape": SPHERE}],
    }
    path = tmp_path / "anim.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(
    "fps, out, range_text",
    [
        (0.0001, "loop.gif", "[0.002, 1000]"),  # Pillow: a delay past 16 bits was a struct.error traceback
        (0.0019, "loop.gif", "[0.002, 1000]"),
        (1e-300, "film.mp4", "[0.001, 1000]"),  # ffmpeg's rate became 0: a ValueError traceback
        (1e-5, "film.mp4", "[0.001, 1000]"),  # the .mp4 muxer failed and left a broken file
        (0.0009, "film.webm", "[0.001, 1000]"),
    ],
)
def test_a_rate_the_output_cannot_carry_is_one_line(tmp_path, fps, out, range_text):
    path = scene(tmp_path, fps)
    ran = implgen("render", path, "-o", tmp_path / out, "-q")
    assert_one_line(ran, f"{path}: animation.fps: {fps:g} is outside {range_text} for -o {out}")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["anim.yaml"]  # no output, no sidecar, no frame


def test_frame_pngs_take_any_rate_of_the_scene(tmp_path):
    path = scene(tmp_path, 1e-300)
    ran = implgen("render", path, "-o", tmp_path / "f%d.png", "-q")
    assert ran.code == 0, ran.err
    assert (tmp_path / "f0.png").exists() and (tmp_path / "f1.png").exists()


def test_the_slowest_gif(tmp_path):
    lo = FPS_RANGES["gif"][0]
    ran = implgen("render", scene(tmp_path, lo), "-o", tmp_path / "slow.gif", "-q")
    assert ran.code == 0, ran.err
    with Image.open(tmp_path / "slow.gif") as im:
        assert im.n_frames == 2 and im.info["duration"] == 500_000  # 500 s a frame, 50,000 hundredths


@pytest.mark.parametrize("suffix", [".mp4", ".webm"])
@pytest.mark.parametrize("end", [0, 1])
def test_both_ends_of_the_video_range(tmp_path, suffix, end):
    fps = FPS_RANGES["video"][end]
    out = tmp_path / f"film{suffix}"
    ran = implgen("render", scene(tmp_path, fps, frames=3), "-o", out, "-q")
    assert ran.code == 0, ran.err
    assert len(list(iio.imiter(out))) == 3
