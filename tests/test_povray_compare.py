"""bench/povray_compare.py: the .pov text of a scene (camera, plane, polynomial, transform), the exact verdict on
a known hit, a known miss and a tangent ray, the options, report.md from a hand-made results dict; and the tests
that run POV-Ray itself (Debian's povray: its renders of exported scenes, a --quick run end to end on one
scene), skipped when it is missing, failed with IMPLGEN_REQUIRE_ALL set."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent

povray = pytest.importorskip("implgen.export.povray")
if not hasattr(povray, "scene_pov"):
    pytest.skip("the installed implgen predates the scene exporter (pip install .)", allow_module_level=True)

import povray_compare as pc  # noqa: E402

from implgen.scene.load import load_scene, parse_scene  # noqa: E402

TORUS = ROOT / "bench" / "scenes" / "torus.yaml"


def _sphere_scene(r: float = 1.0) -> object:
    return parse_scene(
        {
            "image": {"width": 80, "height": 60},
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
            "objects": [
                {
                    "equation": f"x^2 + y^2 + z^2 - {r * r}",
                    "name": "ball",
                    "bounds": {"x": [-r, r], "y": [-r, r], "z": [-r, r]},
                }
            ],
        },
        "<test>",
    )


def test_pov_text_has_matched_camera_plane_and_polynomial():
    scene = load_scene(TORUS)
    text = povray.scene_pov(scene, 800, 600)
    assert "right -x*1.3333333333333333" in text  # left-handed POV-Ray mirrored back
    angle = float(text.split("angle ")[1].split()[0])
    assert angle == pytest.approx(math.degrees(2 * math.atan(math.tan(math.radians(40) / 2) * 4 / 3)))
    assert "location <0, 2.2000000000000002, 5.5>" in text
    assert "plane { <0, 1, 0>, -0" in text or "plane { <0, 1, 0>, 0" in text
    assert "polynomial { 4," in text and "sturm" in text
    assert "clipped_by { box" in text and "bounded_by { clipped_by }" in text
    assert "assumed_gamma 1.0" in text and "light_source" in text
    cover = povray.scene_pov(scene, 800, 600, coverage=True)
    assert "plane" not in cover and "light_source" not in cover and "ambient 1 diffuse 0" in cover


def test_pov_matrix_is_transposed_for_row_vectors():
    m = np.array([[1.0, 2, 3, 10], [4, 5, 6, 20], [7, 8, 9, 30]])
    vals = [float(v) for v in povray.pov_matrix(m)[len("matrix <") : -1].split(",")]
    p = np.array([0.5, -1.0, 2.0])
    row = p @ np.array(vals[:9]).reshape(3, 3) + np.array(vals[9:])  # POV-Ray: row vector times matrix
    assert np.allclose(row, m[:, :3] @ p + m[:, 3])


def test_exact_verdict_hit_miss_and_tangent():
    scene = _sphere_scene()
    judge = pc.PixelJudge(scene, 80, 60)
    assert judge.hits(40, 30)  # through the centre
    assert not judge.hits(0, 0)  # a corner ray passes far from the ball
    (obj,) = judge.exact.objects
    eye = np.array([0.0, 0.0, 5.0])
    assert obj.meets(eye, np.array([0.0, 0.0, -1.0]))
    assert not obj.meets(eye, np.array([0.0, 0.0, 1.0]))  # pointing away: roots t < 0
    assert obj.meets(np.array([0.0, 1.0, 5.0]), np.array([0.0, 0.0, -1.0]))  # tangent: double root
    assert not obj.meets(np.array([0.0, 1.0 + 2.0**-40, 5.0]), np.array([0.0, 0.0, -1.0]))


def test_camera_ray_matches_the_tracer_convention():
    scene = _sphere_scene()
    o, d = pc.camera_ray(scene, 40.0, 30.0, 80, 60)  # image centre looks at look_at
    assert np.allclose(o, [0, 0, 5]) and np.allclose(d / np.linalg.norm(d), [0, 0, -1])
    _, d = pc.camera_ray(scene, 80.0, 0.0, 80, 60)  # top right corner: +x (right-handed), +y
    assert d[0] > 0 and d[1] > 0
    assert d[1] / -d[2] == pytest.approx(math.tan(math.radians(20)))  # vertical half-fov


@pytest.mark.needs_program("povray")
def test_povray_renders_the_exported_ball(tmp_path):
    exe = shutil.which("povray")
    scene = _sphere_scene()
    pov = tmp_path / "ball.pov"
    pov.write_text(povray.scene_pov(scene, 80, 60, coverage=True))
    out = tmp_path / "ball.png"
    pc.run_povray(exe, pov, out, 80, 60, 1)
    mask = pc.pov_mask(out)
    assert mask[30, 40] and not mask[0, 0]


def _cut_ball_scene(bounds: dict) -> object:
    """A unit ball whose spec box cuts it: bounds in x only ([-inf, inf] elsewhere) or all three axes."""
    return parse_scene(
        {
            "image": {"width": 64, "height": 48},
            "camera": {"position": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
            "objects": [{"equation": "x^2 + y^2 + z^2 - 1", "name": "ball", "bounds": bounds}],
        },
        "<test>",
    )


def test_box_that_cuts_the_surface_is_exported_as_clipped_by():
    box = {"x": [-0.5, 0.5], "y": [-2, 2], "z": [-2, 2]}
    text = povray.scene_pov(_cut_ball_scene(box), 64, 48)
    clip = text.split("clipped_by { box { ")[1].split(" } }")[0]
    lo, hi = (np.array([float(v) for v in part.strip("<>").split(",")]) for part in clip.split(">, <"))
    assert lo[0] == pytest.approx(-0.5, abs=1e-8) and hi[0] == pytest.approx(0.5, abs=1e-8)
    assert lo[0] < -0.5 and hi[0] > 0.5  # grown by 1e-9 of the extent, as the runtime clips
    assert "bounded_by { clipped_by }" in text
    # only x bounded: the planes of the finite bounds
    text = povray.scene_pov(_cut_ball_scene({"x": [-0.5, 0.5]}), 64, 48)
    assert "clipped_by { intersection { plane { x, 0.50000000" in text and "plane { -x, 0.50000000" in text
    assert "bounded_by" not in text


def test_exact_verdict_clips_to_the_box():
    judge = pc.PixelJudge(_cut_ball_scene({"x": [-0.5, 0.5], "y": [-2, 2], "z": [-2, 2]}), 64, 48)
    (obj,) = judge.exact.objects
    eye = np.array([0.0, 0.0, 5.0])
    assert obj.meets(eye, np.array([0.0, 0.0, -1.0]))  # through the middle, inside the box
    # towards x = 0.8 on the sphere's front: outside the box's x range, so no hit (the whole ball would say yes)
    target = np.array([0.8, 0.0, 0.6])
    assert not obj.meets(eye, target - eye)
    full = pc.PixelJudge(_cut_ball_scene({"x": [-2, 2], "y": [-2, 2], "z": [-2, 2]}), 64, 48)
    assert full.exact.hits(eye, target - eye)


@pytest.mark.needs_program("povray")
def test_povray_renders_the_clipped_ball_like_the_exact_verdict(tmp_path):
    """POV-Ray itself, on the exported coverage scene: the ball cut to |x| <= 0.5 covers the pixels whose rays
    the exact verdict says hit inside the box, and not the cut-away sides."""
    scene = _cut_ball_scene({"x": [-0.5, 0.5], "y": [-2, 2], "z": [-2, 2]})
    pov = tmp_path / "cut.pov"
    pov.write_text(povray.scene_pov(scene, 64, 48, coverage=True))
    png = tmp_path / "cut.png"
    pc.run_povray(shutil.which("povray"), pov, png, 64, 48, 1)
    mask = pc.pov_mask(png)
    judge = pc.PixelJudge(scene, 64, 48)
    hits = 0
    for py in range(4, 48, 6):
        for px in range(2, 64, 5):
            assert mask[py, px] == judge.hits(px, py), (px, py)
            hits += int(mask[py, px])
    assert hits >= 5
    # pixel 43 of row 24 looks at the ball's front at x ~ 0.7 (the whole ball spans ~14 pixels either side)
    assert mask[24, 32] and not mask[24, 43] and not judge.hits(43, 24)
    whole = pc.PixelJudge(_cut_ball_scene({"x": [-2, 2], "y": [-2, 2], "z": [-2, 2]}), 64, 48)
    assert whole.hits(43, 24)


def _timing(ours_wall: float, ours_render: float, pov_wall: float, pov_trace: float) -> dict:
    return {
        "ours_wall": ours_wall,
        "ours_render": ours_render,
        "pov_wall": pov_wall,
        "pov_trace": pov_trace,
        "ours_wall_all": [ours_wall],
        "pov_wall_all": [pov_wall],
        "ratio_wall": pov_wall / ours_wall,
        "ratio_render": pov_trace / ours_render,
    }


def _coverage(implgen_right: int, povray_right: int) -> dict:
    return {
        "edge_checked": 20,
        "edge_both_wrong": 1,
        "edge_pixels": 900,
        "pixels": 120000,
        "implgen_hits": 30000,
        "povray_hits": 29000,
        "disputed": 1500,
        "disputed_fraction": 1500 / 120000,
        "only_implgen": 1250,
        "only_povray": 250,
        "checked": implgen_right + povray_right,
        "implgen_right": implgen_right,
        "povray_right": povray_right,
        "check_seconds": 1.5,
        "examples": [],
    }


def test_report_states_the_measurements(tmp_path):
    """write_report on a hand-made results dict: every table row, the speed-ups worked out from the 1- and
    4-thread timings, the images, and the targets' verdicts (degree >= 6 needs 5x on 1 thread, else 2x)."""
    results = {
        "machine": {"cpu": "Test CPU", "cores": 4, "system": "TestOS", "date": "2000-01-02", "load_before": 0.25},
        "povray": "3.7.0.10",
        "width": 400,
        "height": 300,
        "runs": 3,
        "threads": [1, 4],
        "scenes": {
            "torus": {
                "degree": 4,
                "timing": {"1": _timing(2.0, 1.0, 6.0, 5.0), "4": _timing(0.5, 0.25, 2.0, 2.5)},
                "coverage": _coverage(10, 2),
            },
            "chmutov": {
                "degree": 8,
                "timing": {"1": _timing(1.0, 0.5, 4.0, 3.0), "4": _timing(0.5, 0.25, 1.0, 1.0)},
                "coverage": _coverage(3, 3),
            },
        },
        "degree": [
            {
                "degree": 2,
                "coeffs_ns": 2.34,
                "solve_ns": 20.5,
                "total_ns": 80.0,
                "roots_per_ray": 1.5,
                "hit_fraction": 0.5,
                "ops_coeffs": 20,
                "ops_value": 11,
                "ops_gradient": 30,
            }
        ],
    }
    pc.write_report(results, tmp_path)
    text = (tmp_path / "report.md").read_text()
    lines = text.splitlines()
    assert lines[0] == "# implgen against POV-Ray 3.7.0.10" and text.endswith("\n")
    assert "on 2000-01-02: Test CPU, 4 cores, TestOS. 400x300, 1 sample, median of 3 interleaved run(s)" in text
    assert "Load average before the run: 0.25" in text
    headings = [line for line in lines if line.startswith("## ")]
    assert [h.split(" (")[0] for h in headings] == [
        "## Render time",
        "## Multi-core speed-up",
        "## Coverage",
        "## Cost against degree",
        "## Targets",
    ]
    # render time: one row per scene and thread count, ratio = POV-Ray / implgen
    assert "| torus | 4 | 1 | 2.000 | 6.000 | 3.00x | 1.000 | 5.000 | 5.00x |" in lines
    assert "| torus | 4 | 4 | 0.500 | 2.000 | 4.00x | 0.250 | 2.500 | 10.00x |" in lines
    assert "| chmutov | 8 | 1 | 1.000 | 4.000 | 4.00x | 0.500 | 3.000 | 6.00x |" in lines
    # speed-up: 1 thread against all (the last thread count)
    assert "| torus | 4.00x (render 4.00x) | 3.00x (trace 2.00x) |" in lines
    assert "| chmutov | 2.00x (render 2.00x) | 4.00x (trace 3.00x) |" in lines
    assert "| torus | 30000 | 29000 | 1500 | 1.250 | 1250 | 250 | 12 | 10 | 2 | 20 | 1 |" in lines
    assert "| chmutov | 30000 | 29000 | 1500 | 1.250 | 1250 | 250 | 6 | 3 | 3 | 20 | 1 |" in lines
    for name in ("torus", "chmutov"):
        assert f"![{name}]({name}_side_by_side.png) ![{name} disagreement]({name}_disagreement.png)" in lines
    assert "| 2 | 2.3 | 20.5 | 80.0 | 1.50 | 20 | 11 | 30 |" in lines
    assert "![cost against degree](degree_cost.png)" in lines
    targets = lines[lines.index("## Targets") + 2 :]
    assert targets == [
        "- torus (degree 4), 1 thread, at least 2x faster: wall 3.00x MET; render-only 5.00x MET",
        "- chmutov (degree 8), 1 thread, at least 5x faster: wall 4.00x MISSED; render-only 6.00x MET",
        "- torus: disputed pixels checked 12; implgen wrong on 2, POV-Ray wrong on 10: fewer disagreements with "
        "the exact reference MET",
        "- chmutov: disputed pixels checked 6; implgen wrong on 3, POV-Ray wrong on 3: fewer disagreements with "
        "the exact reference TIE (not strictly met)",
    ]


def test_options_quick_defaults_and_unknown_scene(capsys):
    quick = pc.parse_options(["--quick", "-o", "out"])
    assert (quick.runs, quick.w, quick.h, quick.scenes) == (1, 400, 300, list(pc.SCENES))
    assert quick.out == Path("out").resolve() and (quick.max_verdicts, quick.edge_checks) == (1500, 300)
    full = pc.parse_options(["--runs", "5", "--scenes", "heart,,torus"])
    assert (full.runs, full.w, full.h, full.scenes, full.quick) == (5, 800, 600, ["heart", "torus"], False)
    with pytest.raises(SystemExit) as exit_info:
        pc.parse_options(["--scenes", "torus,nope"])
    assert exit_info.value.code == 2 and "unknown scene(s) nope" in capsys.readouterr().err


@pytest.mark.needs_program("povray")
def test_quick_run_end_to_end(tmp_path, monkeypatch):
    """main --quick on the torus, the degree family cut to degrees 2 and 4: every step runs and the outputs
    agree with each other (the coverage counts add up, the report has the measured rows)."""
    real_family = pc.degree_family
    monkeypatch.setattr(pc, "degree_family", lambda degrees, rays, reps: real_family(degrees[:2], rays, reps))
    argv = ["--quick", "--scenes", "torus", "-o", str(tmp_path), "--max-verdicts", "40", "--edge-checks", "20"]
    assert pc.main(argv) == 0
    r = json.loads((tmp_path / "results.json").read_text())
    assert (r["width"], r["height"], r["runs"], list(r["scenes"])) == (400, 300, 1, ["torus"])
    torus = r["scenes"]["torus"]
    assert torus["degree"] == 4 and list(torus["timing"]) == [str(t) for t in r["threads"]]
    for t in torus["timing"].values():
        assert t["ours_wall"] > 0 and t["pov_wall"] > 0 and t["ratio_wall"] == t["pov_wall"] / t["ours_wall"]
    c = torus["coverage"]
    assert c["pixels"] == 400 * 300 and c["disputed"] == c["only_implgen"] + c["only_povray"]
    assert c["implgen_hits"] - c["only_implgen"] == c["povray_hits"] - c["only_povray"] > 1000
    assert c["checked"] == min(c["disputed"], 40) == c["implgen_right"] + c["povray_right"]
    assert c["edge_checked"] == 20 and c["edge_pixels"] > 20
    assert [d["degree"] for d in r["degree"]] == [2, 4] and all(d["ops_coeffs"] > 0 for d in r["degree"])
    report = (tmp_path / "report.md").read_text()
    assert f"| torus | 4 | 1 | {torus['timing']['1']['ours_wall']:.3f} |" in report
    assert f"| torus | {c['implgen_hits']} | {c['povray_hits']} | {c['disputed']} |" in report
    for name in ("torus_side_by_side.png", "torus_disagreement.png", "degree_cost.png", "pov/torus.pov"):
        assert (tmp_path / name).stat().st_size > 0, name
