"""A prototype, not `implgen mesh`: what the topology would be if each cell's sheets were built from the exact
crossings on its faces rather than from the signs at its corners (docs/mesh.md, "Why not coarser").

    nice .venv/bin/python bench/mesh_crossing_sheets.py [-o bench/results/mesh_crossing_sheets.md]

Every boundary point of the solid on every grid line is kept, several on one edge included (a thin neck
crossing an edge between two outside vertices). On each face of a cell, the crossings around its border, in
order, bound arcs alternately inside and outside; the face's curves pair them: two crossings, one curve; four or
more, the solid's value at the face centre decides (inside: each curve cuts off an outside arc; else an inside
one), as `implgen mesh` decides an ambiguous face. The curves on a cell's six faces close into loops: one sheet
per loop. Each crossing gives a quad of the sheets holding it in the four cells around its edge, oriented by the
side the solid is on below it. Two cells pair a shared face's crossings alike, so the quads close up. Only the
topology is measured: Euler characteristic V - Q of the quad complex, closed when every directed quad side is
matched by its reverse. Python loops per cell: small grids only.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter, defaultdict
from pathlib import Path

import numpy as np

from implgen.measure.machine import describe as machine
from implgen.measure.machine import write_results
from implgen.mesh.contour import contour
from implgen.mesh.crossings import grid_flags, inside_flags, line_points
from implgen.mesh.pipeline import closed_and_euler
from implgen.mesh.region import make_grid
from implgen.spec.entry import load_spec

ROOT = Path(__file__).resolve().parents[1]
# (label, spec, known Euler characteristic, grids: the sign-based method's smallest right one and below)
CASES = (
    ("torus", "examples/shapes/torus_z.yaml", 0, (4, 5, 6)),
    ("tanglecube", "examples/mesh/tanglecube.yaml", -8, (8, 12, 14, 16)),
    ("Chmutov 8", "examples/shapes/chmutov8.yaml", -160, (8, 12, 14)),
    ("Chmutov 12 (degree 12)", "examples/mesh/chmutov12.yaml", -648, (24, 32, 48)),
    ("Chmutov 20 (degree 20)", "examples/mesh/chmutov20.yaml", -3400, (48, 64, 96)),
)


def edge_crossings(lib, clips, grid):
    """{(axis, i, j, k): crossing ids along the edge from vertex (i, j, k), ascending}, and the points."""
    shape = grid.shape
    edges, pts = defaultdict(list), []
    for axis in range(3):
        base = np.indices(tuple(1 if a == axis else s for a, s in enumerate(shape))).reshape(3, -1).T
        starts = grid.origin + grid.h * base
        line, t, _ = line_points(lib, clips, grid.n[axis] * grid.h, axis, starts)
        step = np.clip(np.floor(t / grid.h).astype(np.int64), 0, shape[axis] - 2)
        for li, tt, st in zip(line, t, step):
            idx = base[li].copy()
            idx[axis] = st
            edges[(axis, *map(int, idx))].append(len(pts))
            p = starts[li].copy()
            p[axis] += tt
            pts.append(p)
    return edges, np.array(pts)


def face_pairs(loop, first_inside, centre_inside):
    """The curves on a face: pairs of crossings, given in order around its border (the arc before loop[0] holds
    a corner, inside or not)."""
    m = len(loop)
    if m == 2:
        return [(loop[0], loop[1])]
    out = []
    for r in range(1, m + 1):  # arc r runs from loop[r - 1] to loop[r % m]
        if (first_inside ^ (r % 2 == 1)) != centre_inside:
            out.append((loop[r - 1], loop[r % m]))
    return out


def cell_sheets(cell, edges, inside, lib, clips, grid, many: set):
    """{crossing id: sheet number in the cell}, from the curves on the cell's faces. many: gets the faces with
    six or more crossings (three curves or more, the centre alone deciding how they pair)."""
    parent = {}

    def find(x):
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a in range(3):
        b, c = (x for x in range(3) if x != a)
        for s in (0, 1):
            org = list(cell)
            org[a] += s

            def corner(ob, oc):
                q = list(org)
                q[b] += ob
                q[c] += oc
                return q

            loop = []
            for (ob, oc), ax, back in (((0, 0), b, False), ((1, 0), c, False), ((0, 1), b, True), ((0, 0), c, True)):
                ids = edges.get((ax, *corner(ob, oc)), [])
                loop += ids[::-1] if back else ids
            if not loop:
                continue
            if len(loop) >= 6:
                many.add((a, *org))
            if len(loop) % 2:
                raise RuntimeError(f"an odd number of crossings around a face of cell {cell}")
            centre = np.array(org, dtype=np.float64) + 0.5
            centre[a] -= 0.5
            c_in = len(loop) > 2 and bool(inside_flags(lib, clips, (grid.origin + grid.h * centre)[None])[0][0])
            for x in loop:
                parent.setdefault(x, x)
            for x, y in face_pairs(loop, bool(inside[tuple(corner(0, 0))]), c_in):
                parent[find(x)] = find(y)
    roots = {}
    return {x: roots.setdefault(find(x), len(roots)) for x in parent}


def crossing_topology(lib, clips, grid):
    """(closed, Euler characteristic, faces with six or more crossings) of the quad complex of the
    crossing-built sheets."""
    inside, _ = grid_flags(lib, clips, grid)
    edges, _ = edge_crossings(lib, clips, grid)
    cells = set()
    for a, i, j, k in edges:
        b, c = (x for x in range(3) if x != a)
        for db in (0, 1):
            for dc in (0, 1):
                cell = [i, j, k]
                cell[b] -= db
                cell[c] -= dc
                if all(0 <= cell[x] < grid.n[x] for x in range(3)):
                    cells.add(tuple(cell))
    sheet, count, many = {}, 0, set()
    for cell in sorted(cells):
        local = cell_sheets(cell, edges, inside, lib, clips, grid, many)
        for x, s in local.items():
            sheet[(cell, x)] = count + s
        count += max(local.values(), default=-1) + 1
    quads = []
    for (a, i, j, k), ids in edges.items():
        b, c = (a + 1) % 3, (a + 2) % 3  # counter-clockwise about +a, as contour.AROUND
        for n, x in enumerate(ids):
            quad = []
            for db, dc in ((1, 1), (0, 1), (0, 0), (1, 0)):
                cell = [i, j, k]
                cell[b] -= db
                cell[c] -= dc
                quad.append(sheet.get((tuple(cell), x)))
            if None in quad:
                return False, None, len(many)
            below_inside = bool(inside[i, j, k]) ^ (n % 2 == 1)
            quads.append(quad if below_inside else quad[::-1])
    sides = Counter((q[r], q[(r + 1) % 4]) for q in quads for r in range(4))
    closed = all(sides[(u, v)] == sides[(v, u)] and u != v for u, v in sides)
    return closed, len({v for q in quads for v in q}) - len(quads), len(many)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("-o", "--output", default=str(ROOT / "bench/results/mesh_crossing_sheets.md"))
    args = ap.parse_args()
    from implgen.mesh.shapelib import ShapeLib

    rows = [
        "| surface | cells | sign-based (`implgen mesh`): closed, Euler | crossing-based: closed, Euler | known "
        "| faces with 6+ crossings |",
        "|---|---|---|---|---|---|",
    ]
    for label, path, known, grids in CASES:
        spec = load_spec(ROOT / path, cache=True)
        lib = ShapeLib(spec, list(spec.params.values()))
        for n in grids:
            grid, clips = make_grid(spec.box(), [], n, path)
            m = contour(lib, clips, grid)
            signs = closed_and_euler(m.faces, len(m.vertices)) if len(m.faces) else (False, None)
            cross = crossing_topology(lib, clips, grid)
            rows.append(f"| {label} | {n} | {signs[0]}, {signs[1]} | {cross[0]}, {cross[1]} | {known} | {cross[2]} |")
            print(rows[-1], flush=True)
    lines = [
        "# Sheets from the crossings: a prototype's topology",
        "",
        f"Machine: {machine()}.",
        "Written by `nice .venv/bin/python bench/mesh_crossing_sheets.py` (see its docstring for the method).",
        "",
        *rows,
        "",
    ]
    write_results(Path(args.output), "\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
