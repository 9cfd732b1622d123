"""The mesh of a solid f < 0 ∩ clips on a grid: vertex flags, exact crossings (crossings.py), sheets per cell
(cells.py), one dual vertex per sheet (dual.py), one quad per active edge split into two triangles, oriented so
the normal points to f > 0 (outside)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from implgen.mesh import cells
from implgen.mesh.crossings import Crossings, axis_crossings, grid_flags, inside_flags
from implgen.mesh.dual import outside_pieces, piece_mask, project, qef_points
from implgen.mesh.faces import Quads, triangulate
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


def _corner_offsets(strides: np.ndarray) -> np.ndarray:
    return np.array([((c & 1) * strides[0] + (c >> 1 & 1) * strides[1] + (c >> 2 & 1) * strides[2]) for c in range(8)])


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


def contour(lib: ShapeLib, clips: list[Clip], grid: Grid) -> Mesh:
    clock = [time.perf_counter()]
    inside, g = grid_flags(lib, clips, grid)
    clock.append(time.perf_counter())
    shape = inside.shape
    strides = np.array([shape[1] * shape[2], shape[2], 1])
    if inside[0].any() or inside[-1].any() or inside[:, 0].any() or inside[:, -1].any():
        raise AssertionError("the grid's outer layer must lie outside every clip")
    if inside[:, :, 0].any() or inside[:, :, -1].any():
        raise AssertionError("the grid's outer layer must lie outside every clip")
    cross: list[Crossings] = [axis_crossings(lib, clips, grid, a, inside, g) for a in range(3)]
    clock.append(time.perf_counter())
    lib.check()  # the budget, between phases (budget.py)

    # cells: corner flags -> config; active ones get their sheets
    ins = inside.view(np.uint8)
    n0, n1, n2 = grid.n
    config = np.zeros((n0, n1, n2), dtype=np.uint8)
    for c in range(8):
        dx, dy, dz = c & 1, c >> 1 & 1, c >> 2 & 1
        config |= ins[dx : dx + n0, dy : dy + n1, dz : dz + n2] << np.uint8(c)
    cidx = np.argwhere((config != 0) & (config != 255))
    if len(cidx) == 0:  # no boundary in the grid: nothing to mesh (pipeline.py says so)
        return Mesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64), grid, {"cells": list(grid.n)})
    conf = config[tuple(cidx.T)].astype(np.int64)
    cflat = np.ravel_multi_index(tuple(cidx.T), shape)
    key = conf | _face_bits(lib, clips, grid, cidx, conf) << 8
    row, table, nsheets = cells.cell_table(key)
    sheets = table[row]  # (C, 12)
    count = nsheets[row]
    base = np.concatenate([[0], np.cumsum(count)[:-1]])
    cellvert = np.where(sheets >= 0, base[:, None] + sheets, -1)
    nverts = int(count.sum())

    clock.append(time.perf_counter())
    lib.check()  # the budget, between phases (budget.py)
    # every sheet's crossings -> QEF point -> onto the surface
    corner = _corner_offsets(strides)
    vids, cps, cns, cpieces = [], [], [], []
    for e in range(12):
        has = np.nonzero(cellvert[:, e] >= 0)[0]
        a = e // 4
        start, _ = cells.edge_corners(e)
        edge = cflat[has] + corner[start]
        k = np.searchsorted(cross[a].edges, edge)
        vids.append(cellvert[has, e])
        cps.append(cross[a].points[k])
        cns.append(cross[a].normals[k])
        cpieces.append(cross[a].piece[k])
    vid, cp, cn, cpiece = (np.concatenate(x) for x in (vids, cps, cns, cpieces))
    cell_of_vertex = np.repeat(np.arange(len(cidx)), count)
    lower = grid.origin + grid.h * cidx[cell_of_vertex]
    qef = qef_points(vid, cp, cn, nverts, lower, grid.h)
    mask = piece_mask(vid, cpiece, nverts)
    clock.append(time.perf_counter())
    lib.check()  # the budget, between phases (budget.py)
    verts, projected = project(lib, clips, qef, mask, grid.h, grid.size)
    extra = outside_pieces(lib, clips, verts, mask, grid.size)
    if extra.any():  # on one piece but outside another (a cap vertex past the rim): onto both
        redo = np.nonzero(extra)[0]
        mask[redo] |= extra[redo]
        verts[redo], projected[redo] = project(lib, clips, verts[redo], mask[redo], grid.h, grid.size)
    failed = ~projected
    if failed.any():  # Newton strayed (near a node, a thin neck): the sheet's crossing nearest the QEF point,
        d = np.linalg.norm(cp - qef[vid], axis=1)  # which lies on the surface exactly
        order = np.lexsort((d, vid))
        first = order[np.unique(vid[order], return_index=True)[1]]
        verts[failed] = cp[first][failed]

    clock.append(time.perf_counter())
    lib.check()  # the budget, between phases (budget.py)
    # one quad per active edge, from the sheets of its four cells
    rowof = np.full(int(np.prod(shape)), -1, dtype=np.int64)
    rowof[cflat] = np.arange(len(cflat))
    parts = []
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        lo_ax, _ = cells.other_axes(a)
        edges = cross[a].edges
        quad = np.empty((edges.size, 4), dtype=np.int64)
        for q, (db, dc) in enumerate(AROUND):
            r = rowof[edges - db * strides[b] - dc * strides[c]]
            u, v = (db, dc) if lo_ax == b else (dc, db)  # the edge's offsets inside that cell
            quad[:, q] = cellvert[r, 4 * a + u + 2 * v]
        flip = ~inside.reshape(-1)[edges]  # outside below: the outside is toward -a
        parts.append((quad, np.full(edges.size, a), edges, flip, cross[a].points, cross[a].piece))
    quads = Quads(*(np.concatenate([p[i] for p in parts]) for i in range(6)))
    near_amb = np.repeat(cells.AMBIGUOUS[conf] != 0, count)  # sheets of cells with an ambiguous face
    verts, faces, split = triangulate(quads, verts, near_amb, inside, grid, lib, clips, AROUND)
    clock.append(time.perf_counter())
    phases = ("signs", "crossings", "sheets", "qef", "projection", "faces")
    stats = {
        "seconds": {k: round(b - a, 4) for k, a, b in zip(phases, clock, clock[1:])},
        "cells": list(grid.n),
        "active_edges": int(sum(c.edges.size for c in cross)),
        "fallback_crossings": int(sum(c.fallback for c in cross)),
        "multi_sheet_cells": int((count > 1).sum()),
        "vertices_at_a_crossing": int(failed.sum()),
        "hidden_crossing_edges": int(sum(c.hidden for c in cross)),
        "split_sides": split,
    }
    cell = np.full(len(verts), -1, dtype=np.int64)
    cell[:nverts] = cflat[cell_of_vertex]
    return Mesh(vertices=verts, faces=faces, grid=grid, stats=stats, cell=cell)
