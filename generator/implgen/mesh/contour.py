"""The mesh of a solid f < 0 ∩ clips on a grid: vertex flags, exact crossings (crossings.py), sheets per cell
(cells.py), one dual vertex per sheet (dual.py), one quad per active edge split into two triangles, oriented so
the normal points to f > 0 (outside)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from implgen.mesh import cells
from implgen.mesh.crossings import Crossings, axis_crossings, grid_flags, inside_flags
from implgen.mesh.dual import CREASE, DROP, outside_pieces, project
from implgen.mesh.faces import Quads, triangulate
from implgen.mesh.missed import Missed, missed_detail
from implgen.mesh.region import Clip, Grid
from implgen.mesh.shapelib import ShapeLib

# the four cells around an edge along a, counter-clockwise seen from +a in the (a + 1, a + 2) plane: how far
# below the edge each cell's lower corner is along a + 1 and a + 2
AROUND = ((1, 1), (0, 1), (0, 0), (1, 0))


@dataclass
class Mesh:
    vertices: np.ndarray  # (V, 3)
    faces: np.ndarray  # (F, 3) counter-clockwise seen from outside (f > 0)
    grid: Grid
    stats: dict = field(default_factory=dict)
    cell: np.ndarray | None = None  # per vertex, the flat index of its cell's lower corner (-1: added by faces.py)
    missed: Missed | None = None  # detail the grid misses (missed.py)
    parts: Parts | None = None  # what refine.py needs of the grid's contour; dropped once refined or not


@dataclass
class Parts:
    """The contour's own pieces, kept for refine.py: vertex flags, crossings, cells and their sheets' vertices."""

    inside: np.ndarray
    cross: list[Crossings]
    cells: _Cells
    strides: np.ndarray
    sheet_verts: np.ndarray  # the first cells.nverts vertices, before triangulate() adds its own
    g: np.ndarray  # max(f, clips) at every grid vertex
    quads: Quads
    rowof: np.ndarray  # each grid vertex's row in `cells` (the cell of which it is the lower corner), or -1


def _face_bits(lib, clips, grid: Grid, cell_idx: np.ndarray, config: np.ndarray) -> np.ndarray:
    """Bit f when face f of the cell is ambiguous and the solid's value at its centre is inside. The centre is
    computed from the face's global index, so the two cells that share it read the same point."""
    amb = cells.AMBIGUOUS[config]
    bits = np.zeros(config.shape, dtype=np.int64)
    for f in range(6):
        sel = np.nonzero((amb >> f) & 1)[0]
        if sel.size == 0:
            continue
        a, s = f // 2, f % 2
        idx = cell_idx[sel].astype(np.float64) + 0.5
        idx[:, a] += s - 0.5
        inside, _ = inside_flags(lib, clips, grid.origin + grid.h * idx)
        bits[sel] |= inside.astype(np.int64) << f
    return bits


@dataclass
class _Cells:
    """The active cells (neither all inside nor all outside) and their sheets."""

    flat: np.ndarray  # each cell's lower corner, flat among the grid's vertices
    conf: np.ndarray  # its corners' inside flags, 8 bits
    key: np.ndarray  # conf and the face bits: the row of cells.cell_table
    sheets: np.ndarray  # (C, 12) int8: the sheet of each edge in its cell, -1 where not active
    count: np.ndarray  # sheets per cell
    base: np.ndarray  # each cell's first vertex

    @property
    def nverts(self) -> int:
        return int(self.count.sum())


def _check_outer_layer(inside: np.ndarray) -> None:
    if inside[0].any() or inside[-1].any() or inside[:, 0].any() or inside[:, -1].any():
        raise AssertionError("the grid's outer layer must lie outside every clip")
    if inside[:, :, 0].any() or inside[:, :, -1].any():
        raise AssertionError("the grid's outer layer must lie outside every clip")


def active_cells(lib: ShapeLib, clips: list[Clip], grid: Grid, inside: np.ndarray, strides: np.ndarray) -> _Cells:
    """Corner flags -> config; the active cells get their sheets."""
    ins = inside.view(np.uint8)
    n0, n1, n2 = grid.n
    config = np.zeros((n0, n1, n2), dtype=np.uint8)
    for c, (dx, dy, dz) in enumerate(cells.CORNER_OFFSETS):
        config |= ins[dx : dx + n0, dy : dy + n1, dz : dz + n2] << np.uint8(c)
    cflat = np.flatnonzero((config != 0) & (config != 255))  # in the cells' own (n0, n1, n2) numbering
    cidx = np.stack(np.unravel_index(cflat, grid.n), axis=1)
    conf = config.reshape(-1)[cflat].astype(np.int64)
    key = conf | _face_bits(lib, clips, grid, cidx, conf) << 8
    row, table, nsheets = cells.cell_table(key)
    count = nsheets[row]
    return _Cells(
        flat=cidx @ strides, conf=conf, key=key, sheets=table[row], count=count, base=np.cumsum(count) - count
    )


def dual_vertices(lib: ShapeLib, clips: list[Clip], grid: Grid, cross: list[Crossings], cs: _Cells, strides, clock):
    """Every sheet's crossings -> QEF point (one C loop over the cells) -> onto the surface: (vertices, which of
    them fell back to their sheet's crossing nearest the QEF point, where Newton strayed near a node or a thin
    neck: a crossing lies on the surface exactly). The QEF's end goes on the clock."""
    nv = int(np.prod(grid.shape))
    keys = np.concatenate([a * nv + c.edges for a, c in enumerate(cross)])
    cp = np.concatenate([c.points for c in cross])
    cn = np.concatenate([c.normals for c in cross])
    cpiece = np.concatenate([c.piece for c in cross])
    qef, mask, nearest = lib.sheet_points(
        cs.flat, cs.sheets, cs.base, strides, nv, keys, cp, cn, cpiece, grid.origin, grid.h, CREASE, DROP, cs.nverts
    )
    clock.append(time.perf_counter())
    lib.check()  # the budget, between phases (budget.py)
    verts, projected = project(lib, clips, qef, mask, grid.h, grid.size)
    extra = outside_pieces(lib, clips, verts, mask, grid.size)
    if extra.any():  # on one piece but outside another (a cap vertex past the rim): onto both
        redo = np.nonzero(extra)[0]
        mask[redo] |= extra[redo]
        verts[redo], projected[redo] = project(lib, clips, verts[redo], mask[redo], grid.h, grid.size)
    failed = ~projected
    if failed.any():
        verts[failed] = cp[nearest[failed]]
    return verts, failed


def _quads(grid: Grid, cross: list[Crossings], cs: _Cells, inside: np.ndarray, strides) -> tuple[Quads, np.ndarray]:
    """One quad per active edge, from the sheets of its four cells; and each grid vertex's active cell row."""
    rowof = np.full(int(np.prod(grid.shape)), -1, dtype=np.int64)
    rowof[cs.flat] = np.arange(len(cs.flat))
    parts = []
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        lo_ax, _ = cells.other_axes(a)
        edges = cross[a].edges
        quad = np.empty((edges.size, 4), dtype=np.int64)
        for q, (db, dc) in enumerate(AROUND):
            r = rowof[edges - db * strides[b] - dc * strides[c]]
            u, v = (db, dc) if lo_ax == b else (dc, db)  # the edge's offsets inside that cell
            quad[:, q] = cs.base[r] + cs.sheets[r, 4 * a + u + 2 * v]
        flip = ~inside.reshape(-1)[edges]  # outside below: the outside is toward -a
        parts.append((quad, np.full(edges.size, a), edges, flip, cross[a].points, cross[a].piece))
    return Quads(*(np.concatenate([p[i] for p in parts]) for i in range(6))), rowof


def _stats(clock: list[float], grid: Grid, cross: list[Crossings], cs: _Cells, failed, split, missed) -> dict:
    phases = ("signs", "crossings", "missed", "sheets", "qef", "projection", "faces")
    return {
        "seconds": {k: round(b - a, 4) for k, a, b in zip(phases, clock, clock[1:])},
        "grid_cells": list(grid.n),
        "active_edges": int(sum(c.edges.size for c in cross)),
        "fallback_crossings": int(sum(c.fallback for c in cross)),
        "multi_sheet_cells": int((cs.count > 1).sum()),
        "vertices_at_a_crossing": int(failed.sum()),
        "hidden_crossing_edges": int(sum(c.hidden for c in cross)),
        **missed.stats(),
        "split_sides": split,
    }


def contour(lib: ShapeLib, clips: list[Clip], grid: Grid) -> Mesh:
    """The phases in order, the budget checked between them; each phase's seconds in the stats."""
    clock = [time.perf_counter()]
    inside, g = grid_flags(lib, clips, grid)
    clock.append(time.perf_counter())
    _check_outer_layer(inside)
    strides = np.array([inside.shape[1] * inside.shape[2], inside.shape[2], 1])
    cross: list[Crossings] = [axis_crossings(lib, clips, grid, a, inside, g) for a in range(3)]
    clock.append(time.perf_counter())
    missed = missed_detail(lib, clips, grid, inside, cross)
    clock.append(time.perf_counter())
    lib.check()  # the budget, between phases (budget.py)
    cs = active_cells(lib, clips, grid, inside, strides)
    clock.append(time.perf_counter())
    lib.check()
    verts, failed = dual_vertices(lib, clips, grid, cross, cs, strides, clock)
    clock.append(time.perf_counter())
    lib.check()
    quads, rowof = _quads(grid, cross, cs, inside, strides)
    near_amb = np.repeat(cells.AMBIGUOUS[cs.conf] != 0, cs.count)  # sheets of cells with an ambiguous face
    verts, faces, split = triangulate(quads, verts, near_amb, inside, grid, lib, clips, AROUND, rowof, cs.key)
    clock.append(time.perf_counter())
    cell = np.full(len(verts), -1, dtype=np.int64)
    cell[: cs.nverts] = np.repeat(cs.flat, cs.count)
    stats = _stats(clock, grid, cross, cs, failed, split, missed)
    parts = Parts(inside, cross, cs, strides, verts[: cs.nverts], g, quads, rowof)
    return Mesh(vertices=verts, faces=faces, grid=grid, stats=stats, cell=cell, missed=missed, parts=parts)
