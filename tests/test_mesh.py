"""`implgen mesh`'s meshes checked by independent means: trimesh (closed, winding consistent, positive
volume) and manifold3d (a valid manifold) on every shape; the Euler characteristic against the known one
(sphere 2, torus 0, genus 2 -2, tanglecube -8, Chmutov's octic -160 by Morse theory on f); vertices on the true
surface (mpmath at 40 digits from SymPy's own tree of f, not the generated code); normals against SymPy's
gradient; volumes against the textbook; singular points against the literature (Cayley's cubic 4, a Kummer
quartic 16, Barth's sextic 50 affine of its 65), each refined and checked with mpmath. Small grids."""

from __future__ import annotations

import math
from functools import cache
from pathlib import Path

import manifold3d
import mpmath
import numpy as np
import pytest
import sympy
import trimesh

from implgen.mesh.pipeline import closed_and_euler, mesh_spec, signed_volume, singular_in_solid
from implgen.mesh.region import make_grid, parse_clip
from implgen.spec.entry import load_spec, parse_spec

ROOT = Path(__file__).resolve().parent.parent
EX = ROOT / "examples"

# (spec, cells, clip, Euler characteristic or None where the surface has nodes)
CASES = {
    "sphere": ("shapes/sphere.yaml", 12, None, 2),
    "torus": ("shapes/torus_z.yaml", 24, None, 0),
    "genus2": ("mesh/genus2.yaml", 40, None, -2),
    "tanglecube": ("mesh/tanglecube.yaml", 24, None, -8),
    "chmutov8": ("shapes/chmutov8.yaml", 24, None, -160),
    "heart": ("shapes/heart.yaml", 32, None, 2),
    "piriform": ("shapes/piriform.yaml", 24, None, 2),
    "cone_ball": ("shapes/cone.yaml", 16, "sphere:1", 4),  # the two solid cones, apart at the apex: 2 + 2
    "cylinder_box": ("shapes/cylinder.yaml", 12, "box:1.5", 2),  # a capped rod
    "cayley_ball": ("mesh/cayley.yaml", 24, "sphere:2", None),
    "barth_ball": ("shapes/barth6.yaml", 32, "sphere:1.8", None),
}


@cache
def meshed(name: str):
    path, cells, clip, _ = CASES[name]
    spec = load_spec(EX / path, cache=True)
    return spec, mesh_spec(spec, {}, cells, parse_clip(clip) if clip else [], singular=False)


def _xyz(spec):
    """The spec's own x, y, z symbols (they carry assumptions, so sympy.symbols("x") is another symbol)."""
    named = {s.name: s for s in spec.f.free_symbols}
    return tuple(named.get(n, sympy.Symbol(n)) for n in "xyz")


def _mp_functions(spec):
    """mpmath f and gradient from SymPy's tree of f, params substituted at 40 digits."""
    x, y, z = _xyz(spec)
    f = spec.f.subs({s: sympy.Float(v, 40) for s, v in zip(spec.param_symbols, spec.params.values())})
    grad = [sympy.diff(f, v) for v in (x, y, z)]
    return sympy.lambdify((x, y, z), f, "mpmath"), sympy.lambdify((x, y, z), grad, "mpmath")


@pytest.mark.parametrize("name", list(CASES))
def test_closed_manifold_outward(name):
    _, result = meshed(name)
    v, f = result.mesh.vertices, result.mesh.faces
    tm = trimesh.Trimesh(v, f, process=False)
    assert tm.is_watertight and tm.is_winding_consistent
    assert tm.volume > 0  # faces turn counter-clockwise seen from f > 0
    m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=v.astype(np.float32), tri_verts=f.astype(np.uint32)))
    assert m.status() == manifold3d.Error.NoError
    closed, euler = closed_and_euler(f, len(v))
    assert closed and euler == tm.euler_number
    assert result.mesh.stats["fallback_crossings"] == 0


@pytest.mark.parametrize("name", [n for n, c in CASES.items() if c[3] is not None])
def test_euler_characteristic(name):
    _, result = meshed(name)
    tm = trimesh.Trimesh(result.mesh.vertices, result.mesh.faces, process=False)
    assert tm.euler_number == CASES[name][3]


@pytest.mark.parametrize("name", ["torus", "tanglecube", "chmutov8", "heart", "cone_ball", "barth_ball"])
def test_vertices_on_the_true_surface(name):
    """Every vertex of a sample lies on the solid's boundary to 1e-9 of the box: on f = 0 (distance |f| / |grad f|
    at 40 digits) with every clip <= 0, or on a clip with f <= 0."""
    spec, result = meshed(name)
    mpmath.mp.dps = 40
    f, grad = _mp_functions(spec)
    size = result.mesh.grid.size
    rng = np.random.default_rng(7)
    verts = result.mesh.vertices
    sample = verts[rng.choice(len(verts), size=min(60, len(verts)), replace=False)]
    for p in sample:
        q = [mpmath.mpf(float(c)) for c in p]
        fv = f(*q)
        clip = [float(c.value(p)) for c in result.clips]
        on_clip = [abs(c) <= 1e-9 * size for c in clip]
        if any(on_clip):
            assert fv <= mpmath.mpf(1e-9) * size * mpmath.norm(grad(*q)) or fv <= 0
            continue
        assert max(clip, default=-1.0) < 0
        dist = abs(fv) / mpmath.norm(grad(*q))
        assert dist <= 1e-9 * size, (p, dist)


@pytest.mark.parametrize("name", ["sphere", "torus", "genus2", "tanglecube", "chmutov8", "heart"])
def test_face_normals_follow_the_gradient(name):
    spec, result = meshed(name)
    x, y, z = _xyz(spec)
    fsym = spec.f.subs(dict(zip(spec.param_symbols, spec.params.values())))
    grad = sympy.lambdify((x, y, z), [sympy.diff(fsym, v) for v in (x, y, z)], "numpy")
    v, fc = result.mesh.vertices, result.mesh.faces
    n = np.cross(v[fc[:, 1]] - v[fc[:, 0]], v[fc[:, 2]] - v[fc[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    c = v[fc].mean(axis=1)
    g = np.stack(np.broadcast_arrays(*grad(c[:, 0], c[:, 1], c[:, 2])), axis=1).astype(np.float64)
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    dots = (n * g).sum(axis=1)
    assert np.median(dots) > 0.99
    assert (dots > 0.5).mean() > 0.99


def test_volumes_against_the_textbook():
    """A mesh inscribed in the surface: its volume a little below the true one, closing in as O(h^2)."""
    _, s = meshed("sphere")
    _, t = meshed("torus")
    ball = 4 / 3 * math.pi
    torus = 2 * math.pi**2 * 1.0 * 0.25**2  # 2 pi^2 R r^2
    for result, exact in ((s, ball), (t, torus)):
        vol = signed_volume(result.mesh.vertices, result.mesh.faces)
        assert 0.97 * exact < vol < exact


def test_grazing_grid_line():
    """A ball whose radius makes one grid line tangent to it: that line's double root is at most one root (or
    none, the radius being the tangent one only to rounding), never two, and the mesh stays a closed sphere."""
    data = {"name": "ball", "equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": 1.0}}
    data["bounds"] = {a: [-1.3, 1.3] for a in "xyz"}
    spec = parse_spec(data, "<test>", cache=True)
    grid, _ = make_grid(spec.box(), [], 16, "<test>")
    ys, zs = grid.coords(1), grid.coords(2)
    j, k = int(np.argmin(np.abs(ys - 0.5))), int(np.argmin(np.abs(zs - 0.6)))
    r = math.hypot(ys[j], zs[k])  # the x-line through (ys[j], zs[k]) touches the sphere
    result = mesh_spec(spec, {"r": r}, 16, [], singular=False)
    roots, counts = result.lib.roots(np.array([[grid.origin[0], ys[j], zs[k]]]), [1.0, 0, 0], 0.0, 10.0)
    assert counts[0] <= 1 and np.all(np.abs(roots[0, : counts[0]] - (0 - grid.origin[0])) < 1e-6)
    tm = trimesh.Trimesh(result.mesh.vertices, result.mesh.faces, process=False)
    assert tm.is_watertight and tm.euler_number == 2


def _check_singular(spec, pts, f_tol):
    """Each point, refined by Newton on grad f at 40 digits from SymPy's tree, is a critical point nearby where
    |f| <= f_tol (1e-25 for a spec written with exact coefficients)."""
    mpmath.mp.dps = 40
    x, y, z = _xyz(spec)
    f = spec.f.subs({s: sympy.Float(v, 40) for s, v in zip(spec.param_symbols, spec.params.values())})
    grad = [sympy.diff(f, v) for v in (x, y, z)]
    gfun = sympy.lambdify((x, y, z), grad, "mpmath")
    ffun = sympy.lambdify((x, y, z), f, "mpmath")
    for p in pts:
        root = mpmath.findroot(lambda a, b, c: gfun(a, b, c), [mpmath.mpf(float(v)) for v in p])
        assert max(abs(float(root[i]) - p[i]) for i in range(3)) < 1e-9
        assert abs(ffun(*root)) < f_tol


@pytest.mark.parametrize(
    "path, box, count, f_tol",
    [("mesh/cayley.yaml", 2.0, 4, 1e-25), ("mesh/kummer.yaml", 3.0, 16, 1e-25), ("shapes/barth6.yaml", 2.5, 50, 1e-12)],
    ids=["cayley-4", "kummer-16", "barth-50-affine"],
)
def test_singular_points_against_the_literature(path, box, count, f_tol):
    """Cayley's nodal cubic: 4 nodes, all affine. The Kummer quartic with mu = 1.3: 16 nodes, all real and affine
    (|p| < 3). Barth's sextic: 65 nodes in projective space, 15 of them at infinity, so 50 affine ones, all
    within |p| < 1.8. (Its spec gives phi as a double, so its nodes are nodes only to that double's rounding:
    |f| ~ 1e-15 at the critical points.)"""
    spec = load_spec(EX / path, cache=True)
    result = mesh_spec(spec, {}, 8, parse_clip(f"box:{box}"), singular=True)
    pts = result.singular.points
    assert result.singular.complete and len(pts) == count
    if path.endswith("cayley.yaml"):
        expected = {(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)}
        assert {tuple(int(round(v)) for v in p) for p in pts} == expected
    _check_singular(spec, pts, f_tol)
    if path.endswith("barth6.yaml"):
        assert (np.linalg.norm(pts, axis=1) < 1.8).all()
        assert singular_in_solid(result).sum() == 50


def test_mesh_passes_through_the_nodes():
    """With the singular search on, the vertices of each node's cell sit on the node: Cayley's cubic in a ball
    of 2 passes through each of its 4 nodes -- with one vertex there, or, where two sheets of the node's cell
    (its two cones) both came onto it, with those two vertices parted by the split distance (unpinch.py), as
    what the report says of that node --, and stays a closed manifold."""
    spec = load_spec(EX / "mesh/cayley.yaml", cache=True)
    result = mesh_spec(spec, {}, 24, parse_clip("sphere:2"), singular=True)
    v, f = result.mesh.vertices, result.mesh.faces
    split = result.mesh.stats["split_distance"]
    for node, said in zip(result.singular.points, result.at_singular):
        dist = np.sort(np.linalg.norm(v - node, axis=1))
        if said == "the mesh passes through it":
            assert dist[0] == 0.0
        else:
            assert said == "2 sheets that touched there moved 1e-05 of the region apart"
            assert 0.5 * split <= dist[0] <= dist[1] <= 2 * split
    assert sorted(set(result.at_singular)) == [
        "2 sheets that touched there moved 1e-05 of the region apart",
        "the mesh passes through it",
    ]
    assert result.mesh.stats["snapped_to_singular"] >= 4
    tm = trimesh.Trimesh(v, f, process=False)
    assert tm.is_watertight and tm.is_winding_consistent and tm.volume > 0
    m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=v.astype(np.float32), tri_verts=f.astype(np.uint32)))
    assert m.status() == manifold3d.Error.NoError


def test_the_piriform_cusp():
    """The piriform's cusp at the origin (f = x^4 - x^3 + y^2 + z^2: f_x = x^2 (4x - 3) touches zero without
    changing sign) is found and the mesh is a closed sphere; at 48 cells the mesh passes through the cusp (at 32
    the cusp's cell holds no vertex to move onto it)."""
    spec = load_spec(EX / "shapes/piriform.yaml", cache=True)
    for cells in (32, 48):
        result = mesh_spec(spec, {}, cells, [], singular=True)
        pts = result.singular.points
        assert result.singular.complete and len(pts) == 1 and np.abs(pts[0]).max() < 1e-7
        through = np.abs(result.mesh.vertices - pts[0]).max(axis=1).min() == 0.0
        assert through == (cells == 48) and result.mesh.stats["snapped_to_singular"] == (cells == 48)
        tm = trimesh.Trimesh(result.mesh.vertices, result.mesh.faces, process=False)
        assert tm.is_watertight and tm.euler_number == 2


def test_clip_values_along_grid_lines():
    """A clip's value at points on grid lines (Clip.along, which skips building the points for a plane) equals
    its value at those points, for a ball and every side of a box, lines along each axis."""
    rng = np.random.default_rng(7)
    clips = parse_clip("sphere:1.3") + parse_clip("box:0.9")
    starts = rng.uniform(-2.0, 2.0, size=(40, 3))
    line = rng.integers(0, len(starts), size=200)
    t = rng.uniform(0.0, 4.0, size=200)
    for axis in range(3):
        p = starts[line].copy()
        p[:, axis] += t
        for c in clips:
            assert np.array_equal(c.along(axis, starts, line, t), c.value(p))


def test_closed_and_euler_on_small_complexes():
    """A tetrahedron (closed, V - E + F = 4 - 6 + 4 = 2), with unused vertices around it; without a face (open);
    with a face twice (edges in three faces) or turned over (an edge twice the same way); two tetrahedra (4)."""
    tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    assert closed_and_euler(tet, 4) == (True, 2)
    assert closed_and_euler(tet + 3, 10) == (True, 2)
    assert closed_and_euler(tet[1:], 4) == (False, 4 - 6 + 3)
    assert not closed_and_euler(np.concatenate([tet, tet[:1]]), 4)[0]
    assert not closed_and_euler(np.concatenate([tet[:1, ::-1], tet[1:]]), 4)[0]
    assert closed_and_euler(np.concatenate([tet, tet + 4]), 8) == (True, 4)
