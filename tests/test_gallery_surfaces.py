"""The gallery's equations against what the literature says of each surface (docs/surfaces.md): node counts
(Cayley 4, Kummer 16, Barth 65 and 345, Togliatti 31, Endraß 168), the 15 lines of Clebsch's cubic that Clebsch
wrote down, Chebyshev polynomials for Chmutov's surfaces, parametrisations, symmetries, and boxes that hold the
whole of a closed surface. Exact arithmetic (SymPy over Q) wherever the statement is exact; the node counts by
Newton's method (tests/surface_nodes.py)."""

from __future__ import annotations

import itertools
from fractions import Fraction

import numpy as np
import pytest
import sympy as sp

from implgen.spec.gallery import entry
from implgen.spec.parse import X, Y, Z
from surface_nodes import real_nodes


def poly(name: str, **values: float) -> sp.Expr:
    """f of a gallery spec in x, y, z with its params (defaults, or `values`) as exact rationals."""
    spec = entry(name).load()
    given = {**spec.params, **values}
    subs = {sym: sp.nsimplify(given[k], rational=True) for sym, k in zip(spec.param_symbols, spec.params)}
    f = spec.f.subs(subs)
    return sp.expand(f)


def f_of(name: str, **values: float) -> sp.Expr:
    return poly(name, **values)


@pytest.mark.parametrize(
    "name, values, nodes, affine",
    [
        ("cayley", {}, 4, 4),  # Cayley 1869
        ("kummer", {"mu": 1.3}, 16, 16),  # Kummer 1864: 16, all real for 1 < mu^2 < 3
        ("kummer", {"mu": 1.1}, 16, 16),
        ("kummer", {"mu": 1.7}, 16, 16),
        ("kummer", {"mu": 0.8}, 4, 4),  # 1/3 < mu^2 < 1: 4 real, 12 complex
        ("togliatti", {}, 31, 31),  # Togliatti 1940, Beauville 1980: 31 is the most for a quintic
        ("barth6", {}, 65, 50),  # Barth 1996: 20 + 30 in the affine chart, 15 at infinity
        ("endrass", {}, 168, 144),  # Endraß 1997: X+, all 168 real
        ("barth10", {}, 345, 300),  # Barth 1996
    ],
)
def test_node_counts_are_the_literatures(name, values, nodes, affine):
    found = real_nodes(f_of(name, **values), grid=11)
    assert len(found) == nodes
    assert sum(1 for v, _ in found if abs(v[3]) > 1e-9) == affine
    assert all(cond > 1e-8 for _, cond in found)  # ordinary double points: Hessian of rank 3


def test_cayley_nodes_and_the_edges_joining_them_exactly():
    f = f_of("cayley")
    grad = [sp.diff(f, v) for v in (X, Y, Z)]
    nodes = [(1, 1, -1), (1, -1, 1), (-1, 1, 1), (-1, -1, -1)]
    for p in nodes:
        at = dict(zip((X, Y, Z), p))
        assert f.subs(at) == 0 and all(g.subs(at) == 0 for g in grad)
    t = sp.Symbol("t")
    for p, q in itertools.combinations(nodes, 2):  # the six edges lie on the surface
        line = {c: a + t * (b - a) for c, a, b in zip((X, Y, Z), p, q)}
        assert sp.expand(f.subs(line, simultaneous=True)) == 0


def test_clebsch_holds_its_fifteen_rational_lines():
    """On x0^3 + ... + x4^3 = 0 = x0 + ... + x4 lie the lines x_i + x_j = x_k + x_l = x_m = 0 ({i..m} = {0..4}):
    15 of the 27 (Clebsch 1871). In the spec's chart x0..x3 = x, y, z, w; x4 = -(x + y + z + w)."""
    W = sp.Symbol("w")
    F = sp.Poly(f_of("clebsch"), X, Y, Z).homogenize(W).as_expr()
    coords = [X, Y, Z, W]
    s, t = sp.symbols("s t")
    lines = set()
    for m in range(5):
        rest = [i for i in range(5) if i != m]
        for a in rest[1:]:
            i, j = rest[0], a
            k, n = [r for r in rest if r not in (i, j)]
            forms = [X, Y, Z, W, -(X + Y + Z + W)]
            eqs = [forms[i] + forms[j], forms[k] + forms[n], forms[m]]
            basis = sp.Matrix([[e.coeff(c) for c in coords] for e in eqs]).nullspace()
            assert len(basis) == 2  # the three planes meet in a line
            point = {c: s * basis[0][q] + t * basis[1][q] for q, c in enumerate(coords)}
            assert sp.expand(F.subs(point, simultaneous=True)) == 0
            lines.add(tuple(sorted(map(tuple, sp.Matrix.hstack(*basis).T.rref()[0].tolist()))))
    assert len(lines) == 15


@pytest.mark.parametrize("name, n", [("chmutov6", 6), ("chmutov8", 8), ("chmutov12", 12)])
def test_chmutov_is_a_sum_of_chebyshev_polynomials(name, n):
    want = sum(sp.chebyshevt(n, v) for v in (X, Y, Z))
    assert sp.expand(f_of(name) - want) == 0


def test_roman_surface_is_the_sphere_under_yz_zx_xy():
    f = f_of("roman")
    for a, b, c, d in [(1, 2, 2, 3), (2, 3, 6, 7), (1, 4, 8, 9), (2, 6, 9, 11)]:  # a^2 + b^2 + c^2 = d^2
        for sx, sy, sz in itertools.product((1, -1), repeat=3):
            x, y, z = Fraction(sx * a, d), Fraction(sy * b, d), Fraction(sz * c, d)
            assert f.subs({X: y * z, Y: z * x, Z: x * y}) == 0
    grad = [sp.diff(f, v) for v in (X, Y, Z)]
    t = sp.Symbol("t")
    for axis in [(t, 0, 0), (0, t, 0), (0, 0, t)]:  # the double lines
        assert all(sp.expand(g.subs(dict(zip((X, Y, Z), axis)))) == 0 for g in grad)


def test_whitney_umbrella_is_the_image_of_uv_u_v2():
    u, v = sp.symbols("u v")
    f = f_of("whitney")
    assert sp.expand(f.subs({X: u * v, Y: u, Z: v**2}, simultaneous=True)) == 0
    t = sp.Symbol("t")
    assert all(sp.diff(f, c).subs({X: 0, Y: 0, Z: t}) == 0 for c in (X, Y, Z))  # singular along the z-axis


@pytest.mark.parametrize("name, axis", [("dingdong", Z), ("zitrus", Y), ("octdong", Z)])
def test_surfaces_of_revolution(name, axis):
    f = f_of(name)
    a, b = [c for c in (X, Y, Z) if c != axis]
    assert sp.expand(b * sp.diff(f, a) - a * sp.diff(f, b)) == 0  # invariant under turns about the axis


@pytest.mark.parametrize("name, points", [("dingdong", [(0, 0, 0)]), ("zitrus", [(0, 0, 0), (0, 1, 0)])])
def test_singular_points_where_the_pictures_have_them(name, points):
    f = f_of(name)
    for p in points:
        at = dict(zip((X, Y, Z), p))
        assert f.subs(at) == 0 and all(sp.diff(f, c).subs(at) == 0 for c in (X, Y, Z))


def test_octdong_at_a_half_is_hausers():
    assert sp.expand(f_of("octdong", a=0.5) - (X**2 + Y**2 + Z**4 - Z**2)) == 0


def test_dupin_cyclide_at_c_zero_is_the_torus():
    a, d = sp.Rational(6, 5), sp.Rational(2, 5)
    torus = (X**2 + Y**2 + Z**2 + a**2 - d**2) ** 2 - 4 * a**2 * (X**2 + Y**2)
    assert sp.expand(f_of("dupin", a=1.2, c=0.0, d=0.4) - torus) == 0


@pytest.mark.parametrize("name", ["tanglecube", "tooth", "goursat", "chmutov6"])
def test_cube_symmetry(name):
    f = f_of(name)
    for perm in itertools.permutations((X, Y, Z)):
        for signs in itertools.product((1, -1), repeat=3):
            image = {c: s * p for c, s, p in zip((X, Y, Z), signs, perm)}
            assert sp.expand(f.subs(image, simultaneous=True) - f) == 0


def test_monkey_saddle_has_threefold_symmetry():
    f = f_of("monkey_saddle")
    c, s = sp.Rational(-1, 2), sp.sqrt(3) / 2  # a turn by 120 degrees about z
    assert sp.expand(f.subs({X: c * X - s * Y, Y: s * X + c * Y}, simultaneous=True) - f) == 0


@pytest.mark.parametrize(
    "name", ["tanglecube", "tooth", "goursat", "chmutov6", "chmutov8", "chmutov12", "dupin", "octdong", "zitrus"]
)
def test_a_closed_surface_lies_inside_its_box(name):
    """f > 0 on every face of the box: the box holds the whole (closed, f < 0 inside) surface."""
    spec = entry(name).load()
    fn = sp.lambdify((X, Y, Z), f_of(name), "numpy")
    box = spec.box()
    lo, hi = np.array(box[:3]), np.array(box[3:])
    s = np.linspace(0.0, 1.0, 61)
    u, v = np.meshgrid(s, s)
    for axis, end in itertools.product(range(3), (lo, hi)):
        others = [i for i in range(3) if i != axis]
        pts = np.empty((3, *u.shape))
        pts[axis] = end[axis]
        pts[others[0]] = lo[others[0]] + u * (hi[others[0]] - lo[others[0]])
        pts[others[1]] = lo[others[1]] + v * (hi[others[1]] - lo[others[1]])
        assert (fn(*pts) > 0).all(), (name, axis, end[axis])
