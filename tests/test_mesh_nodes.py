"""Meshes of nodal surfaces stay 2-manifolds once written: the Kummer quartic (16 real nodes) cut by a ball of 2,
written by `implgen mesh` in every format and read back by trimesh, which merges vertices at equal positions.
Each read-back mesh is closed, oriented, every vertex's faces are one fan (no two sheets touching at a point),
and its Euler characteristic is the one the report gives. The report says what was done at each node."""

from __future__ import annotations

import json
from functools import cache
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from implgen.mesh.command import main

ROOT = Path(__file__).resolve().parent.parent
KUMMER = ROOT / "examples/mesh/kummer.yaml"


def fans(faces: np.ndarray) -> int:
    """How many fans of faces meet at the vertices: the corners (a; b, c) of each face join the link edges
    (a, b) and (a, c) at a; one connected link per used vertex when the mesh is a 2-manifold there."""
    f = np.asarray(faces, dtype=np.int64)
    n = int(f.max()) + 1
    a = f.reshape(-1)
    b = f[:, [1, 2, 0]].reshape(-1)
    c = f[:, [2, 0, 1]].reshape(-1)
    keys, inv = np.unique(np.concatenate([a * n + b, a * n + c]), return_inverse=True)
    m = len(a)
    graph = coo_matrix((np.ones(m), (inv[:m], inv[m:])), shape=(len(keys), len(keys)))
    return connected_components(graph, directed=False)[0]


def test_fans_counts_a_pinch():
    """Two tetrahedra sharing one vertex: 7 vertices, 8 fans; apart: 8 and 8."""
    tet = np.array([[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    apart = np.concatenate([tet, tet + 4])
    pinched = np.where(apart == 4, 0, apart)
    assert fans(apart) == 8 and len(np.unique(apart)) == 8
    assert fans(pinched) == 8 and len(np.unique(pinched)) == 7


@cache
def written(cells: int, folder: str) -> dict:
    """The Kummer quartic in a ball of 2 at `cells`, written in every format; the report."""
    out = Path(folder)
    for suffix in (".stl", ".obj", ".ply", ".glb"):
        args = [str(KUMMER), "--clip", "sphere:2", "--cells", str(cells), "-o", str(out / f"k{cells}{suffix}")]
        assert main([*args, "--report", str(out / f"k{cells}.json")]) == 0
    return json.loads((out / f"k{cells}.json").read_text())


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> str:
    return str(tmp_path_factory.mktemp("kummer"))


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".glb"])
@pytest.mark.parametrize("cells", [32, 64, 128])
def test_written_kummer_is_a_manifold_with_the_reported_euler(folder, cells, suffix):
    rep = written(cells, folder)
    mesh = trimesh.load(Path(folder) / f"k{cells}{suffix}", force="mesh")  # equal positions merged
    assert len(mesh.faces) == rep["triangles"] and len(mesh.vertices) == rep["vertices"]
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
    assert fans(mesh.faces) == len(mesh.vertices), "two sheets touch at a vertex"
    assert mesh.euler_number == rep["euler_characteristic"]


PHRASES = (
    "the mesh passes through it",
    "no vertex on it (its cell holds none)",
    "2 sheets that touched there moved 1e-05 of the region apart",
    "an island of 12 triangles squashed onto it dropped",
)


@pytest.mark.parametrize("cells", [32, 64, 128])
def test_the_report_says_what_was_done_at_each_node(folder, cells):
    """One sentence per node; where sheets were parted, their vertices lie about the split distance from the node
    and on the surface (|f| / |grad f| at most 1e-9 of the region, f from SymPy's tree of the spec, not the
    generated code), and none was left off it."""
    import sympy

    from implgen.spec.entry import load_spec

    rep = written(cells, folder)
    said = rep["at_singular_points"]
    assert len(said) == len(rep["singular_points"]) == 16
    for text in said:
        assert all(part in PHRASES for part in text.split("; ")), text
    if cells in (32, 64):
        assert sum("moved" in t for t in said) == {32: 1, 64: 4}[cells]
    assert rep["stats"]["split_off_surface"] == 0 and rep["stats"]["touching_left"] == 0
    spec = load_spec(KUMMER, cache=True)
    x, y, z = sorted(spec.f.free_symbols, key=lambda s: s.name)
    f = sympy.lambdify((x, y, z), spec.f, "numpy")
    grad = sympy.lambdify((x, y, z), [sympy.diff(spec.f, v) for v in (x, y, z)], "numpy")
    mesh = trimesh.load(Path(folder) / f"k{cells}.ply", process=False)
    split = rep["stats"]["split_distance"]
    for node, text in zip(np.array(rep["singular_points"]), said):
        if "moved" not in text:
            continue
        d = np.linalg.norm(mesh.vertices - node, axis=1)
        near = mesh.vertices[d <= 2 * split]
        assert len(near) >= 2 and d.min() >= 0.5 * split
        g = np.linalg.norm(np.stack(grad(*near.T), axis=1), axis=1)
        assert (np.abs(f(*near.T)) <= 1e-9 * 4.0 * g).all()  # the region: the ball of 2, 4 across
