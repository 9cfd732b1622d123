"""A mesh's bounds (implgen.mesh.budget): the deadline stops a heavy mesh soon after it passes and a generous one
changes nothing (the C batch calls cut in slices give the same doubles); a stop from another thread ends a mesh;
the cells are checked before any work; the memory estimate is above the measured peak; `implgen mesh
--time-limit` is one line and exit status 2 when it runs out, or when it is not a positive number."""

from __future__ import annotations

import threading
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from implgen.errors import UserError
from implgen.mesh import budget, pipeline, shapelib
from implgen.mesh.budget import OverBudget, Stopped
from implgen.mesh.pipeline import mesh_spec
from implgen.mesh.region import parse_clip
from implgen.mesh.write import mesh_bytes, vertex_normals
from implgen.spec.entry import load_spec
from implgen_proc import implgen

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ROOT / "examples/mesh/chmutov20.yaml"  # degree 20: the costliest of bench/results/mesh_budget.md
TORUS = ROOT / "examples/shapes/torus_z.yaml"
# How far past its deadline a mesh may stop: a slice of a C batch call or one phase's NumPy work (at most 0.13 s
# in bench/results/mesh_budget.md; 4.2 s before the contour's phases moved into C), with room for a loaded 2-core
# machine. Far below the unbudgeted run.
LATE = 6.0


@pytest.fixture(scope="module")
def heavy():
    spec = load_spec(HEAVY, cache=True)
    mesh_spec(spec, {}, 4, [], singular=False)  # its library built and cached: the budget is the mesh's own
    return spec


def test_a_tiny_budget_stops_a_heavy_mesh_soon_after_its_deadline(heavy) -> None:
    for seconds in (0.05, 0.6):
        t0 = time.monotonic()
        with pytest.raises(OverBudget) as info:
            mesh_spec(heavy, {}, 192, [], deadline=t0 + seconds, seconds=seconds)
        late = time.monotonic() - t0 - seconds
        assert 0 <= late < LATE, late
        assert str(info.value) == (
            f"mesh: over its time budget of {seconds:g} s at 192 cells ({info.value.phase}); try fewer cells"
        )
        assert isinstance(info.value, UserError)  # the CLI's and the viewer's one line


def test_a_past_deadline_stops_before_the_shape_is_built(monkeypatch) -> None:
    monkeypatch.setattr(pipeline, "ShapeLib", lambda *a: pytest.fail("built after the deadline"))
    with pytest.raises(OverBudget, match="building the shape"):
        mesh_spec(load_spec(TORUS, cache=True), {}, 16, [], deadline=time.monotonic() - 1)


def test_the_message_names_the_budget_given_not_what_is_left_of_it(monkeypatch) -> None:
    """A pause between the deadline and the mesh's start (a loaded machine, a process starting) shortens what is
    left of the budget: the message still says the seconds given."""
    now = [1000.0]
    monkeypatch.setattr(budget.time, "monotonic", lambda: now[0])
    timed = budget.Budget(1000.0 + 0.05, None, 192, "meshing", seconds=0.05)
    now[0] = 1000.0 + 0.05 + 1e-3
    with pytest.raises(OverBudget) as info:
        timed.check()
    assert str(info.value) == "mesh: over its time budget of 0.05 s at 192 cells (meshing); try fewer cells"
    now[0] = 1000.0
    late = budget.Budget(1000.0 + 0.05 - 1e-4, None, 192, "meshing", seconds=0.05)  # made after a pause
    now[0] = 1001.0
    with pytest.raises(OverBudget, match="of 0.05 s at 192 cells"):
        late.check()
    with pytest.raises(OverBudget, match="of 0.05 s at 16 cells"):  # mesh_spec passes it on
        mesh_spec(load_spec(TORUS, cache=True), {}, 16, [], deadline=now[0] - 1, seconds=0.05)


def test_bad_cells_name_the_option_given() -> None:
    for name in ("--cells", "cells"):
        with pytest.raises(UserError) as info:
            mesh_spec(load_spec(TORUS, cache=True), {}, 3, [], cells_name=name)
        assert info.value.source == name
    with pytest.raises(UserError) as info:
        mesh_spec(load_spec(TORUS, cache=True), {}, 3, [])
    assert info.value.source == "--cells"


def test_a_generous_budget_gives_the_same_mesh_slice_by_slice(monkeypatch) -> None:
    """With a budget every batch call runs in slices; made tiny here (a few rays, points or grid slabs each) so
    that every call is cut many times, the mesh is the same to the last bit, singular points included."""
    spec = load_spec(ROOT / "examples/mesh/cayley.yaml", cache=True)
    clips = parse_clip("sphere:2")
    free = mesh_spec(spec, {}, 24, clips)
    calls = []
    real = shapelib.ShapeLib._slices

    def counted(self, n, size):
        for s in real(self, n, size):
            calls.append(s)
            yield s

    monkeypatch.setattr(shapelib, "ROWS", 7)
    monkeypatch.setattr(shapelib, "POINTS", 1000)
    monkeypatch.setattr(shapelib.ShapeLib, "_slices", counted)
    timed = mesh_spec(spec, {}, 24, clips, deadline=time.monotonic() + 1000, cancel=threading.Event())
    assert len(calls) > 1000  # cut, and checked, many times
    assert np.array_equal(free.mesh.vertices, timed.mesh.vertices)
    assert np.array_equal(free.mesh.faces, timed.mesh.faces)
    assert np.array_equal(free.singular.points, timed.singular.points) and len(free.singular.points) == 4


def test_a_stop_from_another_thread_ends_the_mesh(heavy) -> None:
    stop = threading.Event()
    timer = threading.Timer(0.3, stop.set)
    t0 = time.monotonic()
    timer.start()
    with pytest.raises(Stopped):
        mesh_spec(heavy, {}, 192, [], cancel=stop)
    assert time.monotonic() - t0 < 0.3 + LATE


@pytest.mark.parametrize("cells", [3, 257, 100_000, 64.0, True, "64"])
def test_cells_are_checked_before_any_work(monkeypatch, cells) -> None:
    monkeypatch.setattr(pipeline, "ShapeLib", lambda *a: pytest.fail("built before the cells were checked"))
    with pytest.raises(UserError, match=r"expected a whole number of cells in \[4, 256\]"):
        mesh_spec(load_spec(TORUS, cache=True), {}, cells, [])
    with pytest.raises(UserError, match="cells"):
        budget.estimate_bytes([-1, -1, -1, 1, 1, 1], 4, [], cells, "test")


MEMORY_CASES = [
    (TORUS, None, 40),
    (ROOT / "examples/shapes/chmutov8.yaml", None, 40),
    (ROOT / "examples/shapes/barth6.yaml", "sphere:1.8", 32),
]


@pytest.mark.parametrize("path, clip, cells", MEMORY_CASES)
def test_the_memory_estimate_is_above_the_peak(path, clip, cells) -> None:
    """What Save mesh does (the pipeline, the normals, the STL's bytes), traced by tracemalloc, against the estimate
    made before any work; the estimate grows as cells^2 to cells^3."""
    spec = load_spec(path, cache=True)
    clips = parse_clip(clip) if clip else []

    def run(n: int) -> int:
        tracemalloc.start()
        try:
            result = mesh_spec(spec, {}, n, clips, singular=False)
            normals = vertex_normals(result.lib, result.clips, result.mesh.vertices)
            mesh_bytes("stl", result.mesh.vertices, result.mesh.faces, normals)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    run(8)  # imports and caches, not the mesh's own
    peak = run(cells)
    est = budget.estimate_bytes(spec.box({}), spec.degree, clips, cells, "test")
    assert peak < est < 10 * peak, (peak, est)
    ratio = budget.estimate_bytes(spec.box({}), spec.degree, clips, 2 * cells, "test") / est
    assert 3.5 < ratio < 8.5


def test_the_estimate_refuses_an_unbounded_region_before_any_work() -> None:
    with pytest.raises(UserError, match="unbounded"):
        budget.estimate_bytes(None, 2, [], 64, "cone.yaml")


def test_cli_time_limit_is_one_line_and_writes_nothing(tmp_path, heavy) -> None:
    out = tmp_path / "c.stl"
    ran = implgen("mesh", HEAVY, "-o", out, "--cells", "192", "--time-limit", "0.3")
    assert ran.code == 2 and ran.out == ""
    assert ran.err.count("\n") == 1 and "over its time budget of 0.3 s at 192 cells" in ran.err, ran.err
    assert "Traceback" not in ran.err and not out.exists() and list(tmp_path.iterdir()) == []
    for bad, says in (("0", "outside (0"), ("-2", "outside (0"), ("soon", "expected a finite number"), ("nan", "")):
        ran = implgen("mesh", TORUS, "-o", out, "--time-limit", bad)
        assert ran.code == 2 and ran.err.count("\n") == 1 and ran.err.startswith("implgen: error: --time-limit")
        assert says in ran.err and not out.exists()
    ran = implgen("mesh", TORUS, "-o", out, "--cells", "16", "--time-limit", "600")
    assert ran.code == 0 and out.exists(), ran.err
