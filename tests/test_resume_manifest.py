"""Resume trusts only frames made by the same settings (scene, options, implgen's version): a stale frame is
rendered again, never kept.

A manifest beside the frames records what made them (the scene's digest, the size and the options that change
pixels). A rerun skips a frame only when the manifest matches and the file is a PNG of the run's size; frames
made otherwise are rendered again, or a frame pattern is refused in one line when some of them lie outside
the run. Never a mixed set. Each frame is on the disk (fsync) before it is renamed into place.
"""

from __future__ import annotations

import os
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import yaml
from PIL import Image

from implgen_proc import assert_one_line, implgen
from test_animation_render import FRAMES, anim_scene


def write_scene(tmp_path: Path, **changes) -> Path:
    data = anim_scene()
    data.update(changes)
    path = tmp_path / "anim.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def size(path: Path) -> tuple[int, int]:
    with Image.open(path) as im:
        return im.size


def pixels(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def ok(*args) -> str:
    ran = implgen("render", *args, "-q")
    assert ran.code == 0 and ran.err == "", ran.err[-3000:]
    return ran.out


def test_a_pattern_rendered_again_at_another_size_is_one_size(tmp_path):
    scene = write_scene(tmp_path)
    out = tmp_path / "f" / "f_%02d.png"
    ok(scene, "-o", out, "--frames", "0:2")
    said = ok(scene, "-o", out, "--width", "24", "--height", "18")
    sizes = {size(p) for p in out.parent.glob("*.png")}
    assert sizes == {(24, 18)}, sizes  # before: frames 0-2 at 48x36 kept beside 3-5 at 24x18, exit 0
    assert len(list(out.parent.glob("*.png"))) == FRAMES
    assert "3 frames there rendered again (width 48, now 24, height 36, now 18)" in said, said


def test_a_pattern_whose_stale_frames_lie_outside_the_run_is_refused(tmp_path):
    scene = write_scene(tmp_path)
    out = tmp_path / "f" / "f_%02d.png"
    ok(scene, "-o", out)
    before = {p.name: p.read_bytes() for p in out.parent.iterdir()}
    ran = implgen("render", scene, "-o", out, "--frames", "0:1", "--width", "24", "--height", "18", "-q")
    assert_one_line(
        ran, f"-o {out}: 6 frame files there were made otherwise (width 48, now 24", "4 of them are outside"
    )
    assert {p.name: p.read_bytes() for p in out.parent.iterdir()} == before  # nothing touched


def test_an_edited_scene_renders_every_frame_again(tmp_path):
    out = tmp_path / "f" / "f_%02d.png"
    scene = write_scene(tmp_path)
    ok(scene, "-o", out, "--frames", "0:2")
    scene = write_scene(tmp_path, background=[0.9, 0.1, 0.1])  # same size, same options, other pixels
    said = ok(scene, "-o", out)
    assert "wrote 6 frames" in said and "the scene or its shapes changed" in said, said
    alone = tmp_path / "alone"
    ok(scene, "-o", alone / "a_%02d.png")
    for f in range(FRAMES):
        assert np.array_equal(pixels(out.parent / f"f_{f:02d}.png"), pixels(alone / f"a_{f:02d}.png")), f


def test_an_edited_shape_file_renders_every_frame_again(tmp_path):
    spec = tmp_path / "ball.yaml"
    spec.write_text("name: ball\nequation: x^2 + y^2 + z^2 - r^2\nparams: {r: 1.0}\n")
    data = anim_scene()
    data["objects"][1]["shape"] = str(spec)
    scene = tmp_path / "anim.yaml"
    scene.write_text(yaml.safe_dump(data))
    out = tmp_path / "f_%d.png"
    ok(scene, "-o", out)
    spec.write_text("name: ball\nequation: x^2 + 2*y^2 + z^2 - r^2\nparams: {r: 1.0}\n")  # the scene is the same
    said = ok(scene, "-o", out)
    assert "wrote 6 frames" in said and "the scene or its shapes changed" in said, said


def test_the_same_command_again_renders_nothing(tmp_path):
    scene = write_scene(tmp_path)
    out = tmp_path / "f_%d.png"
    ok(scene, "-o", out)
    stamps = {p.name: p.stat().st_mtime_ns for p in tmp_path.glob("f_*.png")}
    said = ok(scene, "-o", out, "--threads", "1", "--tiles", "2")  # neither changes a pixel
    assert "wrote 0 frames, 6 already there" in said, said
    assert {p.name: p.stat().st_mtime_ns for p in tmp_path.glob("f_*.png")} == stamps


def test_a_frame_that_is_not_a_whole_png_is_rendered_again(tmp_path):
    """What a power loss can leave without fsync: the name in place, the bytes not."""
    scene = write_scene(tmp_path)
    out = tmp_path / "f_%d.png"
    ok(scene, "-o", out)
    good = (tmp_path / "f_2.png").read_bytes()
    (tmp_path / "f_2.png").write_bytes(b"")
    (tmp_path / "f_4.png").write_bytes(good[:10])
    said = ok(scene, "-o", out)
    assert "wrote 2 frames, 4 already there" in said, said
    assert (tmp_path / "f_2.png").read_bytes() == good


def test_a_gif_resumed_at_another_size_holds_frames_of_its_size(tmp_path):
    scene = write_scene(tmp_path)
    out = tmp_path / "loop.gif"
    ok(scene, "-o", out, "--frames", "0:3", "--keep-frames")
    out.unlink()  # as if the first run had died before encoding
    ok(scene, "-o", out, "--width", "24", "--height", "18")
    with Image.open(out) as im:
        assert im.size == (24, 18) and im.n_frames == FRAMES
        for f in range(FRAMES):
            im.seek(f)
            assert im.convert("RGB").size == (24, 18)  # before: 48x36 frames in a 24x18 GIF
    assert not (tmp_path / "loop.gif.frames").exists()


def test_a_video_resumed_at_another_size_is_made_at_that_size(tmp_path):
    scene = write_scene(tmp_path)
    out = tmp_path / "film.mp4"
    ok(scene, "-o", out, "--frames", "0:3", "--keep-frames")
    old = out.read_bytes()
    out.unlink()
    ok(scene, "-o", out, "--width", "24", "--height", "18")  # before: a ValueError traceback
    frames = np.stack(list(iio.imiter(out)))
    assert frames.shape == (FRAMES, 18, 24, 3) and out.read_bytes() != old


def test_a_sidecar_without_a_manifest_is_not_trusted(tmp_path):
    """Frames from an older implgen, or copied in: no record of what made them, so they are made again."""
    scene = write_scene(tmp_path)
    out = tmp_path / "loop.gif"
    sidecar = tmp_path / "loop.gif.frames"
    sidecar.mkdir()
    Image.new("RGB", (48, 36), (255, 0, 255)).save(sidecar / "0001.png")
    said = ok(scene, "-o", out, "--keep-frames")
    assert "wrote 6 frames" in said and "1 frame there rendered again" in said, said
    assert not np.array_equal(pixels(sidecar / "0001.png")[0, 0], [255, 0, 255])


def test_every_frame_is_on_the_disk_before_its_rename(tmp_path, monkeypatch):
    from implgen.animation import frameout
    from implgen.animation.batch import Runner, render_frames
    from implgen.animation.frames import FrameOptions, load_frames

    frames = load_frames(write_scene(tmp_path))
    out = frameout.plan_output(tmp_path / "f_%d.png", FRAMES, FRAMES - 1, 48, 36)
    events: list[tuple[str, str]] = []
    real_fsync, real_replace = os.fsync, os.replace

    def fsync(fd):
        events.append(("fsync", os.readlink(f"/proc/self/fd/{fd}") if os.path.exists("/proc/self/fd") else str(fd)))
        return real_fsync(fd)

    def replace(src, dst):
        events.append(("replace", str(src)))
        return real_replace(src, dst)

    monkeypatch.setattr(os, "fsync", fsync)
    monkeypatch.setattr(os, "replace", replace)
    opts = FrameOptions(width=48, height=36, spp=1, max_depth=2, threads=1)
    render_frames(frames, range(FRAMES), opts, out, Runner())
    renames = [i for i, (what, _) in enumerate(events) if what == "replace"]
    assert len(renames) == FRAMES + 1  # the manifest, then each frame
    for i in renames:
        src = events[i][1]
        assert ("fsync", src) in events[:i], (src, events[:i])


def test_a_pattern_name_near_the_limit_still_gets_a_manifest(tmp_path):
    """The manifest's name adds 14 bytes to the pattern's: past 255, it takes a short hashed name instead."""
    scene = write_scene(tmp_path)
    out = tmp_path / ("a" * 240 + "%04d.png")
    ok(scene, "-o", out)
    manifests = [p.name for p in tmp_path.glob(".implgen-*.json")]
    assert len(manifests) == 1 and len(list(tmp_path.glob("a*.png"))) == FRAMES
    assert "wrote 0 frames, 6 already there" in ok(scene, "-o", out)
