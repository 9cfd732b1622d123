"""Chunks of frames and the writer (animation/chunks.py, writer.py): chunk sizes that cover the frames once and
keep the last round balanced, chunks whose pixels are the frames rendered alone, validated frames kept rather
than parsed again, and frames put in place in order, whole, whatever order their flushes finish in."""

from __future__ import annotations

import math
import pickle
import time
from collections import deque
from pathlib import Path

import numpy as np
import pytest
import yaml

from implgen.animation import chunks
from implgen.animation.batch import Runner, _jobs
from implgen.animation.chunks import MAX_CHUNK, SHARES, Pace, Part, render_chunk
from implgen.animation.frameout import plan_output
from implgen.animation.frames import FrameOptions, frames_from_data, render_frame_png
from implgen.animation.writer import OrderedWriter
from implgen.errors import UserError
from implgen.imagefile import decode_png, encode_png, to_uint8
from implgen.scene.load import parse_scene
from implgen.scene.render import render
from test_animation_render import anim_scene


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    path = tmp_path_factory.mktemp("chunks") / "anim.yaml"
    path.write_text(yaml.safe_dump(anim_scene(frames=8)))
    return frames_from_data(yaml.safe_load(path.read_text()), path)


def handed_out(pace: Pace, frames: int, threads: int, per_frame: float | None) -> list[int]:
    sizes, left = [], frames
    while left:
        n = pace.size(left, threads)
        assert 1 <= n <= left
        sizes.append(n)
        left -= n
        if per_frame is not None:
            pace.record(n, n * per_frame)
    return sizes


@pytest.mark.parametrize("threads", [1, 2, 16])
@pytest.mark.parametrize("per_frame", [0.0005, 0.01, 0.3, 5.0])
def test_chunk_sizes_cover_the_frames_and_balance_the_last_round(threads, per_frame):
    sizes = handed_out(Pace(), 1000, threads, per_frame)
    assert sum(sizes) == 1000 and sizes[0] == 1  # one frame until a render time is known
    left = 1000
    for n in sizes:
        assert n == 1 or n <= math.ceil(left / (SHARES * threads))  # what is left stays shared out
        assert n <= MAX_CHUNK and (n == 1 or n * per_frame <= chunks.TARGET_SECONDS)
        left -= n
    if per_frame >= chunks.TARGET_SECONDS:
        assert set(sizes) == {1}  # a frame that takes longer than a chunk should is a chunk of its own
    if per_frame <= 0.001 and threads <= 2:
        assert len(sizes) < 60  # small frames: few tasks (one a frame was 1000)


def test_a_fixed_chunk_size():
    assert handed_out(Pace(fixed=3), 10, 4, None) == [3, 3, 3, 1]


def test_jobs_are_runs_of_the_missing_frames_in_order(frames):
    missing = [0, 1, 2, 4, 5, 7]  # 3 and 6 there already
    opts = FrameOptions(width=8, height=6, spp=1, max_depth=1, threads=1)
    jobs = list(_jobs(frames, missing, [None], opts, Runner(chunk=4), False, Pace(fixed=4)))
    assert [part for part, _ in jobs] == [Part((0, 1, 2, 4)), Part((5, 7))]
    scenes, got_opts, rows, fold, encode = jobs[0][1]
    assert [s is frames.scene(f) for s, f in zip(scenes, (0, 1, 2, 4))] == [True] * 4
    assert (got_opts, rows, fold, encode) == (opts, None, False, False)  # pixels here; PNGs come from Dask
    tiles = list(_jobs(frames, [5], [(0, 3), (3, 6)], opts, Runner(), False, Pace()))
    assert [part for part, _ in tiles] == [Part((5,), 0), Part((5,), 1)] and str(tiles[1][0]) == "5-1"


def test_a_chunk_is_its_frames_rendered_alone(frames):
    opts = FrameOptions(width=40, height=30, spp=2, max_depth=3, threads=2)
    todo = (1, 2, 3, 6)
    res = render_chunk(tuple(frames.scene(f) for f in todo), opts, encode=False)
    pngs = render_chunk(tuple(frames.scene(f) for f in todo), opts, encode=True)
    for f, pixels, png in zip(todo, res.images, pngs.images):
        alone = render(frames.scene(f), width=40, height=30, spp=2, max_depth=3, threads=1)
        assert np.array_equal(pixels, to_uint8(alone)), f
        assert png == render_frame_png(frames.scene(f), opts) == encode_png(pixels), f  # the same bytes
    band = render_chunk((frames.scene(2),), opts, rows=(7, 19), encode=False).images[0]
    assert np.array_equal(band, res.images[1][7:19])


def test_validated_frames_are_kept_not_parsed_again(frames, monkeypatch):
    from implgen.animation import frames as frames_module

    again = [parse_scene(frames.data, frames.source, frame=f) for f in range(frames.count)]
    monkeypatch.setattr(frames_module, "parse_scene", lambda *a, **k: pytest.fail("parsed again"))
    for f in range(frames.count):
        assert pickle.dumps(frames.scene(f)) == pickle.dumps(again[f]), f


def test_too_many_frames_to_keep_are_parsed_on_demand(tmp_path, monkeypatch):
    from implgen.animation import frames as frames_module

    monkeypatch.setattr(frames_module, "KEEP_OBJECT_FRAMES", 10)  # 8 frames x (1 keyed object + 1) is more
    fr = frames_from_data(anim_scene(frames=8), tmp_path / "anim.yaml")
    assert fr.kept == []
    assert pickle.dumps(fr.scene(5)) == pickle.dumps(parse_scene(fr.data, fr.source, frame=5))


def slow_stage(out, delays: dict[int, float]):
    """out.stage, slowed down per frame (the frame is read from the pixels' first value)."""
    real = out.stage

    def stage(image):
        time.sleep(delays.get(int(image[0, 0, 0]), 0.0))
        return real(image)

    return stage


def test_frames_are_put_in_place_in_order_whatever_order_their_flushes_end(tmp_path):
    out = plan_output(tmp_path / "f_%02d.png", 12, 11, 4, 3)
    out.prepare()
    out.stage = slow_stage(out, {0: 0.3, 1: 0.2, 5: 0.25})  # frames 2-4 and 6-11 are staged before them
    real_commit = out.commit
    commits: list[tuple[int, set]] = []

    def commit(frame, tmp):
        commits.append((frame, {int(p.stem[2:]) for p in tmp_path.glob("f_*.png")}))
        real_commit(frame, tmp)

    out.commit = commit
    writer = OrderedWriter(out, threads=4)
    images = [np.full((3, 4, 3), f, dtype=np.uint8) for f in range(12)]
    placed: list[int] = []
    for f in range(12):
        placed += writer.put(f, images[f])
    placed += writer.close()
    assert placed == list(range(12))
    assert commits == [(f, set(range(f))) for f in range(12)]  # each after every frame ahead of it
    for f in range(12):
        assert np.array_equal(decode_png(out.path(f).read_bytes()), images[f])
    assert not list(tmp_path.glob(".ig-*"))


def test_a_writer_left_behind_removes_what_it_staged(tmp_path):
    out = plan_output(tmp_path / "f_%02d.png", 6, 5, 4, 3)
    out.prepare()
    out.stage = slow_stage(out, {0: 0.3})
    writer = OrderedWriter(out, threads=2)
    for f in range(6):
        assert writer.put(f, np.full((3, 4, 3), f, dtype=np.uint8)) == []  # frame 0 holds the rest back
    writer.abandon()
    assert list(tmp_path.iterdir()) == []  # neither a frame nor a temporary file


def test_a_frame_that_cannot_be_written_is_one_line(tmp_path):
    out = plan_output(tmp_path / "f_%02d.png", 3, 2, 4, 3)
    out.prepare()

    def full(image):
        raise OSError(28, "No space left on device")

    out.stage = full
    writer = OrderedWriter(out)
    with pytest.raises(UserError) as err:
        writer.put(0, b"png")
        writer.close()
    writer.abandon()
    assert str(err.value).endswith("cannot write frame 0: No space left on device")
    assert "\n" not in str(err.value) and Path(tmp_path).exists()


class _CutDeque(deque):
    """A deque whose first append is cut by Ctrl-C: the frame's staging has been handed to a thread already."""

    cut = False

    def append(self, item):
        if not self.cut:
            self.cut = True
            raise KeyboardInterrupt
        super().append(item)


def test_ctrl_c_anywhere_in_the_writer_leaves_no_temporary_file(tmp_path):
    """Before: a frame staged while Ctrl-C came was left as a temporary file, and a frame renamed just before
    it was renamed again, which failed ('cannot write frame 1: No such file or directory', status 2)."""
    out = plan_output(tmp_path / "f_%02d.png", 4, 3, 4, 3)
    out.prepare()
    writer = OrderedWriter(out)
    writer.pending = _CutDeque()
    with pytest.raises(KeyboardInterrupt):
        writer.put(0, np.zeros((3, 4, 3), dtype=np.uint8))
    writer.abandon()
    assert list(tmp_path.iterdir()) == []

    real_commit = out.commit

    def commit_then_cut(frame, tmp):
        real_commit(frame, tmp)
        raise KeyboardInterrupt

    out.commit = commit_then_cut
    writer = OrderedWriter(out)
    with pytest.raises(KeyboardInterrupt):
        for f in range(4):
            writer.put(f, np.full((3, 4, 3), f, dtype=np.uint8))
        writer.close()
    writer.abandon()
    assert [p.name for p in tmp_path.iterdir()] == ["f_00.png"]  # in place whole, and nothing else
