"""The two-sided material: `inside` colours the back (f < 0) side of a surface. Checked on exact cases: with
only ambient light (ambient 1, no lights) the colour seen along a ray is the base colour of the side it hits."""

from __future__ import annotations

import numpy as np
import pytest

from implgen.errors import UserError
from implgen.scene.build import build_scene
from implgen.scene.load import parse_scene
from implgen.scene.tracer import CScene

FLAT = {"ambient": 1.0, "diffuse": 0.0, "specular": 0.0}
RED, BLUE = [0.9, 0.1, 0.1], [0.1, 0.2, 0.8]


def scene(objects: list, inside: list | None = BLUE) -> CScene:
    mat = {"color": RED, **FLAT}
    if inside is not None:
        mat["inside"] = inside
    data = {"background": [0, 0, 0], "materials": {"two": mat}, "objects": objects}
    sc = parse_scene(data, "two_sided.yaml")
    return CScene(sc, build_scene(sc))


BALL = {"equation": "x^2 + y^2 + z^2 - 1", "name": "ball", "material": "two"}


def test_a_surface_shows_its_inside_colour_from_inside() -> None:
    cs = scene([BALL])
    assert np.allclose(cs.trace([0, 0, 5], [0, 0, -1]), RED)  # from outside: the front, f > 0 side
    assert np.allclose(cs.trace([0, 0, 0], [0, 0, -1]), BLUE)  # from the centre: the back of the sphere
    assert np.allclose(cs.trace([0.3, -0.2, 0.1], [1, 2, 3]), BLUE)


def test_the_side_follows_the_sign_of_f_not_the_equation_text() -> None:
    """1 - |p|^2 = 0 is the same sphere with inside and outside swapped: f < 0 is now outside the ball."""
    flipped = dict(BALL, equation="1 - x^2 - y^2 - z^2")
    cs = scene([flipped])
    assert np.allclose(cs.trace([0, 0, 5], [0, 0, -1]), BLUE)
    assert np.allclose(cs.trace([0, 0, 0], [0, 0, -1]), RED)


def test_a_csg_solid_seen_from_inside_shows_the_inside_colour() -> None:
    """The cap {|p| < 1, z < -0.5}: entered through its flat face from above, left through the sphere from
    inside (the normal of a solid points out of it, so a ray going out sees its back)."""
    cap = {"intersection": [dict(BALL), {"equation": "z + 0.5", "name": "half"}], "material": "two"}
    cs = scene([cap])
    assert np.allclose(cs.trace([0, 0, 5], [0, 0, -1]), RED)
    assert np.allclose(cs.trace([0, 0, -0.7], [0, 0, -1]), BLUE)
    assert np.allclose(cs.trace([0, 0, -0.7], [0, 0, 1]), BLUE)  # out through the flat face


def test_without_inside_both_sides_show_the_colour() -> None:
    cs = scene([BALL], inside=None)
    assert np.allclose(cs.trace([0, 0, 5], [0, 0, -1]), RED)
    assert np.allclose(cs.trace([0, 0, 0], [0, 0, -1]), RED)


@pytest.mark.parametrize("bad", [[1, 2], [0, 0, -0.1], "blue", [0, 0, 101]])
def test_a_bad_inside_colour_is_one_line(bad) -> None:
    with pytest.raises(UserError, match=r"materials\.two\.inside"):
        scene([BALL], inside=bad)
