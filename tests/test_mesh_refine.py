"""Local refinement (mesh/refine.py, mesh/critical.py): where a thin neck or a narrow gap hides between grid
vertices, a block of cells is meshed on a finer grid and stitched to the rest. The Cassini surface with a neck of
radius 0.03 (tests/data/cassini_neck.yaml, Euler characteristic 2) and two balls 0.02 apart
(tests/data/two_balls_gap.yaml, 4) come out right at every grid from 16 to 48 cells -- on the grid alone they
are wrong at 15 and 33 of those grids --, closed, oriented, one fan at every vertex, read back by trimesh and
manifold3d from the files written, every vertex on f = 0 (mpmath at 40 digits); shapes with nothing hidden are
meshed exactly as without refinement."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import manifold3d
import mpmath
import numpy as np
import pytest
import sympy
import trimesh

from implgen.mesh import refine
from implgen.mesh.manifold import one_fan_each
from implgen.mesh.pipeline import closed_and_euler, mesh_spec
from implgen.spec.entry import load_spec
from implgen_proc import implgen

ROOT = Path(__file__).resolve().parent.parent
CASSINI = ROOT / "tests/data/cassini_neck.yaml"
BALLS = ROOT / "tests/data/two_balls_gap.yaml"


@cache
def spec_of(path: Path):
    return load_spec(path, cache=True)


def topology(path: Path, cells: int, **kw):
    result = mesh_spec(spec_of(path), {}, cells, [], singular=False, **kw)
    faces = result.mesh.faces
    closed, euler = closed_and_euler(faces, len(result.mesh.vertices))
    return closed and one_fan_each(faces), euler, result.mesh.stats


@pytest.mark.parametrize("path, euler", [(CASSINI, 2), (BALLS, 4)], ids=["cassini_neck", "two_balls"])
def test_right_at_every_grid_from_16_to_48(path, euler):
    wrong = []
    for cells in range(16, 49):
        manifold, got, stats = topology(path, cells)
        assert manifold, cells
        assert stats["refine_skipped"] is None, (cells, stats["refine_skipped"])
        if got != euler:
            wrong.append((cells, got))
    assert wrong == []


def test_nothing_refined_where_nothing_hides():
    """The torus at 24 cells: no thin feature, no missed interval -- the very mesh of the grid alone."""
    spec = load_spec(ROOT / "examples/shapes/torus_z.yaml", cache=True)
    a = mesh_spec(spec, {}, 24, [], singular=False)
    b = mesh_spec(spec, {}, 24, [], singular=False, refine=False)
    assert a.mesh.stats["refined"] == [] and a.mesh.stats["refine_sites"]["thin_features"] == 0
    assert np.array_equal(a.mesh.faces, b.mesh.faces) and np.array_equal(a.mesh.vertices, b.mesh.vertices)


def test_over_the_fine_cells_cap_it_keeps_the_grids_mesh(monkeypatch):
    monkeypatch.setattr(refine, "MAX_FINE", 1000)
    manifold, euler, stats = topology(CASSINI, 32)
    assert manifold and euler == 4  # the grid's own mesh, neck lost
    assert stats["refined"] == [] and "fine cells, more than 1000" in stats["refine_skipped"]


def _block_holds(block: dict, point) -> bool:
    return all(lo <= v <= hi for lo, hi, v in zip(block["from"], block["to"], point))


@pytest.mark.parametrize(
    "path, cells, euler, where", [(CASSINI, 32, 2, (0, 0, 0)), (BALLS, 16, 4, (0, 0, 0))], ids=["cassini", "balls"]
)
@pytest.mark.parametrize("fmt", [".stl", ".obj", ".ply"])
def test_written_and_read_back(tmp_path, path, cells, euler, where, fmt):
    """The file as written: trimesh (merging equal positions) reads a closed, consistently wound mesh of the right
    Euler characteristic, manifold3d accepts it; the report says where the grid was refined, the stderr line
    that it was."""
    out, rep = tmp_path / f"m{fmt}", tmp_path / "r.json"
    ran = implgen("mesh", path, "--cells", str(cells), "--no-singular", "-o", out, "--report", rep)
    assert ran.code == 0, ran.err
    assert f"Euler characteristic {euler}" in ran.err and "refined 1 block(s)" in ran.err
    tm = trimesh.load(out, process=True, force="mesh")
    assert tm.is_watertight and tm.is_winding_consistent and tm.euler_number == euler
    v, f = np.asarray(tm.vertices), np.asarray(tm.faces)
    m = manifold3d.Manifold(manifold3d.Mesh(vert_properties=v.astype(np.float32), tri_verts=f.astype(np.uint32)))
    assert m.status() == manifold3d.Error.NoError
    stats = json.loads(rep.read_text())["stats"]
    assert len(stats["refined"]) == 1 and _block_holds(stats["refined"][0], where)
    assert stats["refined"][0]["ratio"] >= 2 and stats["missed_detail_edges"] == 0


@pytest.mark.parametrize("path, cells", [(CASSINI, 40), (BALLS, 24)], ids=["cassini", "balls"])
def test_vertices_on_the_surface(path, cells):
    """Every vertex in the refined block and a sample of the rest: |f| / |grad f| at 40 digits within 1e-9 of the
    region (mpmath from SymPy's own tree of f, not the generated code)."""
    spec = spec_of(path)
    result = mesh_spec(spec, {}, cells, [], singular=False)
    block = result.mesh.stats["refined"][0]
    verts = result.mesh.vertices
    near = np.array([_block_holds(block, p) for p in verts])
    rng = np.random.default_rng(3)
    pick = np.concatenate([np.flatnonzero(near)[:400], rng.choice(np.flatnonzero(~near), 40, replace=False)])
    named = {s.name: s for s in spec.f.free_symbols}
    x, y, z = (named.get(n, sympy.Symbol(n)) for n in "xyz")
    f = sympy.lambdify((x, y, z), spec.f, "mpmath")
    grad = sympy.lambdify((x, y, z), [sympy.diff(spec.f, v) for v in (x, y, z)], "mpmath")
    mpmath.mp.dps = 40
    size = result.mesh.grid.size
    assert near.sum() > 50
    for p in verts[pick]:
        q = [mpmath.mpf(float(c)) for c in p]
        dist = abs(f(*q)) / mpmath.norm(grad(*q))
        assert dist <= 1e-9 * size, (p, dist)


def test_one_fan_each_sees_two_cones_at_a_vertex():
    tet = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    assert one_fan_each(tet)
    two = np.concatenate([tet, np.where(tet == 0, 0, tet + 3)])  # a second tetrahedron sharing vertex 0
    assert closed_and_euler(two, 7)[0] and not one_fan_each(two)


@pytest.mark.parametrize("path, size", [(CASSINI, 0.03), (BALLS, 0.01)], ids=["neck_radius", "half_gap"])
def test_the_critical_point_gives_the_features_size(path, size):
    """The neck's saddle (f < 0) at the origin: f reaches 0 at the neck's radius, 0.03; the gap's (f > 0): at half
    the gap, 0.01. At 32 cells no grid line crosses the Cassini neck; the grid's samples still lead to it."""
    from implgen.mesh.critical import critical_points
    from implgen.mesh.crossings import grid_flags
    from implgen.mesh.region import make_grid
    from implgen.mesh.shapelib import ShapeLib

    spec = spec_of(path)
    lib = ShapeLib(spec, list(spec.params.values()))
    grid, clips = make_grid(spec.box(), [], 32, str(path))
    crit = critical_points(lib, clips, grid, grid_flags(lib, clips, grid)[1])
    assert len(crit.points) == 1
    assert np.abs(crit.points[0]).max() < 1e-9
    assert crit.size[0] == pytest.approx(size, rel=0.01)


def test_a_failed_check_grows_the_blocks():
    """The genus-2 surface at 23 cells: the first stitching fails the check (edges with one triangle, next to the
    box's cap); the blocks grown by a cell pass it, and the mesh is refined, closed, of genus 2."""
    manifold, euler, stats = topology(ROOT / "examples/mesh/genus2.yaml", 23)
    assert manifold and euler == -2
    assert stats["refine_skipped"] is None and len(stats["refined"]) == 2
