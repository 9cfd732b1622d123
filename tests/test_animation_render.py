"""Rendering animations in this process: PNG patterns, videos and GIFs decoded back, frame ranges, resume,
and every frame equal to that frame rendered alone."""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
import yaml
from PIL import Image

from implgen.animation.frames import frames_from_data
from implgen.cli import main as cli_main
from implgen.imagefile import to_uint8
from implgen.scene.render import render

ROOT = Path(__file__).resolve().parent.parent
SPHERE = str(ROOT / "examples" / "shapes" / "sphere.yaml")
FRAMES = 6


def anim_scene(frames: int = FRAMES) -> dict:
    """A small keyed animation: a ball that grows, a camera on an orbit, a light that dims."""
    return {
        "animation": {"frames": frames, "fps": 12},
        "image": {"width": 48, "height": 36, "spp": 2, "max_depth": 3},
        "camera": {"orbit": {"center": [0, 0.5, 0], "radius": 6, "height": 1.5, "turns": 0.5}, "fov": 40},
        "background": [0.2, 0.3, 0.6],
        "lights": [{"position": [3, 8, 4], "intensity": {"keys": {0: 1.0, frames - 1: 0.6}}}],
        "materials": {"floor": {"checker": {"colors": [[1, 1, 1], [0.1, 0.1, 0.1]], "scale": 0.5}}},
        "objects": [
            {"equation": "y", "name": "ground", "material": "floor"},
            {
                "shape": SPHERE,
                "params": {"r": {"keys": {0: 0.4, frames - 1: 1.0}, "ease": "smooth"}},
                "transform": {"translate": [0, 1.1, 0]},
                "material": {"color": [0.9, 0.4, 0.2], "reflectivity": 0.2},
            },
        ],
    }


@pytest.fixture(scope="module")
def anim(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("anim") / "anim.yaml"
    path.write_text(yaml.safe_dump(anim_scene()))
    return path


@pytest.fixture(scope="module")
def alone(anim) -> list[np.ndarray]:
    """Each frame rendered on its own, through the plain still renderer, as the 8-bit picture."""
    fr = frames_from_data(yaml.safe_load(anim.read_text()), anim)
    return [to_uint8(render(fr.scene(f))) for f in range(FRAMES)]


def read(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def test_frames_differ_and_each_equals_the_frame_rendered_alone(tmp_path, anim, alone, capsys):
    assert cli_main(["render", str(anim), "-o", str(tmp_path / "f_%03d.png"), "-q"]) == 0
    assert "wrote 6 frames of 48x36" in capsys.readouterr().out
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == [".f_%03d.png.implgen.json"] + [f"f_{i:03d}.png" for i in range(FRAMES)]  # and the manifest
    for f in range(FRAMES):
        assert np.array_equal(read(tmp_path / f"f_{f:03d}.png"), alone[f]), f
    assert all(not np.array_equal(alone[f], alone[f + 1]) for f in range(FRAMES - 1))  # it moves


def test_a_range_and_a_single_frame(tmp_path, anim, alone):
    assert cli_main(["render", str(anim), "-o", str(tmp_path / "f%d.png"), "--frames", "2:3", "-q"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [".f%d.png.implgen.json", "f2.png", "f3.png"]
    assert np.array_equal(read(tmp_path / "f3.png"), alone[3])
    assert cli_main(["render", str(anim), "-o", str(tmp_path / "one.png"), "--frames", "4", "-q"]) == 0
    assert np.array_equal(read(tmp_path / "one.png"), alone[4])


def test_a_rerun_renders_only_the_missing_frames(tmp_path, anim, alone, capsys):
    pattern = str(tmp_path / "f_%02d.png")
    assert cli_main(["render", str(anim), "-o", pattern, "-q"]) == 0
    capsys.readouterr()
    before = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in tmp_path.iterdir()}  # a freed inode
    # number may come back for a new file: the time it was written tells them apart
    (tmp_path / "f_01.png").unlink()
    (tmp_path / "f_04.png").unlink()
    (tmp_path / ".ig-0123456789ab.tmp").write_bytes(b"half a frame")  # what a crash mid-write leaves
    assert cli_main(["render", str(anim), "-o", pattern, "-q"]) == 0
    assert "wrote 2 frames, 4 already there" in capsys.readouterr().out
    after = {p.name: (p.stat().st_ino, p.stat().st_mtime_ns) for p in tmp_path.iterdir() if p.suffix == ".png"}
    assert {n for n in after if after[n] == before.get(n)} == {f"f_{i:02d}.png" for i in (0, 2, 3, 5)}
    for f in (1, 4):
        assert np.array_equal(read(tmp_path / f"f_{f:02d}.png"), alone[f])


@pytest.mark.parametrize("suffix", [".mp4", ".webm"])
def test_a_video_decodes_back_to_every_frame(tmp_path, anim, alone, suffix):
    out = tmp_path / f"film{suffix}"
    assert cli_main(["render", str(anim), "-o", str(out), "-q"]) == 0
    frames = iio.imread(out, plugin="pyav") if _has_pyav() else np.stack(list(iio.imiter(out)))
    assert frames.shape == (FRAMES, 36, 48, 3)
    # lossy, but each decoded frame is nearest to its own source frame
    for f in range(FRAMES):
        err = [np.abs(frames[f].astype(int) - a.astype(int)).mean() for a in alone]
        assert int(np.argmin(err)) == f and err[f] < 12, (f, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == [out.name]  # the sidecar frames are gone


def _has_pyav() -> bool:
    try:
        import av  # noqa: F401
    except ImportError:
        return False
    return True


def test_a_gif_has_every_frame_and_the_fps(tmp_path, anim, alone):
    """12 fps is 83 ms a frame; a GIF counts in hundredths of a second: 80 ms."""
    out = tmp_path / "loop.gif"
    assert cli_main(["render", str(anim), "-o", str(out), "-q", "--keep-frames"]) == 0
    with Image.open(out) as im:
        assert im.n_frames == FRAMES and im.info["duration"] == 80 and im.info["loop"] == 0
        im.seek(2)
        picture = np.asarray(im.convert("RGB")).astype(int)
    assert np.abs(picture - alone[2]).mean() < 6  # 256 colours
    kept = sorted(p.name for p in (tmp_path / "loop.gif.frames").iterdir())
    assert kept == [".loop.gif.implgen.json"] + [f"{i:04d}.png" for i in range(FRAMES)]


def test_a_video_resumes_from_its_sidecar_frames(tmp_path, anim, capsys):
    out = tmp_path / "film.mp4"
    sidecar = tmp_path / "film.mp4.frames"
    assert cli_main(["render", str(anim), "-o", str(out), "-q", "--frames", "0:3", "--keep-frames"]) == 0
    out.unlink()  # as if the run had died before encoding
    capsys.readouterr()
    mtimes = {p.name: p.stat().st_mtime_ns for p in sidecar.glob("*.png")}
    assert cli_main(["render", str(anim), "-o", str(out), "-q"]) == 0
    assert "wrote 2 frames, 4 already there" in capsys.readouterr().out
    assert len(list(iio.imiter(out))) == FRAMES and not sidecar.exists()
    assert len(mtimes) == 4


def test_frames_share_one_library(tmp_path, anim, monkeypatch):
    """The scene library is built, and loaded (its seal checked), once for the whole animation: not once per
    frame."""
    from implgen.animation import chunks
    from implgen.compile import clib

    chunks.forget_renderers()
    builds, loads = [], []
    real_build, real_load = chunks.build_scene, clib.load
    monkeypatch.setattr(chunks, "build_scene", lambda *a, **k: builds.append(1) or real_build(*a, **k))
    monkeypatch.setattr(clib, "load", lambda *a, **k: loads.append(1) or real_load(*a, **k))
    assert cli_main(["render", str(anim), "-o", str(tmp_path / "f%d.png"), "-q"]) == 0
    assert len(builds) == 1 and len(list(tmp_path.glob("*.png"))) == FRAMES
    assert len(loads) == 1  # before: once more for every frame


def test_the_example_animation_is_valid_on_every_frame():
    path = ROOT / "examples" / "scenes" / "torus_opening.yaml"
    fr = frames_from_data(yaml.safe_load(path.read_text()), path)
    assert fr.count == 48 and fr.params_vary
    b = [fr.scene(f).leaves()[1].params["b"] for f in range(48)]
    assert b[0] < 1.0 < b[-1] and all(x <= y for x, y in zip(b, b[1:]))  # the tube grows past a = 1
    assert os.path.getsize(path) < 4000


@pytest.mark.parametrize(
    "frames, size, threads",
    [(40, (160, 120, 32), ["--threads", "1"]), (300, (40, 30, 24), [])],  # one frame at a time; side by side
)
def test_ctrl_c_in_this_process_stops_at_once_and_the_rerun_resumes(tmp_path, frames, size, threads):
    """The frames render on threads of their own and are written on others: Ctrl-C still ends the command
    within 2 s, in one line, with every frame file whole and no temporary file left."""
    import signal
    import time

    from implgen_proc import implgen, start

    data = anim_scene(frames=frames)
    data["image"].update(width=size[0], height=size[1], spp=size[2])
    scene = tmp_path / "anim.yaml"
    scene.write_text(yaml.safe_dump(data))
    out = tmp_path / "f" / "f%03d.png"
    proc = start("render", scene, "-o", out, "-q", *threads)
    try:
        deadline = time.monotonic() + 90
        while len(list(out.parent.glob("f*.png"))) < 2:
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=30)
        seconds = time.monotonic() - t0
    finally:
        proc.kill()
    assert proc.returncode == 130 and err == "implgen: interrupted\n", (proc.returncode, err[-2000:])
    assert seconds < 2.0, seconds
    kept = sorted(out.parent.glob("f*.png"))
    assert 2 <= len(kept) < frames and not list(out.parent.glob(".ig-*"))
    for p in kept:
        assert read(p).shape == (size[1], size[0], 3)  # whole
    ran = implgen("render", scene, "-o", out, "-q", "--frames", "0:2", timeout=120)
    assert ran.code == 0 and "already there" in ran.out, ran.err


def test_small_frames_render_side_by_side_on_fewer_threads():
    from implgen.animation.chunks import SAMPLES_PER_THREAD, lanes
    from implgen.animation.frames import FrameOptions

    small = FrameOptions(width=32, height=24, spp=2, max_depth=4)
    assert lanes(small, 16) == (16, FrameOptions(32, 24, 2, 4, threads=1))
    big = FrameOptions(width=640, height=480, spp=2, max_depth=4)
    assert lanes(big, 16) == (1, FrameOptions(640, 480, 2, 4, threads=16))
    assert lanes(big, 2)[0] == 1
    middle = FrameOptions(width=100, height=100, spp=1, max_depth=4)  # 10,000 samples a thread on 1 core
    assert lanes(middle, 16)[0] == 16 and 10_000 < SAMPLES_PER_THREAD
    assert lanes(dataclasses.replace(small, threads=3), 16) == (1, dataclasses.replace(small, threads=3))
