"""Scene validation, the build cache, and small renders checked by properties (not byte-exact images)."""

from __future__ import annotations

import ctypes
import math
from pathlib import Path

import numpy as np
import pytest

from implgen.cli import main as cli_main
from implgen.compile import clib
from implgen.errors import UserError
from implgen.scene import build
from implgen.scene.load import load_scene, parse_scene
from implgen.scene.render import RenderInfo, render
from implgen.scene.tracer import CScene
from implgen.scene.transform import parse_transform

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "examples" / "shapes"
SCENES = ROOT / "examples" / "scenes"


def base_scene(**over):
    sc = {
        "image": {"width": 64, "height": 48, "spp": 1, "max_depth": 6},
        "camera": {"position": [0, 2, 6], "look_at": [0, 0.5, 0], "fov": 40},
        "background": [0.2, 0.4, 0.9],
        "lights": [{"position": [0, 10, 0]}],
        "materials": {
            "floor": {
                "checker": {"colors": [[1, 1, 1], [0, 0, 0]], "scale": 1.0},
                "ambient": 0.1,
                "diffuse": 0.9,
                "specular": 0,
            }
        },
        "objects": [{"equation": "y", "name": "ground", "material": "floor"}],
    }
    sc.update(over)
    return sc


def scene_at(tmp_path: Path, data: dict, name: str = "s.yaml") -> Path:
    import yaml

    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


# ------------------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    "patch, key",
    [
        ({"camera": {"position": [0, 0, 1], "look_at": [0, 0, 1]}}, "camera.look_at"),
        ({"image": {"width": 0}}, "image.width"),
        ({"image": {"spp": 1.5}}, "image.spp"),
        ({"lights": [{"position": [0, 1]}]}, "lights[0].position"),
        ({"objects": [{"equation": "y", "material": "nope"}]}, "objects[0].material"),
        ({"objects": [{"shape": "missing.yaml"}]}, "objects[0].shape"),
        ({"objects": [{"equation": "y", "transform": {"scale": [1, 0, 1]}}]}, "objects[0].transform"),
        ({"objects": [{"equation": "y", "transform": {"rotate": [0, 0]}}]}, "objects[0].transform.rotate"),
        ({"objects": [{"union": [{"equation": "y"}]}]}, "objects[0].union"),
        ({"objects": [{"equation": "y", "colour": 1}]}, "objects[0].colour"),
        ({"materials": {"m": {"transparency": 2}}}, "materials.m.transparency"),
        ({"objects": [{"shape": str(SHAPES / "sphere.yaml"), "params": {"q": 1}}]}, "objects[0].params.q"),
        ({"objects": [{"equation": "y", "name": "p"}, {"equation": "x +* y"}]}, "objects[1]"),
        (
            {"objects": [{"difference": [{"equation": "y"}, {"equation": "x", "transform": {"axes": [[1, 0, 0]]}}]}]},
            "objects[0].difference[1].transform",
        ),
    ],
)
def test_bad_scene_names_file_and_key(tmp_path: Path, patch: dict, key: str) -> None:
    path = scene_at(tmp_path, base_scene(**patch))
    with pytest.raises(UserError) as err:
        load_scene(path)
    msg = str(err.value)
    assert msg.startswith(str(path)) and key in msg and "\n" not in msg


def test_cli_bad_scene_exit_2_writes_nothing(tmp_path: Path, capsys) -> None:
    path = scene_at(tmp_path, base_scene(objects=[{"equation": "y", "material": "nope"}]))
    out = tmp_path / "out.png"
    assert cli_main(["render", str(path), "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "objects[0].material" in err
    assert list(tmp_path.iterdir()) == [path]


def test_transforms() -> None:
    m = parse_transform("s", "t", {"scale": 2, "rotate": {"axis": [0, 0, 1], "angle": 90}, "translate": [1, 2, 3]})
    # x axis: scaled to 2, rotated onto +y, moved by (1, 2, 3)
    assert np.allclose(m[:, :3] @ [1, 0, 0] + m[:, 3], [1, 4, 3])
    basis = parse_transform("s", "t", {"position": [5, 0, 0], "axes": [[0, 2, 0], [-3, 0, 0], [0, 0, 1]]})
    assert np.allclose(basis[:, :3], [[0, -3, 0], [2, 0, 0], [0, 0, 1]]) and np.allclose(basis[:, 3], [5, 0, 0])
    ai = np.linalg.inv(basis[:, :3])  # its inverse maps the position back to the origin
    assert np.allclose(ai @ basis[:, :3], np.eye(3)) and np.allclose(ai @ ([5, 0, 0] - basis[:, 3]), 0)
    seq = parse_transform("s", "t", [{"translate": [1, 0, 0]}, {"rotate": [0, 0, 90]}])
    assert np.allclose(seq[:, :3] @ [0, 0, 0] + seq[:, 3], [0, 1, 0])  # translate first, then rotate


# ------------------------------------------------------------------------------------- build cache


def test_cache_second_build_compiles_nothing(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("IMPLGEN_CACHE", str(tmp_path / "cache"))
    sc = parse_scene(base_scene(objects=[{"equation": "y + 0.25*x", "name": "tilted"}]), tmp_path / "a.yaml")
    first = build.build_scene(sc)
    assert first.generated == 1 and first.library.exists()
    calls = []
    real = clib.subprocess.run

    def spy(cmd, *a, **k):
        if "-shared" in cmd:
            calls.append(cmd)
        return real(cmd, *a, **k)

    monkeypatch.setattr(clib.subprocess, "run", spy)
    sc2 = parse_scene(base_scene(objects=[{"equation": "y + 0.25*x", "name": "tilted"}]), tmp_path / "a.yaml")
    second = build.build_scene(sc2)
    assert second.library == first.library and second.generated == 0 and calls == []
    # a changed spec regenerates and rebuilds
    sc3 = parse_scene(base_scene(objects=[{"equation": "y + 0.5*x", "name": "tilted"}]), tmp_path / "a.yaml")
    third = build.build_scene(sc3)
    assert third.generated == 1 and third.library != first.library and len(calls) == 1


def test_a_new_shape_compiles_only_itself_and_the_glue(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("IMPLGEN_CACHE", str(tmp_path / "cache"))
    build.build_scene(parse_scene(base_scene(objects=[{"equation": "y + 0.25*x", "name": "tilted"}]), "a.yaml"))
    compiled: list[str] = []
    real = clib.subprocess.run

    def spy(cmd, *a, **k):
        if "-c" in cmd:
            compiled.append(Path(cmd[cmd.index("-c") + 1]).name)
        return real(cmd, *a, **k)

    monkeypatch.setattr(clib.subprocess, "run", spy)
    sc = parse_scene(base_scene(objects=[{"equation": "x^2 + y^2 + z^2 - 1", "name": "ball"}]), "b.yaml")
    res = build.build_scene(sc)
    assert len(compiled) == 2 and "ball.c" in compiled and any(c.startswith("glue-") for c in compiled)
    # the library works: the ray along -z from z = 5 meets the unit sphere at t = 4
    assert CScene(sc, res).intersect([0, 0, 5], [0, 0, -1]).t == pytest.approx(4.0)


def test_only_the_scenes_shapes_are_compiled(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.setenv("IMPLGEN_CACHE", str(tmp_path / "cache"))
    sc = load_scene(SCENES / "csg_trio.yaml")
    res = build.build_scene(sc)
    assert sorted(e.spec.name for e in res.entries) == ["floor", "sphere", "torus_y"]


# ------------------------------------------------------------------------------------- renders


def torus_scene() -> dict:
    return base_scene(
        camera={"position": [0, 6, 0.001], "look_at": [0, 0, 0], "fov": 50},
        objects=[
            {
                "shape": str(SHAPES / "torus_y.yaml"),
                "params": {"a": 1.0, "b": 0.3},
                "material": {"color": [1, 0, 0]},
                "transform": {"translate": [0, 1, 0]},
            }
        ],
    )


def test_torus_hole_shows_background() -> None:
    img = render(parse_scene(torus_scene()), width=64, height=64, threads=2)
    bg = np.array([0.2, 0.4, 0.9], dtype=np.float32)
    assert np.allclose(img[32, 32], bg)  # looking down the axis through the hole
    assert img[32, 32 + 13, 0] > 0.5  # the tube (radius 1 at ~13 px from the centre) is red
    assert np.allclose(img[1, 1], bg)  # the corner is outside the torus too
    assert np.isfinite(img).all()


def test_shadow_darker_than_lit_ground() -> None:
    sc = base_scene(
        camera={"position": [0, 8, 0.001], "look_at": [0, 0, 0], "fov": 60},
        materials={"g": {"color": [1, 1, 1], "ambient": 0.1, "diffuse": 0.9, "specular": 0}},
        objects=[
            {"equation": "y", "name": "ground", "material": "g"},
            {
                "shape": str(SHAPES / "sphere.yaml"),
                "params": {"r": 0.5},
                "transform": {"translate": [2, 2, 0]},
                "material": "g",
            },
        ],
        lights=[{"position": [2, 10, 0]}],
    )
    parsed = parse_scene(sc)
    c = CScene(parsed, build.build_scene(parsed))
    # straight below the sphere: shadowed (ambient only); far from it: lit
    shadow = c.trace([2, 1, 0], [0, -1, 0])
    lit = c.trace([-2, 1, 0], [0, -1, 0])
    assert np.allclose(shadow, 0.1, atol=1e-9)
    assert lit[0] > 0.8 and np.all(shadow < 0.5 * lit)
    c.close()


def test_glass_sphere_flips_checkerboard() -> None:
    # a wall of vertical stripes z = -4 (x < 0 half white, x > 0 half black, seen head on); a glass ball
    # between the camera and the wall inverts the image: through the ball's left part we see the right half.
    sc = base_scene(
        camera={"position": [0, 0, 8], "look_at": [0, 0, 0], "fov": 30},
        lights=[{"position": [0, 0, 8]}],
        materials={
            "wall": {
                "checker": {"colors": [[1, 1, 1], [0, 0, 0]], "scale": 100.0},
                "ambient": 1.0,
                "diffuse": 0,
                "specular": 0,
            }
        },
        objects=[
            {"equation": "z + 4", "name": "wall", "material": "wall", "transform": {"translate": [0.0, 50.0, 0]}},
            {
                "shape": str(SHAPES / "sphere.yaml"),
                "params": {"r": 1.0},
                "material": {
                    "color": [1, 1, 1],
                    "ambient": 0,
                    "diffuse": 0,
                    "specular": 0,
                    "transparency": 1.0,
                    "ior": 1.5,
                },
            },
        ],
    )
    parsed = parse_scene(sc)
    c = CScene(parsed, build.build_scene(parsed))
    eye = [0, 0, 8]
    direct_left = c.trace(eye, [-1.5, 0.2, -8 - 4])  # misses the ball: x < 0 -> cell floor(x/100) = -1
    direct_right = c.trace(eye, [1.5, 0.2, -8 - 4])
    through_left = c.trace(eye, [-0.5, 0.05, -8])  # passes through the ball's left half
    through_right = c.trace(eye, [0.5, 0.05, -8])
    assert not np.allclose(direct_left, direct_right)
    assert np.allclose(through_left, direct_right, atol=0.1) and np.allclose(through_right, direct_left, atol=0.1)
    c.close()


@pytest.mark.parametrize("scene", sorted(p.name for p in SCENES.glob("*.yaml")))
def test_example_scenes_render_without_nan(scene: str) -> None:
    info = RenderInfo()
    img = render(SCENES / scene, width=48, height=36, spp=1, threads=2, info=info)
    assert img.shape == (36, 48, 3) and np.isfinite(img).all()
    assert info.nonfinite == 0  # no sample came out NaN (the renderer would have masked it)
    assert img.std() > 0.01  # not a blank image


def test_cli_writes_png(tmp_path: Path) -> None:
    from PIL import Image

    out = tmp_path / "t.png"
    assert (
        cli_main(
            [
                "render",
                str(SCENES / "torus_shadow.yaml"),
                "-o",
                str(out),
                "--width",
                "40",
                "--height",
                "30",
                "--spp",
                "1",
                "-q",
            ]
        )
        == 0
    )
    with Image.open(out) as im:
        assert im.size == (40, 30) and im.mode == "RGB"
    assert [p.name for p in tmp_path.iterdir()] == ["t.png"]


def test_threads_do_not_change_the_image() -> None:
    a = render(SCENES / "csg_trio.yaml", width=60, height=26, spp=2, threads=1)
    b = render(SCENES / "csg_trio.yaml", width=60, height=26, spp=2, threads=2)
    assert np.array_equal(a, b)


def test_docs_example_scene_is_valid() -> None:
    """The complete scene example in the README parses and renders (as if it lived in examples/scenes/)."""
    import re

    import yaml

    text = (ROOT / "docs" / "formats.md").read_text()
    block = re.search(r"### The scene format\n\n```yaml\n(.*?)```", text, re.S).group(1)
    sc = parse_scene(yaml.safe_load(block), SCENES / "doc_example.yaml")
    img = render(sc, width=32, height=24, spp=1, threads=2)
    assert np.isfinite(img).all()


def test_stratified_samples_measure_pixel_coverage() -> None:
    """A vertical colour edge crosses one pixel at a known fraction; the N-rooks samples are stratified in x,
    so the pixel's value is that fraction of the two colours to within 1/spp (spp = 1: the pixel centre)."""
    # wall z = 0 seen head on from (2, 0, 10); tan(fov/2) = 0.5 and 8x2 pixels: pixel k covers x in
    # [-18 + 5k, -13 + 5k]; the checker edge x = 0 splits pixel 3 into 3/5 (x < 0) and 2/5 (x > 0)
    fov = 2 * math.degrees(math.atan(0.5))
    sc = parse_scene(
        base_scene(
            image={"width": 8, "height": 2, "spp": 16},
            camera={"position": [2, 0, 10], "look_at": [2, 0, 0], "fov": fov},
            lights=[],
            materials={
                "w": {
                    "checker": {"colors": [[1, 1, 1], [0, 0, 0]], "scale": 1000.0},
                    "ambient": 1.0,
                    "diffuse": 0,
                    "specular": 0,
                }
            },
            objects=[{"equation": "z", "name": "wall", "material": "w", "transform": {"translate": [0, 500, 0]}}],
        )
    )
    left = render(sc, spp=1, threads=1)[0, 0, 0]  # x < 0 side colour
    right = render(sc, spp=1, threads=1)[0, 7, 0]
    assert {float(left), float(right)} == {0.0, 1.0}
    for spp in (4, 16, 64):
        v = float(render(sc, spp=spp, threads=1)[:, 3, 0].mean())
        want = 0.6 * left + 0.4 * right
        assert abs(v - want) <= 1.0 / spp + 1e-6, (spp, v, want)


def test_python_ray_queries_and_spawn_offset() -> None:
    """CScene.intersect/spawn: a unit sphere scaled by 1e3 far from the origin; the spawned origin sits off the
    surface by the hit's error bound, on the side the new ray goes to, and a ray from it re-finds the far side."""
    sc = parse_scene(
        base_scene(
            objects=[{"shape": str(SHAPES / "sphere.yaml"), "transform": {"scale": 1e3, "translate": [5e3, 0, 0]}}]
        )
    )
    c = CScene(sc, build.build_scene(sc))
    h = c.intersect([5e3, 0, -1e4], [0, 0, 1])
    assert h is not None and abs(h.t - 9e3) < 1e-9 * 9e3 and h.entering == 1
    assert 0 < h.err < 1e-9 * 1e3
    inward = (ctypes.c_double * 3)()  # the origin of a secondary ray leaving h, offset by its error bound
    c.lib.rt_spawn_origin(ctypes.byref(h), (ctypes.c_double * 3)(0, 0, 1), inward)
    inward = list(inward)
    assert inward[2] > h.p[2] and abs(inward[2] - h.p[2] - h.err) <= 1e-12 * 1e4
    far = c.intersect(inward, [0, 0, 1])
    assert far is not None and abs(far.p[2] - 1e3) < 1e-9 * 1e3 and far.entering == 0
    c.close()


def test_progress_bar_reaches_every_row(capsys) -> None:
    render(SCENES / "torus_shadow.yaml", width=40, height=30, spp=1, threads=2, progress=True)
    err = capsys.readouterr().err
    assert "30/30" in err


@pytest.mark.parametrize(
    "option, value, line",
    [
        ("width", 16385, "--width: 16385 is outside [1, 16384]"),
        ("height", 16385, "--height: 16385 is outside [1, 16384]"),
        ("spp", 4097, "--spp: 4097 is outside [1, 4096]"),
        ("threads", 1025, "--threads: 1025 is outside [1, 1024]"),
        ("max_depth", 65, "--max-depth: 65 is outside [0, 64]"),
        ("max_depth", -1, "--max-depth: -1 is outside [0, 64]"),
    ],
)
def test_render_and_the_command_check_options_alike(tmp_path: Path, capsys, option: str, value: int, line: str):
    """One table of option ranges (scene/render.py's OPTION_RANGES): render() and `implgen render` reject a
    value out of range with the same line, before building anything."""
    with pytest.raises(UserError) as err:
        render(SCENES / "csg_trio.yaml", **{option: value})
    assert str(err.value) == line
    out = tmp_path / "x.png"
    argv = ["render", str(SCENES / "csg_trio.yaml"), "-o", str(out), f"--{option.replace('_', '-')}", str(value)]
    assert cli_main(argv) == 2
    assert capsys.readouterr().err.strip().endswith(line) and not out.exists()
