"""`implgen mesh` as the user runs it: all four formats written and read back by trimesh, binary STL by default,
the JSON report and the one stderr line, a shape of a scene placed by its transform, and bad options refused
with one line, exit status 2 and nothing written; a shape with no real points in its box is one line too."""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest
import trimesh

from implgen_proc import implgen

ROOT = Path(__file__).resolve().parent.parent
TORUS = ROOT / "examples/shapes/torus_z.yaml"


@pytest.mark.parametrize("suffix", [".stl", ".obj", ".ply", ".glb"])
def test_every_format_reads_back(tmp_path, suffix):
    out = tmp_path / f"torus{suffix}"
    ran = implgen("mesh", TORUS, "-o", out, "--cells", "16", "--report", tmp_path / "r.json")
    assert ran.code == 0, ran.err
    rep = json.loads((tmp_path / "r.json").read_text())
    loaded = trimesh.load(out, force="mesh")  # merges the STL's per-face corners back into shared vertices
    assert len(loaded.faces) == rep["triangles"]
    assert loaded.is_watertight and loaded.euler_number == 0
    assert abs(loaded.volume - rep["volume"]) < 1e-5 * rep["volume"]
    if suffix == ".stl":  # binary: an 80-byte header, a count, 50 bytes per triangle
        data = out.read_bytes()
        assert struct.unpack("<I", data[80:84])[0] == rep["triangles"]
        assert len(data) == 84 + 50 * rep["triangles"]


def test_report_and_stderr_line(tmp_path):
    out, rep_path = tmp_path / "cayley.obj", tmp_path / "cayley.json"
    ran = implgen("mesh", ROOT / "examples/mesh/cayley.yaml", "--clip", "sphere:2", "--cells", "24", "-o", out,
                  "--report", rep_path)  # fmt: skip
    assert ran.code == 0, ran.err
    assert ran.err.count("\n") == 1 and "4 singular point(s)" in ran.err and "closed" in ran.err
    rep = json.loads(rep_path.read_text())
    assert rep["closed"] and rep["singular_in_clip"] == 4 and rep["singular_search_complete"]
    pts = np.array(rep["singular_points"])
    assert np.allclose(np.abs(pts), 1.0, atol=1e-9) and np.allclose(pts.prod(axis=1), 1.0, atol=1e-9)
    mesh = trimesh.load(out, force="mesh")
    assert mesh.is_watertight and (np.linalg.norm(mesh.vertices, axis=1) <= 2 + 1e-12).all()


def test_param_changes_the_shape(tmp_path):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    for rep, extra in ((a, []), (b, ["--param", "r=0.1"])):
        assert implgen("mesh", TORUS, "-o", tmp_path / "t.ply", "--cells", "32", "--report", rep, *extra).code == 0
    va, vb = json.loads(a.read_text())["volume"], json.loads(b.read_text())["volume"]
    # 2 pi^2 R r^2: the thin torus holds (0.1 / 0.25)^2 of the volume
    assert abs(vb / va - 0.16) < 0.02


def test_scene_object_placed_by_its_transform(tmp_path):
    out = tmp_path / "chmutov.stl"
    ran = implgen("mesh", ROOT / "examples/scenes/high_degree.yaml", "--object", "chmutov8", "--cells", "16",
                  "--no-singular", "-o", out)  # fmt: skip
    assert ran.code == 0, ran.err
    mesh = trimesh.load(out, force="mesh")
    # scaled 0.8 and moved to (0, 1.05, -0.2): the centre follows, the size shrinks
    assert np.allclose(mesh.bounds.mean(axis=0), [0, 1.05, -0.2], atol=0.05)
    assert mesh.is_watertight and mesh.volume > 0


@pytest.mark.parametrize(
    "args, names",
    [
        (["-o", "{d}/x.dxf"], "-o"),
        (["-o", "{d}/x.stl", "--cells", "2"], "--cells"),
        (["-o", "{d}/x.stl", "--cells", "9" * 3000], "--cells: a number of about 1e3000 is outside [4, 256]"),
        (["-o", "{d}/x.stl", "--clip", "ball:3"], "--clip"),
        (["-o", "{d}/x.stl", "--clip", "sphere:-1"], "--clip"),
        (["-o", "{d}/x.stl", "--param", "q=1"], "--param"),
        (["-o", "{d}/x.stl", "--param", "r=abc"], "--param"),
        (["-o", "{d}/x.stl", "--param", "r=0.1", "--param", "r=0.2"], "given twice"),
        (["-o", "{d}/x.stl", "--param", "r\n=0.1"], "--param 'r\\n=0.1'"),  # a newline stays escaped: one line
        (["-o", "{d}/x.stl", "--report", "{d}/r.txt"], "--report"),
        (["-o", "{d}/x.stl", "--object", "torus"], "--object"),
        (["-o", "{d}/no/such/x.stl"], "-o"),
    ],
)
def test_bad_options(tmp_path, args, names):
    ran = implgen("mesh", TORUS, *[a.format(d=tmp_path) for a in args])
    assert ran.code == 2 and ran.err.count("\n") == 1 and names in ran.err and "Traceback" not in ran.err
    assert list(tmp_path.iterdir()) == []


def test_a_param_the_shape_cannot_take_names_the_file_and_the_option_once(tmp_path):
    """R = 1e9 puts the torus's bounds past the coordinate range: "torus_z.yaml: --param: ...", not "--param:
    --param: ...", the same line `implgen share` gives."""
    ran = implgen("mesh", TORUS, "--param", "R=1e9", "-o", tmp_path / "x.stl")
    assert ran.code == 2 and ran.err.count("\n") == 1 and "Traceback" not in ran.err
    assert ran.err.startswith(f"implgen: error: {TORUS}: --param: with these params the bounds"), ran.err
    assert ran.err.count("--param") == 1
    share = implgen("share", TORUS, "--param", "R=1e9", "-o", tmp_path / "x.html")
    assert share.err == ran.err
    assert list(tmp_path.iterdir()) == []


def test_unbounded_needs_a_clip(tmp_path):
    ran = implgen("mesh", ROOT / "examples/shapes/cone.yaml", "-o", tmp_path / "c.stl")
    assert ran.code == 2 and "--clip" in ran.err and ran.err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_a_grid_that_misses_the_solid_says_so(tmp_path):
    """At 4 cells no grid vertex of the torus_z grid lies in the tube (its lines cross it, between vertices): one
    line naming --cells and the crossings seen, nothing written."""
    ran = implgen("mesh", TORUS, "-o", tmp_path / "t.stl", "--cells", "4", "--no-singular")
    assert ran.code == 2 and ran.err.count("\n") == 1 and "--cells 4" in ran.err and "empty" in ran.err
    assert "grid edges hold crossings" in ran.err and "Traceback" not in ran.err
    assert list(tmp_path.iterdir()) == []


def test_no_real_points_is_one_line_not_an_empty_file(tmp_path):
    """x^2 + y^2 + z^2 + 1 > 0 everywhere: no solid to mesh (it was a NumPy traceback)."""
    spec = tmp_path / "none.yaml"
    spec.write_text("name: none\nequation: x^2 + y^2 + z^2 + 1\nbounds: {x: [-1, 1], y: [-1, 1], z: [-1, 1]}\n")
    ran = implgen("mesh", spec, "-o", tmp_path / "n.stl")
    assert ran.code == 2 and ran.err.count("\n") == 1 and "Traceback" not in ran.err
    assert ran.err == f"implgen: error: {spec}: no real points of the surface in the region meshed: nothing to mesh\n"
    assert list(tmp_path.iterdir()) == [spec]


def test_every_format_keeps_its_stated_precision(tmp_path):
    """Each format read back by trimesh against the doubles meshed: OBJ (17 significant digits) and PLY (binary
    doubles) give every vertex back exactly; STL and glTF hold float32, so each coordinate is the double rounded
    to float32 (within 2^-24 of its size). The vertices compared are those the report's order gives: the
    written mesh's own, read without merging."""
    from implgen.mesh.pipeline import mesh_spec
    from implgen.mesh.write import vertex_normals, write_mesh
    from implgen.spec.entry import load_spec

    spec = load_spec(TORUS, cache=True)
    result = mesh_spec(spec, {}, 16, [], singular=False)
    verts, faces = result.mesh.vertices, result.mesh.faces
    normals = vertex_normals(result.lib, result.clips, verts)
    for suffix in (".obj", ".ply", ".stl", ".glb"):
        out = tmp_path / f"t{suffix}"
        write_mesh(out, verts, faces, normals)
        back = trimesh.load(out, force="mesh", process=False)
        got = np.asarray(back.vertices, dtype=np.float64)
        want = verts[faces].reshape(-1, 3) if suffix == ".stl" else verts  # STL: three corners per triangle
        if suffix == ".stl":
            got = got[np.asarray(back.faces).reshape(-1)]
        assert got.shape == want.shape, suffix
        if suffix in (".obj", ".ply"):
            assert np.array_equal(got, want), (suffix, np.abs(got - want).max())
        else:
            assert np.array_equal(got, want.astype(np.float32).astype(np.float64)), suffix


def _too_coarse_numbers(err: str) -> tuple[float, float, float]:
    """(cell size, thickness, cells asked for) from the too-coarse line."""
    import re

    cell = float(re.search(r"cells are ([0-9.e+-]+) wide", err).group(1))
    thick = float(re.search(r"find the solid ([0-9.e+-]+) thick", err).group(1))
    need = float(re.search(r"about ([0-9.e+-]+) cells", err).group(1))
    return cell, thick, need


@pytest.mark.parametrize("half, cells_ok", [(1e6, False), (60.0, True)], ids=["1e6", "60"])
def test_a_grid_too_coarse_for_its_box_says_so_and_by_how_much(tmp_path, half, cells_ok):
    """A unit ball in a box of +-half along x (+-1.2 across) at 32 cells: at 1e6 no grid line comes near the ball
    (cells of 62500), at 60 a few grid lines cross it between vertices. Either way the line says the grid is too
    coarse, not that the surface has no real points: the cell size, the solid's thickness along probe lines
    across the region (the ball's diameter 2, to within the probes' spacing) and the cells that would put grid
    vertices in it (the box's length over half that thickness: 2e6, beyond the cap; 120, within it)."""
    spec = tmp_path / "ball.yaml"
    spec.write_text(
        f"name: ball\nequation: x^2 + y^2 + z^2 - 1\nbounds: {{x: [-{half}, {half}], y: [-1.2, 1.2], z: [-1.2, 1.2]}}\n"
    )
    ran = implgen("mesh", spec, "-o", tmp_path / "b.stl", "--cells", "32", "--no-singular")
    assert ran.code == 2 and ran.err.count("\n") == 1 and "Traceback" not in ran.err, ran.err
    assert "no real points" not in ran.err and "--cells 32" in ran.err and "too coarse" in ran.err, ran.err
    cell, thick, need = _too_coarse_numbers(ran.err)
    assert abs(cell - 2 * half / 32) < 1e-9 * half
    assert 1.9 < thick <= 2.0
    assert 2 * half / 1.0 <= need <= 2 * half / 0.95 + 1
    assert ("raise --cells" in ran.err) == cells_ok and ("more than the 256 allowed" in ran.err) != cells_ok
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ball.yaml"]


def test_cells_reported_as_asked_and_the_grid_beside_them(tmp_path):
    """--cells N is the cells along the region's longest side (docs/mesh.md): the report's "cells" is N, the cell
    size that side over N; the grid, with its margin of outside vertices, is "grid_cells"."""
    rep_path = tmp_path / "r.json"
    ran = implgen("mesh", TORUS, "-o", tmp_path / "t.stl", "--cells", "32", "--no-singular", "--report", rep_path)
    assert ran.code == 0, ran.err
    rep = json.loads(rep_path.read_text())
    assert rep["cells"] == 32
    assert abs(rep["cell_size"] * 32 - 2.5) < 1e-12  # torus_z's box: x and y in [-1.25, 1.25]
    assert len(rep["grid_cells"]) == 3 and all(32 < n <= 36 for n in rep["grid_cells"][:2])


@pytest.mark.parametrize(
    "args, says",
    [
        (["--cells", "abc"], "implgen: error: --cells: expected a whole number, not 'abc'\n"),
        (["--cells", "1.5"], "implgen: error: --cells: expected a whole number, not '1.5'\n"),
        (["--cellz", "3"], "implgen: error: mesh: unrecognized arguments: --cellz 3\n"),
    ],
)
def test_a_bad_option_names_the_command_once(tmp_path, args, says):
    """argparse's own errors carry the command once ("mesh: ..."), not "implgen: error: implgen mesh: ..."; a
    --cells that is no whole number is said as any bad value is."""
    ran = implgen("mesh", TORUS, "-o", tmp_path / "t.stl", *args)
    assert ran.code == 2 and ran.err == says
    assert list(tmp_path.iterdir()) == []
