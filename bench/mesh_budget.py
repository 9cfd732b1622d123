"""A mesh's bounds (mesh/budget.py), measured: the memory of a mesh as the viewer's Save mesh makes it (mesh
pipeline without the singular search, vertex normals, binary STL bytes) against the upper estimate the viewer
reserves before it starts; and how long after its deadline a mesh stops.

    nice .venv/bin/python bench/mesh_budget.py [--cells 32 64 128] [-o bench/results/mesh_budget.md]

Per surface and grid: the grid's vertices V, its active edges E (known only once meshed), the bound on E the
estimate uses (lines x crossings per line), the peak of NumPy's memory traced by tracemalloc, and the estimate.
Then the least-squares fit peak = a V + b E over every run: what a grid vertex and an active edge cost, which
budget.GRID_BYTES and budget.EDGE_BYTES must exceed.

The deadline: Chmutov 20 (the costliest surface here) at OVERRUN_CELLS cells, with the singular search, under
budgets of OVERRUN_BUDGETS seconds: the time from the deadline to the OverBudget, and the phase it stopped in. A
check runs between slices of the shape's C batch calls and between the contour's phases; the NumPy work inside
one phase is not cut, so the overrun is at most about the longest such stretch.

Last, the singular-point search alone (which Save mesh skips and the estimate leaves out: its cost does not
depend on the cells), its time and traced peak, on SINGULAR_SURFACES.
"""

from __future__ import annotations

import argparse
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np

from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results
from implgen.mesh import budget
from implgen.mesh.budget import OverBudget
from implgen.mesh.pipeline import mesh_spec
from implgen.mesh.region import make_grid, parse_clip
from implgen.mesh.singular import find_singular
from implgen.mesh.write import mesh_bytes, vertex_normals
from implgen.spec.entry import load_spec

ROOT = Path(__file__).resolve().parents[1]
SURFACES = (
    ("torus", "examples/shapes/torus_z.yaml", None),
    ("heart", "examples/shapes/heart.yaml", None),
    ("Barth sextic in a ball of 1.8", "examples/shapes/barth6.yaml", "sphere:1.8"),
    ("Chmutov 8", "examples/shapes/chmutov8.yaml", None),
    ("tanglecube", "examples/mesh/tanglecube.yaml", None),
    ("Chmutov 20", "examples/mesh/chmutov20.yaml", None),
)
SINGULAR_SURFACES = ("Barth sextic in a ball of 1.8", "Chmutov 8", "Chmutov 20")
OVERRUN_SPEC, OVERRUN_CELLS, OVERRUN_BUDGETS = "examples/mesh/chmutov20.yaml", 192, (0.25, 0.5, 1, 2, 4, 8, 16)


def overrun(spec, seconds: float) -> tuple[float, str]:
    """(seconds from the deadline to the OverBudget, or NaN when the mesh finished; the phase it stopped in)."""
    t0 = time.monotonic()
    try:
        mesh_spec(spec, {}, OVERRUN_CELLS, [], deadline=t0 + seconds, seconds=seconds)
    except OverBudget as err:
        return time.monotonic() - t0 - seconds, err.phase
    return float("nan"), "finished"


def measure(spec, clips: list, cells: int) -> tuple[int, int, int, int, float]:
    """(V, E, bound on E, peak bytes, seconds) of one Save-mesh-like run."""
    tracemalloc.start()
    t0 = time.perf_counter()
    result = mesh_spec(spec, {}, cells, clips, singular=False)
    normals = vertex_normals(result.lib, result.clips, result.mesh.vertices)
    mesh_bytes("stl", result.mesh.vertices, result.mesh.faces, normals)
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    grid, all_clips = make_grid(spec.box({}), clips, cells, "bench")
    n = grid.n
    verts = (n[0] + 1) * (n[1] + 1) * (n[2] + 1)
    bound = (budget.grid_bytes(grid, all_clips, spec.degree) - budget.GRID_BYTES * verts) // budget.EDGE_BYTES
    return verts, result.mesh.stats["active_edges"], bound, peak, seconds


def singular_cost(spec, clips: list) -> tuple[float, float, int, bool]:
    """(seconds, peak MB, points, complete) of the singular search over the region of a mesh at 8 cells."""
    result = mesh_spec(spec, {}, 8, clips, singular=False)
    g = result.mesh.grid
    tracemalloc.start()
    t0 = time.perf_counter()
    sing = find_singular(result.lib, g.origin, g.origin + g.h * np.array(g.n))
    seconds = time.perf_counter() - t0
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return seconds, peak / 2**20, len(sing.points), sing.complete


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cells", type=int, nargs="+", default=[32, 64, 128])
    ap.add_argument("-o", "--output", default=str(ROOT / "bench" / "results" / "mesh_budget.md"))
    args = ap.parse_args(argv)
    rows, runs, ratios = [], [], []
    for label, path, clip in SURFACES:
        spec = load_spec(ROOT / path, cache=True)
        clips = parse_clip(clip) if clip else []
        measure(spec, clips, 8)  # the library built, trimesh imported, the caches filled: not measured
        for cells in args.cells:
            verts, edges, bound, peak, seconds = measure(spec, clips, cells)
            est = budget.estimate_bytes(spec.box({}), spec.degree, clips, cells, "bench")
            runs.append((verts, edges, peak))
            ratios.append(est / peak)
            row = (
                f"| {label} | {cells} | {verts} | {edges} | {bound} | {peak / 2**20:.1f} | {est / 2**20:.1f} | "
                f"{peak / est:.2f} | {seconds:.2f} |"
            )
            print(row, flush=True)
            rows.append(row)
    a = np.array([[v, e] for v, e, _ in runs], dtype=np.float64)
    y = np.array([p for _, _, p in runs], dtype=np.float64)
    (per_vertex, per_edge), *_ = np.linalg.lstsq(a, y, rcond=None)
    worst = max(p / (budget.GRID_BYTES * v + budget.EDGE_BYTES * e) for v, e, p in runs)
    fit = (
        f"Fit over the {len(runs)} runs: peak = {per_vertex:.1f} bytes a grid vertex + {per_edge:.0f} bytes an active "
        f"edge. budget.GRID_BYTES = {budget.GRID_BYTES}, budget.EDGE_BYTES = {budget.EDGE_BYTES}: the largest peak "
        f"over (GRID_BYTES V + EDGE_BYTES E) with the true E is {worst:.2f}; the estimate (with the bound on E) "
        f"is {min(ratios):.2f} to {max(ratios):.1f} times the peak."
    )
    print(fit)
    sing_rows = []
    for label, path, clip in SURFACES:
        if label in SINGULAR_SURFACES:
            seconds, mb, count, complete = singular_cost(
                load_spec(ROOT / path, cache=True), parse_clip(clip) if clip else []
            )
            row = f"| {label} | {seconds:.1f} | {mb:.0f} | {count} | {'yes' if complete else 'no'} |"
            print(row, flush=True)
            sing_rows.append(row)
    spec = load_spec(ROOT / OVERRUN_SPEC, cache=True)
    late = []
    for seconds in OVERRUN_BUDGETS:
        after, phase = overrun(spec, seconds)
        row = f"| {seconds:g} | {after:.3f} | {phase} |"
        print(row, flush=True)
        late.append(row)
    text = "\n".join(
        [
            "# A mesh's bounds: memory against the estimate, and the deadline",
            "",
            f"Machine: {machine()}; load average {load_average()}.",
            f"Written by `bench/mesh_budget.py --cells {' '.join(map(str, args.cells))}`: each run is the mesh "
            "pipeline without the singular search, the vertex normals and the binary STL's bytes, as the viewer's "
            "Save mesh makes them; its peak is NumPy's memory as tracemalloc traces it.",
            "",
            "| surface | cells | grid vertices V | active edges E | bound on E | peak MB | estimate MB "
            "| peak / estimate | seconds |",
            "|---|---|---|---|---|---|---|---|---|",
            *rows,
            "",
            fit,
            "",
            f"## The deadline: Chmutov 20 at {OVERRUN_CELLS} cells, singular search on",
            "",
            "| budget (s) | stopped this long after the deadline (s) | phase |",
            "|---|---|---|",
            *late,
            "",
            "## The singular-point search alone (not in Save mesh, nor in the estimate)",
            "",
            "| surface | seconds | peak MB | points | complete |",
            "|---|---|---|---|---|",
            *sing_rows,
            "",
        ]
    )
    write_results(Path(args.output), text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
