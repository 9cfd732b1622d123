"""bench/povray_compare.py pieces, fast and without POV-Ray: the .pov text of a scene (camera, plane,
polynomial, transform), and the exact verdict on a known hit, a known miss and a tangent ray. Two tests run
POV-Ray itself (Debian's povray): skipped when it is missing, failed with IMPLGEN_REQUIRE_ALL set."""

from __future__ import annotations

import math
import shutil
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "bench"))

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
    judge = pc.ExactJudge(scene, 80, 60)
    assert judge.hits(40, 30)  # through the centre
    assert not judge.hits(0, 0)  # a corner ray passes far from the ball
    obj = judge.objects[0]
    eye = np.array([0.0, 0.0, 5.0])
    assert judge.ray_hits(obj, eye, np.array([0.0, 0.0, -1.0]))
    assert not judge.ray_hits(obj, eye, np.array([0.0, 0.0, 1.0]))  # pointing away: roots t < 0
    assert judge.ray_hits(obj, np.array([0.0, 1.0, 5.0]), np.array([0.0, 0.0, -1.0]))  # tangent: double root
    assert not judge.ray_hits(obj, np.array([0.0, 1.0 + 2.0**-40, 5.0]), np.array([0.0, 0.0, -1.0]))


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
    judge = pc.ExactJudge(_cut_ball_scene({"x": [-0.5, 0.5], "y": [-2, 2], "z": [-2, 2]}), 64, 48)
    obj = judge.objects[0]
    eye = np.array([0.0, 0.0, 5.0])
    assert judge.ray_hits(obj, eye, np.array([0.0, 0.0, -1.0]))  # through the middle, inside the box
    # towards x = 0.8 on the sphere's front: outside the box's x range, so no hit (the whole ball would say yes)
    target = np.array([0.8, 0.0, 0.6])
    assert not judge.ray_hits(obj, eye, target - eye)
    full = pc.ExactJudge(_cut_ball_scene({"x": [-2, 2], "y": [-2, 2], "z": [-2, 2]}), 64, 48)
    assert full.ray_hits(full.objects[0], eye, target - eye)


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
    judge = pc.ExactJudge(scene, 64, 48)
    hits = 0
    for py in range(4, 48, 6):
        for px in range(2, 64, 5):
            assert mask[py, px] == judge.hits(px, py), (px, py)
            hits += int(mask[py, px])
    assert hits >= 5
    # pixel 43 of row 24 looks at the ball's front at x ~ 0.7 (the whole ball spans ~14 pixels either side)
    assert mask[24, 32] and not mask[24, 43] and not judge.hits(43, 24)
    whole = pc.ExactJudge(_cut_ball_scene({"x": [-2, 2], "y": [-2, 2], "z": [-2, 2]}), 64, 48)
    assert whole.hits(43, 24)


def test_integer_ray_polynomial_is_a_positive_multiple_of_the_exact_one():
    """ExactJudge.ray_poly works on integers; SymPy's expansion of f(o' + t d') over Q is the reference."""
    from fractions import Fraction

    import sympy as sp

    scene = load_scene(TORUS)
    judge = pc.ExactJudge(scene, 80, 60)
    obj = judge.objects[0]
    leaf = next(lf for lf in scene.leaves() if lf.spec.degree == 4)
    o, d = pc.camera_ray(scene, 41.5, 33.5, 80, 60)
    oo, dd = judge.object_ray(obj, o, d)
    t = sp.Symbol("t")
    subs = {pc.param_symbol(k): sp.Rational(Fraction(float(v))) for k, v in leaf.params.items()}
    f = leaf.spec.f.xreplace(subs)
    names = {s.name: s for s in f.free_symbols}
    assert set(names) == {"x", "y", "z"}
    line = {names[n]: sp.Rational(oo[k]) + sp.Rational(dd[k]) * t for k, n in enumerate("xyz")}
    want = [Fraction(int(c.p), int(c.q)) for c in reversed(sp.Poly(sp.expand(f.xreplace(line)), t).all_coeffs())]
    got = judge.ray_poly(obj, o, d)
    ratio = Fraction(got[-1]) / want[-1]
    assert ratio > 0 and all(Fraction(g) == ratio * w for g, w in zip(got, want))
