"""bench/povray_compare.py pieces, fast and without POV-Ray: the .pov text of a scene (camera, plane,
polynomial, transform), and the exact verdict on a known hit, a known miss and a tangent ray."""

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
    assert "polynomial { 4," in text and "sturm" in text and "bounded_by { box" in text
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


def test_povray_renders_the_exported_ball(tmp_path):
    exe = shutil.which("povray")
    if not exe:
        pytest.skip("povray is not installed")
    scene = _sphere_scene()
    pov = tmp_path / "ball.pov"
    pov.write_text(povray.scene_pov(scene, 80, 60, coverage=True))
    out = tmp_path / "ball.png"
    pc.run_povray(exe, pov, out, 80, 60, 1)
    mask = pc.pov_mask(out)
    assert mask[30, 40] and not mask[0, 0]
