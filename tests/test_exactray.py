"""implgen.roots.exactray, the exact judge of a ray's hits (bench/povray_compare.py, bench/embree_scenes.py, the
GLSL checks), against analytic answers: a torus placed by a scale, a rotation and a translation, met at the four
crossings its radii give, touched at its outer equator and missed just beside it; the integer ray polynomial
against SymPy's expansion over Q; and which of two spheres a ray meets first."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy as sp

from implgen.roots.exactray import ExactJudge, Placed
from implgen.spec.entry import load_spec, parse_spec
from implgen.spec.parse import param_symbol

ROOT = Path(__file__).resolve().parent.parent
EPS = 2.0**-30

# object -> world: scale 2, a quarter turn about x (object y -> world z, object z -> world -y), then (1, 2, 3)
TURN = np.array([[2.0, 0, 0, 1], [0, 0, -2, 2], [0, 2, 0, 3]])


@pytest.fixture(scope="module")
def torus() -> Placed:
    """Suffern's torus about its y-axis (a = 1, b = 0.25) placed by TURN: in the world a torus about the line
    x = 1, y = 2 in the plane z = 3, radii 2 and 0.5."""
    spec = load_spec(ROOT / "examples/shapes/torus_y.yaml")
    return Placed.of(spec, spec.params, TURN)


def test_a_placed_torus_is_met_where_its_radii_say(torus):
    o, d = (-9.0, 2.0, 3.0), (2.0, 0.0, 0.0)  # along x through the centre; d not unit: t halves
    for t in (3.75, 4.25, 5.75, 6.25):  # world x = 1 -+ 2.5, 1 -+ 1.5
        assert torus.meets(o, d, t - EPS, t + EPS), t
        assert torus.meets(o, d, Fraction(t), Fraction(t)), t  # a root exactly at a closed end
    for lo, hi in ((0, 3.75 - EPS), (4.25 + EPS, 5.75 - EPS), (6.25 + EPS, np.inf)):
        assert not torus.meets(o, d, lo, hi), (lo, hi)
    assert torus.meets(o, d) and not torus.meets(o, (-2.0, 0.0, 0.0))  # pointing away: every root at t < 0


def test_a_tangent_ray_touches_the_outer_equator_inside_the_padded_box(torus):
    """y = 4.5 touches the outer equator at (1, 4.5, 3): a double root, on the box's face (object z = -1.25),
    inside the box as the runtime pads it; 2^-30 further out the ray misses."""
    assert torus.meets((-9.0, 4.5, 3.0), (1.0, 0.0, 0.0))
    assert torus.meets((-9.0, 4.5, 3.0), (1.0, 0.0, 0.0), 10 - EPS, 10 + EPS)
    assert not torus.meets((-9.0, 4.5 + EPS, 3.0), (1.0, 0.0, 0.0))
    oo, dd = torus.object_ray((-9.0, 4.5, 3.0), (1.0, 0.0, 0.0))
    assert (oo, dd) == ([-5, 0, Fraction(-5, 4)], [Fraction(1, 2), 0, 0])  # exactly: inv(2 R) ((-10, 2.5, 0))


def test_a_box_clip_is_exact():
    """A ball cut to |x| <= 1/2: a ray through the cut-away side misses, the same ray with the whole box hits."""
    cut = {"name": "ball", "equation": "x^2 + y^2 + z^2 - 1", "bounds": {"x": [-0.5, 0.5]}}
    ball = Placed.of(parse_spec(cut), {})
    whole = Placed.of(parse_spec({**cut, "bounds": {"x": [-2, 2], "y": [-2, 2], "z": [-2, 2]}}), {})
    o, d = (0.0, 0.0, 5.0), (0.8, 0.0, -4.4)  # towards (0.8, 0, 0.6) on the front of the ball
    assert whole.meets(o, d) and not ball.meets(o, d)
    assert ball.meets(o, (0.0, 0.0, -1.0))


def test_the_integer_ray_polynomial_is_a_positive_multiple_of_the_exact_one(torus):
    """Placed.ray_poly works on integers; SymPy's expansion of f(inv (o + t d - shift)) over Q is the
    reference."""
    spec = load_spec(ROOT / "examples/shapes/torus_y.yaml")
    o, d = (-9.1, 2.3, 2.9), (1.0, 0.1, 0.07)
    t = sp.Symbol("t")
    m = sp.Matrix(3, 4, [sp.Rational(Fraction(v)) for v in TURN.ravel()])
    world = sp.Matrix([sp.Rational(Fraction(a)) + sp.Rational(Fraction(b)) * t for a, b in zip(o, d)])
    local = m[:, :3].inv() * (world - m[:, 3])
    f = spec.f.xreplace({param_symbol(k): sp.Rational(Fraction(v)) for k, v in spec.params.items()})
    names = {s.name: s for s in f.free_symbols}
    line = {names[n]: local[k] for k, n in enumerate("xyz")}
    want = [Fraction(int(c.p), int(c.q)) for c in reversed(sp.Poly(sp.expand(f.xreplace(line)), t).all_coeffs())]
    got = torus.ray_poly(o, d)
    ratio = Fraction(got[-1]) / want[-1]
    assert len(got) == 5 and ratio > 0 and all(Fraction(g) == ratio * w for g, w in zip(got, want))


def test_the_judge_names_the_first_object_met():
    """Two unit balls on the z-axis, at 0 and at -3: from z = 5 looking down -z the first is met at t = 4, the
    second at t = 7 behind it."""
    spec = parse_spec({"name": "ball", "equation": "x^2 + y^2 + z^2 - 1", "bounds": {a: [-1, 1] for a in "xyz"}})
    near = Placed.of(spec, {})
    far = Placed.of(spec, {}, [[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, -3]])
    judge = ExactJudge([near, far])
    o, d = (0.0, 0.0, 5.0), (0.0, 0.0, -1.0)
    assert judge.right((0, 4.0), (1, 7.0), o, d) and not judge.right((1, 7.0), (0, 4.0), o, d)
    assert judge.right((0, 4.0), (-1, np.inf), o, d) and not judge.right((-1, np.inf), (0, 4.0), o, d)
    assert not judge.right((0, 4.04), (0, 4.0), o, d)  # 1 % off the true distance
    # only the two answers' objects are weighed: against a miss, the far ball's hit at 7 holds
    assert judge.right((1, 7.0), (-1, np.inf), o, d)
    assert judge.right((1, 7.0), (1, 6.0), o, d) and not judge.right((1, 6.0), (1, 7.0), o, d)
    assert judge.hits(o, d) and judge.hits(o, d, 0, 4) and not judge.hits(o, d, 0, 3.9)
    assert judge.hits(o, d, 8, 9) and not judge.hits(o, d, 9.5, np.inf)  # the far ball's back at t = 9
    miss = (0.0, 1.5, 5.0)
    assert not judge.hits(miss, d) and judge.right((-1, np.inf), (0, 4.0), miss, d)
    assert judge.right((-1, np.inf), (-1, np.inf), miss, d)  # two misses agree: nothing to decide
