"""Frames on a real Dask LocalCluster of two worker processes: every frame equal to the frame rendered
alone in this process, a worker killed in the middle of a task, the --local-workers and --cluster commands."""

from __future__ import annotations

import functools
import os
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from implgen.animation.batch import Runner, render_frames
from implgen.animation.frameout import plan_output
from implgen.animation.frames import FrameOptions, frames_from_data, render_frame_png
from implgen.cli import main as cli_main
from implgen.imagefile import to_uint8
from implgen.scene.render import render
from test_animation_render import FRAMES, anim_scene

distributed = pytest.importorskip("distributed")
cloudpickle = pytest.importorskip("cloudpickle")
cloudpickle.register_pickle_by_value(sys.modules[__name__])  # the workers cannot import this test file


@pytest.fixture(scope="module")
def client():
    from dask.distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address="127.0.0.1:0"
    )
    with Client(cluster) as c:
        c.wait_for_workers(2, timeout=120)
        yield c
    cluster.close()


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    path = tmp_path_factory.mktemp("dist") / "anim.yaml"
    path.write_text(yaml.safe_dump(anim_scene()))
    return frames_from_data(yaml.safe_load(path.read_text()), path)


@pytest.fixture(scope="module")
def alone(frames) -> list[np.ndarray]:
    return [to_uint8(render(frames.scene(f))) for f in range(FRAMES)]


def opts_of(frames) -> FrameOptions:
    sc = frames.first
    return FrameOptions(width=sc.width, height=sc.height, spp=sc.spp, max_depth=sc.max_depth, threads=1)


def read(path: Path) -> np.ndarray:
    with Image.open(path) as im:
        return np.asarray(im.convert("RGB"))


def worker_pids(client) -> set[int]:
    return set(client.run(os.getpid).values())


def test_every_frame_from_the_workers_equals_the_frame_rendered_alone(tmp_path, client, frames, alone):
    out = plan_output(tmp_path / "f_%02d.png", FRAMES, FRAMES - 1, 48, 36)
    order: list[int] = []
    report = render_frames(frames, range(FRAMES), opts_of(frames), out, Runner(client=client), on_written=order.append)
    assert order == list(range(FRAMES)) and report.written == order  # written in order
    for f in range(FRAMES):
        assert np.array_equal(read(out.path(f)), alone[f]), f
    # and the bytes are those of the same frame encoded here: nothing but the PNG crossed the wire
    here = render_frame_png(frames.scene(3), opts_of(frames))
    assert out.path(3).read_bytes() == here
    assert report.bytes_moved == sum(p.stat().st_size for p in tmp_path.glob("*.png"))


def _dies_once(marker: str, *args):
    """The frame task, except that the third task started anywhere (or a later one, if two start at once) kills
    its worker process, once: no cleanup and no exception, as a crash or `kill -9` would."""
    import os

    from implgen.animation.chunks import render_chunk

    started = Path(marker).with_suffix(".started")
    started.mkdir(exist_ok=True)
    fd = os.open(started / f"{os.getpid()}-{os.urandom(4).hex()}", os.O_CREAT | os.O_EXCL | os.O_WRONLY)
    os.close(fd)
    if len(os.listdir(started)) >= 3:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pass
        else:
            os.write(fd, str(os.getpid()).encode())
            os.close(fd)
            os._exit(1)
    return render_chunk(*args)


def test_a_worker_killed_mid_task_still_ends_with_every_frame(tmp_path, client, frames, alone):
    marker = tmp_path / "killed"
    pids_before = worker_pids(client)
    out = plan_output(tmp_path / "out" / "f_%02d.png", FRAMES, FRAMES - 1, 48, 36)
    runner = Runner(client=client, task=functools.partial(_dies_once, str(marker)))
    report = render_frames(frames, range(FRAMES), opts_of(frames), out, runner)
    assert marker.exists(), "the fault was not injected"
    killed = int(marker.read_text())
    assert killed in pids_before
    assert report.written == list(range(FRAMES))
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == [".f_%02d.png.implgen.json"] + [f"f_{f:02d}.png" for f in range(FRAMES)]  # no temporary file
    for f in range(FRAMES):
        assert np.array_equal(read(out.path(f)), alone[f]), f
    client.wait_for_workers(2, timeout=120)  # the nanny started a new worker process in its place
    assert killed not in worker_pids(client)


def test_chunks_of_frames_from_the_workers_are_the_serial_files_byte_for_byte(tmp_path, client, frames):
    serial = plan_output(tmp_path / "here" / "f_%02d.png", FRAMES, FRAMES - 1, 48, 36)
    render_frames(frames, range(FRAMES), opts_of(frames), serial, Runner())
    for chunk in (None, 4):  # chosen as the run goes, and 4 frames a task (the last one 2)
        out = plan_output(tmp_path / f"dask{chunk}" / "f_%02d.png", FRAMES, FRAMES - 1, 48, 36)
        report = render_frames(frames, range(FRAMES), opts_of(frames), out, Runner(client=client, chunk=chunk))
        assert report.written == list(range(FRAMES))
        for f in range(FRAMES):
            assert out.path(f).read_bytes() == serial.path(f).read_bytes(), (chunk, f)


def _dies_with_its_chunk(marker: str, *args):
    """The chunk task, except that the first chunk of several frames to finish kills its worker process
    before it hands them back, once: every frame of it is lost and must be rendered again elsewhere."""
    import os

    from implgen.animation.chunks import render_chunk

    result = render_chunk(*args)
    if len(args[0]) > 1:
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            return result
        os.write(fd, str(os.getpid()).encode())
        os.close(fd)
        os._exit(1)
    return result


def test_a_worker_killed_with_a_chunk_done_still_ends_with_every_frame(tmp_path, client, frames, alone):
    marker = tmp_path / "killed"
    out = plan_output(tmp_path / "out" / "f_%02d.png", FRAMES, FRAMES - 1, 48, 36)
    runner = Runner(client=client, task=functools.partial(_dies_with_its_chunk, str(marker)), chunk=3)
    report = render_frames(frames, range(FRAMES), opts_of(frames), out, runner)
    assert marker.exists(), "the fault was not injected"
    assert report.written == list(range(FRAMES))
    names = sorted(p.name for p in (tmp_path / "out").iterdir())
    assert names == [".f_%02d.png.implgen.json"] + [f"f_{f:02d}.png" for f in range(FRAMES)]
    for f in range(FRAMES):
        assert np.array_equal(read(out.path(f)), alone[f]), f
    client.wait_for_workers(2, timeout=120)


def test_the_cluster_command_on_a_running_scheduler(tmp_path, client, frames, alone, capsys):
    scene = Path(frames.source)
    address = client.scheduler.address
    assert cli_main(["render", str(scene), "-o", str(tmp_path / "f%d.png"), "--cluster", address, "-q"]) == 0
    assert "(2 Dask workers)" in capsys.readouterr().out
    for f in range(FRAMES):
        assert np.array_equal(read(tmp_path / f"f{f}.png"), alone[f]), f


def test_local_workers_command(tmp_path, frames, alone, capsys):
    scene = Path(frames.source)
    out = tmp_path / "film.gif"
    assert cli_main(["render", str(scene), "-o", str(out), "--local-workers", "2", "-q", "--keep-frames"]) == 0
    assert "(2 Dask workers)" in capsys.readouterr().out
    for f in range(FRAMES):
        assert np.array_equal(read(tmp_path / "film.gif.frames" / f"{f:04d}.png"), alone[f]), f
    with Image.open(out) as im:
        assert im.n_frames == FRAMES


def test_an_unreachable_scheduler_is_one_line(tmp_path, frames, capsys, monkeypatch):
    from implgen.animation import cluster

    monkeypatch.setattr(cluster, "CONNECT_TIMEOUT", 1)
    scene = Path(frames.source)
    args = ["render", str(scene), "-o", str(tmp_path / "f%d.png"), "--cluster", "tcp://127.0.0.1:9", "-q"]
    assert cli_main(args) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--cluster: cannot reach a Dask scheduler at tcp://127.0.0.1:9" in err
    assert list(tmp_path.iterdir()) == []


def test_a_tiled_still_equals_the_still_rendered_in_one_piece(tmp_path, client, frames):
    from implgen.animation.batch import bands

    sc = frames.scene(2)
    opts = FrameOptions(width=48, height=37, spp=3, max_depth=3, threads=1)  # 37 rows: bands of 5 and 4 rows
    whole = render(sc, width=48, height=37, spp=3, max_depth=3, threads=2)
    # each band, rendered here as floats, is exactly those rows of the whole image
    edges = bands(37, 8)
    assert edges[0][0] == 0 and edges[-1][1] == 37 and {b - a for a, b in edges} == {4, 5}
    for y0, y1 in edges:
        band = render(sc, width=48, height=37, spp=3, max_depth=3, threads=1, rows=(y0, y1))
        assert np.array_equal(band, whole[y0:y1]), (y0, y1)
    # and assembled from tasks on the cluster, bit for bit the 8-bit picture of the whole
    out = plan_output(tmp_path / "still.png", 1, 2, 48, 37)
    report = render_frames(frames, range(2, 3), opts, out, Runner(client=client), tiles=8)
    assert np.array_equal(read(out.target), to_uint8(whole)) and report.written == [2]


def test_the_tiles_command(tmp_path, client, frames, alone, capsys):
    scene = Path(frames.source)
    assert cli_main(["render", str(scene), "-o", str(tmp_path / "t.png"), "--frames", "1", "--tiles", "3", "-q"]) == 0
    assert "in 3 tiles each" in capsys.readouterr().out
    assert np.array_equal(read(tmp_path / "t.png"), alone[1])
    # every frame of an animation in tiles, on the cluster: frames x tiles tasks
    args = [
        "render",
        str(scene),
        "-o",
        str(tmp_path / "f%d.png"),
        "--tiles",
        "5",
        "--cluster",
        client.scheduler.address,
    ]
    assert cli_main([*args, "-q"]) == 0
    for f in range(FRAMES):
        assert np.array_equal(read(tmp_path / f"f{f}.png"), alone[f]), f


def test_workers_need_neither_the_scene_file_nor_its_spec_files(tmp_path, client):
    """Tasks carry the validated scene, shapes included: the files may be gone (or on another machine)."""
    spec = tmp_path / "lens.yaml"
    spec.write_text("name: lens\nequation: x^2 + y^2 + 4*z^2 - r^2\nparams: {r: 1.0}\n")
    data = anim_scene(frames=3)
    data["objects"][1]["shape"] = "lens.yaml"
    scene = tmp_path / "lens_anim.yaml"
    scene.write_text(yaml.safe_dump(data))
    frames = frames_from_data(yaml.safe_load(scene.read_text()), scene)
    spec.unlink()
    scene.unlink()
    out = plan_output(tmp_path / "f%d.png", 3, 2, 48, 36)
    render_frames(frames, range(3), opts_of(frames), out, Runner(client=client))
    for f in range(3):
        assert np.array_equal(read(out.path(f)), to_uint8(render(frames.scene(f)))), f


def _always_dies(*args):
    os._exit(1)


def test_a_task_that_keeps_killing_workers_ends_in_one_line(tmp_path, frames):
    import dask
    from dask.distributed import Client, LocalCluster

    from implgen.errors import UserError

    with dask.config.set({"distributed.scheduler.allowed-failures": 0}):
        cluster = LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address="127.0.0.1:0"
        )
        try:
            with Client(cluster) as c:
                out = plan_output(tmp_path / "out" / "f_%02d.png", FRAMES, FRAMES - 1, 48, 36)
                runner = Runner(client=c, task=_always_dies)
                with pytest.raises(UserError) as err:
                    render_frames(frames, range(FRAMES), opts_of(frames), out, runner)
        finally:
            cluster.close()
    assert "lost its worker" in str(err.value) and "\n" not in str(err.value)
    assert not list((tmp_path / "out").glob("*.png"))  # no frame, not even a temporary one
    assert not list((tmp_path / "out").glob(".ig-*"))
