"""Generated shapes as Embree 3 user geometry (runtime_c/embree_shape.c) against implgen's own tracer, ray by ray,
on the same camera: the same object on >= 99.99 % of pixels, the same distance to 1e-9 where both hit a shape,
the same occlusion answers on shadow rays, every disagreeing pixel decided in exact arithmetic; rays that
start on a surface, ray masks, intersection and occlusion filters, packets of 4, 8 and 16 against single rays;
examples/embree/ built by `make embree-example` and run under ASan and UBSan. Skipped (or failed with
IMPLGEN_REQUIRE_ALL) without Debian's libembree-dev."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from embree_scenes import build_driver, exact_judge, read_agree, showcase  # bench/ (pytest's pythonpath)

ROOT = Path(__file__).resolve().parents[1]


pytestmark = pytest.mark.needs_library("embree3")
W, H = 320, 180  # 57,600 pixels: 99.99 % allows 5 disagreements


@pytest.fixture(scope="module")
def driver(tmp_path_factory) -> Path:
    """The checks, built with ASan and UBSan (any report aborts the run)."""
    return build_driver(tmp_path_factory.mktemp("embree") / "embree_check", sanitize=True)


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("embree_scene") / "scene.txt"
    path.write_text(showcase().text())
    return path


def run(driver: Path, *args, config: str = "") -> str:
    """config: Embree's device configuration ("isa=avx2" runs an AVX2-only machine's kernels on any newer one)."""
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0", UBSAN_OPTIONS="print_stacktrace=1")
    env["IG_EMBREE_CONFIG"] = config
    proc = subprocess.run([str(driver), *map(str, args)], capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


def numbers(line: str) -> list[int]:
    return [int(v) for v in re.findall(r"\d+", line)]


def agreement(driver: Path, scene_file: Path, tmp_path: Path, inst: int) -> dict[str, np.ndarray]:
    out = tmp_path / "answers.bin"
    run(driver, "agree", scene_file, W, H, out, inst)
    return read_agree(out, W * H)


def test_every_pixel_against_the_tracer_with_the_exact_judge(driver, scene_file, tmp_path):
    a = agreement(driver, scene_file, tmp_path, inst=0)
    scene = showcase()
    n, nshapes = W * H, len(scene.objects)
    ot, oe, tt, te = a["obj_tracer"], a["obj_embree"], a["t_tracer"], a["t_embree"]
    assert (ot >= 0).sum() > n // 3 and set(np.unique(ot)) == {-1, *range(nshapes + 1)}  # every object is seen
    same = ot == oe
    assert same.mean() >= 0.9999, f"{(~same).sum()} pixels name different objects"
    both = same & (ot >= 0)
    shape = both & (ot < nshapes)
    rel = np.zeros(n)
    rel[both] = np.abs(te[both] - tt[both]) / tt[both]
    assert rel[shape].max() <= 1e-9, f"worst relative distance {rel[shape].max():.3g} on a shape"
    ground = both & (ot == nshapes)  # two float triangles against the double plane: float's own rounding
    assert rel[ground].max() <= 1e-6
    shadow = a["occ_tracer"] >= 0
    assert shadow.sum() == (ot >= 0).sum() and 0 < a["occ_tracer"][shadow].sum() < shadow.sum()
    occ_differ = shadow & (a["occ_tracer"] != a["occ_embree"])
    assert occ_differ.sum() <= 0.0001 * shadow.sum()
    # every pixel the two disagree on, decided exactly: the object each names, against the other's
    judge = exact_judge(scene)
    wrong_embree = 0
    for k in np.flatnonzero(~same):
        o, d = a["o"][k], a["d"][k]
        tracer, embree = (int(ot[k]), float(tt[k])), (int(oe[k]), float(te[k]))
        e_right, t_right = judge.right(embree, tracer, o, d), judge.right(tracer, embree, o, d)
        assert e_right or t_right, f"pixel {k}: neither {tracer} nor {embree} holds exactly"
        wrong_embree += not e_right
    assert wrong_embree == 0
    # shadow rays the two answer differently, decided too: does any object truly meet the ray in [0, 1]?
    for k in np.flatnonzero(occ_differ):
        truth = judge.hits(a["so"][k], a["sd"][k], 0, 1)
        assert bool(a["occ_embree"][k]) == truth, f"shadow ray of pixel {k}: Embree says {a['occ_embree'][k]}"
    # the judge itself, on pixels the two agree on: the answer holds, a miss or a distance 1 % off does not
    rng = np.random.default_rng(5)
    for k in rng.choice(np.flatnonzero(both), 12, replace=False):
        o, d, hit = a["o"][k], a["d"][k], (int(ot[k]), float(tt[k]))
        assert judge.right(hit, (-1, np.inf), o, d) and not judge.right((-1, np.inf), hit, o, d)
        assert not judge.right((hit[0], 1.01 * hit[1]), hit, o, d)
    lit, dark = np.flatnonzero(shadow & (a["occ_tracer"] == 0)), np.flatnonzero(a["occ_tracer"] == 1)
    for k in [*rng.choice(lit, 4, replace=False), *rng.choice(dark, 4, replace=False)]:
        truth = judge.hits(a["so"][k], a["sd"][k], 0, 1)
        assert truth == bool(a["occ_tracer"][k])


def test_instances_place_shapes_in_float(driver, scene_file, tmp_path):
    """Embree's instances carry float transforms and move the ray in float: the same objects, distances to
    float's rounding (the double transforms of ig_embree_prim_init are what give 1e-9)."""
    a = agreement(driver, scene_file, tmp_path, inst=1)
    ot, oe = a["obj_tracer"], a["obj_embree"]
    same = ot == oe
    assert same.mean() >= 0.9999, f"{(~same).sum()} pixels name different objects"
    hit = same & (ot >= 0)
    rel = np.abs(a["t_embree"][hit] - a["t_tracer"][hit]) / a["t_tracer"][hit]
    assert np.median(rel) < 1e-7 and rel.max() < 1e-5


# Embree's kernels for each kind of machine, all run on this one: what it runs natively (its packet widths).
ISAS = {"isa=sse4.2": "4", "isa=avx2": "4 8", "": None}


@pytest.mark.parametrize("config", ISAS, ids=lambda c: c or "native")
@pytest.mark.parametrize("k", [-1, 2])
def test_packets_of_4_8_16_answer_as_single_rays(driver, scene_file, k, config):
    """k = 2: every query through a context filter that rejects object 2, so the filter sees packets too.

    What Embree 3 promises for a lane the valid mask switches off holds at the widths an ISA runs natively
    (the mask is passed down to the adapter, which must not touch the lane); a wider packet is traced as a
    stream of single rays, where only tnear > tfar switches a lane off. The driver marks off-lanes that way at
    emulated widths, so every ISA is held to what it promises. Found on an AVX2-only machine, where packets of
    16 are emulated: 509 off-lanes came back traced."""
    line = run(driver, "packets", scene_file, 96, 54, k, config=config)
    m = re.match(
        r"packets: (\d+) lanes of width 4, 8, 16 checked, (\d+) differ; .*: (\d+) calls; native widths ?(.*)$",
        line.strip(),
    )
    assert m and int(m[1]) == 3 * 96 * 54 and int(m[2]) == 0, line
    assert (int(m[3]) > 0) == (k >= 0), line
    if ISAS[config] is not None:  # the configuration took: the ISA asked for, not this machine's best
        assert m[4] == ISAS[config], line


def test_threads_tracing_at_once_answer_as_one(driver, scene_file):
    line = run(driver, "threads", scene_file, 64, 36, 3)
    assert line.strip() == f"threads: 3 threads x {64 * 36} rays against one thread, 0 differ", line


def test_rays_leaving_a_surface_do_not_hit_it_again(driver, scene_file):
    line = run(driver, "surface", scene_file, 96, 54)
    rays, early, ids, dist = numbers(line)[:4]
    assert rays > 2000 and early == 0 and ids * 10000 <= rays and dist == 0, line


def test_ray_masks_pick_the_geometries(driver, scene_file):
    line = run(driver, "masks", scene_file, 96, 54)
    assert "mask 4 0 hits" in line, line


@pytest.mark.parametrize("k", [0, 2])
def test_filters_reject_an_object_as_if_it_were_not_there(driver, scene_file, k):
    line = run(driver, "filter", scene_file, 96, 54, k)
    assert "context filter 0 differ, geometry filter 0 differ, 0 distances differ" in line, line
    assert "occlusion differs on 0 and 0" in line, line


def test_the_example_builds_with_make_and_runs_clean_under_sanitizers(tmp_path):
    if shutil.which("make") is None:
        pytest.skip("make not installed")
    out = tmp_path / "make"
    proc = subprocess.run(
        ["make", "-s", "-C", str(ROOT), "embree-example", f"EMBREE_OUT={out}"], capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stdout + proc.stderr
    from PIL import Image

    img = np.asarray(Image.open(out / "scene.ppm"))
    assert img.shape == (360, 640, 3)
    colours = {tuple(c) for c in img.reshape(-1, 3)[::97]}
    assert len(colours) > 200  # shading, shadows and a checker, not a flat fill
    sky = img[0, 0]
    assert (np.abs(img.astype(int) - sky).sum(axis=2) > 30).mean() > 0.5  # the scene fills most of the frame

    from conftest import C_SANITIZE
    from implgen.compile.clib import WARNING_FLAGS, compiler

    srcs = [ROOT / "examples/embree/scene.c", ROOT / "runtime_c/embree_shape.c", ROOT / "runtime_c/shape.c"]
    srcs += sorted(p for p in (ROOT / "runtime_c").glob("roots*.c") if p.name != "roots_bench.c")
    srcs += [ROOT / "generated" / f"{s}.c" for s in ("torus_y", "heart", "chmutov8", "sphere")]
    exe = tmp_path / "scene_asan"
    cmd = [
        compiler(),
        *WARNING_FLAGS,
        *C_SANITIZE,
        f"-I{ROOT / 'runtime_c'}",
        f"-I{ROOT / 'generated'}",
        "-o",
        str(exe),
    ]
    proc = subprocess.run([*cmd, *map(str, srcs), "-lembree3", "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=0")
    proc = subprocess.run([str(exe), str(tmp_path / "small.ppm"), "160", "90"], capture_output=True, env=env)
    assert proc.returncode == 0, proc.stderr
    small = np.asarray(Image.open(tmp_path / "small.ppm"))
    assert small.shape == (90, 160, 3)


def test_the_benchmark_mode_runs_clean(driver, scene_file):
    """bench/embree.py's timing loop (its figures are the benchmark's business, not a test's)."""
    line = run(driver, "bench", scene_file, 32, 18, 1)
    m = re.match(
        r"bench: rays 576 tracer \S+ embree1 \S+ embree8 \S+ tracer_shadow \S+ embree_shadow \S+ hits (\d+)", line
    )
    assert m and int(m[1]) > 0, line


def test_the_snippet_in_the_docs_compiles(tmp_path):
    """docs/embree.md's C block, as a user copies it, with the project's warnings."""
    from implgen.compile.clib import WARNING_FLAGS, compiler

    text = (ROOT / "docs/embree.md").read_text()
    blocks = re.findall(r"```c\n(.*?)```", text, re.S)
    assert len(blocks) == 1 and "ig_embree_new_geometry" in blocks[0]
    src = tmp_path / "snippet.c"
    src.write_text(blocks[0])
    cmd = [compiler(), *WARNING_FLAGS, f"-I{ROOT / 'runtime_c'}", f"-I{ROOT / 'generated'}", "-c", str(src)]
    proc = subprocess.run([*cmd, "-o", str(tmp_path / "snippet.o")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
