"""Local refinement: a finer grid over blocks of cells where the grid misses detail, stitched to the rest.

Where detail hides between grid vertices -- an interval that missed.py flags, or a critical point of f whose feature
(critical.py) is less than half a cell across --, a block of the grid's cells around it (the site's cell and one
more on every side; sites whose blocks touch or overlap share one, their bounding box) is meshed again on a grid r
times finer (r a power of 2, the same for the whole block, at most RMAX: fine cells at most SIDE x w / sqrt(2)
across for an interval w long, SIDE x sqrt(2) x d for a feature of size d, so that a fine grid line or face diagonal
passes inside it), by the same steps as the grid: signs at the fine vertices, every root on every fine grid line, a
vertex per sheet of each fine cell. The fine grid's vertices on the block's faces include the grid's there, at the
very same doubles. Where the fine grid itself still misses detail (missed.py on it, away from the block's faces), the
block is meshed once more, 4 times finer (at most RMAX).

How a block meets the grid's cells around it, and when it is grown: stitch.py. The result is checked: every edge in
two triangles, once each way, and every vertex's triangles one fan. If a block cannot be made consistent, the fine
cells would pass MAX_FINE, or the check fails, the grid's own mesh is kept and the report says why.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.contour import Mesh, Parts, active_cells, dual_vertices
from implgen.mesh.critical import critical_points
from implgen.mesh.crossings import axis_crossings, grid_flags
from implgen.mesh.manifold import closed_and_euler, one_fan_each
from implgen.mesh.missed import Missed, missed_detail
from implgen.mesh.region import Clip, Grid
from implgen.mesh.shapelib import ShapeLib
from implgen.mesh.stitch import Block, Fine, Inconsistent, SubGrid, block_faces, coarse_faces

RMAX = 32  # the finest a block goes: 1/32 of a cell
MAX_FINE = 1 << 22  # fine cells over all blocks, 4,194,304 (about 42 bytes each at the peak: 176 MB)
SIDE = 0.9  # fine cells at most 0.9 x sqrt(2) the feature's size across (a fine grid line then passes within it)
GROW = 3  # tries, besides the first and one finer, to grow blocks whose faces disagree with the grid


def ratio_for(h: float, width: np.ndarray) -> np.ndarray:
    """The power of 2 (2 to RMAX) that makes cells of h / r at most `width` across."""
    need = np.log2(np.maximum(h / np.maximum(width, 1e-300), 1.0))
    return np.minimum(2 ** np.maximum(np.ceil(need), 1), RMAX).astype(np.int64)


def blocks_for(grid: Grid, points: np.ndarray, ratio: np.ndarray) -> list[Block]:
    """A block of 3 x 3 x 3 cells about each site, within the grid's inner cells; touching ones merged."""
    n = np.array(grid.n)
    cell = np.floor((points - grid.origin) / grid.h).astype(np.int64)
    out = [Block(np.clip(c - 1, 1, n - 2), np.clip(c + 2, 2, n - 1), int(r)) for c, r in zip(cell, ratio)]
    return merge(out, n)


def merge(blocks: list[Block], n: np.ndarray) -> list[Block]:
    """Blocks whose closed boxes meet (a shared vertex would join two fine grids) become their bounding box."""
    out = list(blocks)
    changed = True
    while changed:
        changed = False
        for i in range(len(out)):
            for j in range(i + 1, len(out)):
                a, b = out[i], out[j]
                if (a.lo <= b.hi).all() and (b.lo <= a.hi).all():
                    out[i] = Block(np.minimum(a.lo, b.lo), np.maximum(a.hi, b.hi), max(a.r, b.r))
                    del out[j]
                    changed = True
                    break
            if changed:
                break
    return out


def grow(block: Block, n: np.ndarray) -> Block:
    return Block(np.maximum(block.lo - 1, 1), np.minimum(block.hi + 1, n - 1), block.r)


def mesh_block(lib: ShapeLib, clips: list[Clip], grid: Grid, block: Block) -> Fine:
    """The block's fine grid, its signs, crossings, cells and their sheets' vertices."""
    r = block.r
    off = block.lo * r
    h = grid.h / r
    n = tuple(int(v) for v in (block.hi - block.lo) * r)
    sub = SubGrid(origin=grid.origin + h * off, h=h, n=n, base=grid.origin, offset=off, whole=grid.size)  # type: ignore[arg-type]
    inside, g = grid_flags(lib, clips, sub)
    strides = np.array([inside.shape[1] * inside.shape[2], inside.shape[2], 1])
    cross = [axis_crossings(lib, clips, sub, a, inside, g) for a in range(3)]
    cs = active_cells(lib, clips, sub, inside, strides)
    verts, _ = dual_vertices(lib, clips, sub, cross, cs, strides, [])
    rowof = np.full(inside.size, -1, dtype=np.int64)
    rowof[cs.flat] = np.arange(len(cs.flat))
    return Fine(block, sub, inside, cross, cs, strides, verts, rowof)


def _shared_flags_agree(parts: Parts, fine: Fine) -> bool:
    """The fine grid's flags at the grid's own vertices in the block are the grid's."""
    r, blk = fine.block.r, fine.block
    sl = tuple(slice(int(lo), int(hi) + 1) for lo, hi in zip(blk.lo, blk.hi))
    return bool(np.array_equal(fine.inside[::r, ::r, ::r], parts.inside[sl]))


@dataclass
class _Built:
    verts: np.ndarray
    faces: np.ndarray
    cell: np.ndarray
    fines: list[Fine]
    split: int
    ncoarse: int  # the first triangles: the grid's own, unchanged (one fan at each vertex by construction)


def build(lib, clips, mesh: Mesh, blocks: list[Block]) -> _Built:
    """The grid's mesh outside the blocks, each block's fine mesh, stitched (Inconsistent names a block)."""
    parts = mesh.parts
    fines = [mesh_block(lib, clips, mesh.grid, b) for b in blocks]
    for bi, f in enumerate(fines):
        if not _shared_flags_agree(parts, f):
            raise Inconsistent(bi, "the fine grid's signs differ from the grid's at their common vertices")
    verts, tris, split = coarse_faces(lib, clips, mesh, blocks)
    cell = np.full(len(verts), -1, dtype=np.int64)
    cell[: parts.cells.nverts] = np.repeat(parts.cells.flat, parts.cells.count)
    vs, ts, cs = [verts], [tris], [cell]
    off = len(verts)
    for bi, f in enumerate(fines):
        lib.check()  # the budget, between blocks (budget.py)
        fverts, ftris, fsplit = block_faces(lib, clips, parts, f, bi, off)
        vs.append(fverts)
        ts.append(ftris)
        cs.append(np.full(len(fverts), -1, dtype=np.int64))
        off += len(fverts)
        split += fsplit
    return _Built(np.concatenate(vs), np.concatenate(ts), np.concatenate(cs), fines, split, len(tris))


def _fine_missed(lib, clips, fine: Fine) -> Missed:
    """The fine grid's own missed detail, away from the block's faces (where its blocks of corners are cut)."""
    found = missed_detail(lib, clips, fine.grid, fine.inside, fine.cross)
    lo = fine.grid.origin + 2 * fine.grid.h
    hi = fine.grid.origin + fine.grid.h * (np.array(fine.grid.n) - 2)
    return found.keep(((found.middle >= lo) & (found.middle <= hi)).all(axis=1))


def sites(lib, clips, mesh: Mesh, avoid: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict]:
    """Where to refine and how finely: (points, the fine cell size wanted there, counts by kind). The critical
    points of f whose feature is less than half a cell across (critical.py), and the middles of the intervals
    missed.py flags (fine cells of half their width); none within two cells of a singular point (`avoid`)."""
    grid = mesh.grid
    crit = critical_points(lib, clips, grid, mesh.parts.g)
    thin = crit.size < 0.5 * grid.h
    miss = mesh.missed if mesh.missed is not None else Missed(*(np.zeros((0, 3)) for _ in range(4)))
    points = np.concatenate([crit.points[thin], miss.middle.reshape(-1, 3)])
    width = np.concatenate([SIDE * np.sqrt(2) * crit.size[thin], SIDE * miss.width / np.sqrt(2)])
    kind = np.concatenate([np.zeros(int(thin.sum()), dtype=np.int64), np.ones(miss.count, dtype=np.int64)])
    if len(avoid) and len(points):
        far = (np.abs(points[:, None, :] - avoid[None, :, :]).max(axis=2) > 2 * grid.h).all(axis=1)
        points, width, kind = points[far], width[far], kind[far]
    counts = {"critical_points": int(thin.sum()), "thin_features": int((kind == 0).sum()),
              "missed_intervals": int((kind == 1).sum())}  # fmt: skip
    return points, width, counts


def refine(lib: ShapeLib, clips: list[Clip], mesh: Mesh, avoid: np.ndarray) -> None:
    """Refine the mesh in place where detail hides (see the module's docstring); mesh.stats["refined"] says
    where, mesh.stats["refine_skipped"] why not."""
    points, width, counts = sites(lib, clips, mesh, avoid)
    mesh.stats.update({"refine_sites": counts, "refined": [], "refined_cells": 0, "refine_skipped": None})
    if len(points):
        n = np.array(mesh.grid.n)
        built, why = _attempts(lib, clips, mesh, blocks_for(mesh.grid, points, ratio_for(mesh.grid.h, width)), n)
        if built is not None:
            _apply(lib, clips, mesh, built)
        mesh.stats["refine_skipped"] = why
    mesh.parts = None


def _attempts(lib, clips, mesh: Mesh, blocks: list[Block], n: np.ndarray) -> tuple[_Built | None, str | None]:
    """Build, growing a block whose faces disagree (every block, when the stitched mesh fails its check), once
    finer where the fine grid still misses detail: GROW + 2 tries in all."""
    finer_tried, last = False, ""
    for _ in range(GROW + 2):
        total = sum(b.fine_cells for b in blocks)
        if total > MAX_FINE:
            return None, f"the blocks would need {total} fine cells, more than {MAX_FINE}"
        try:
            built = build(lib, clips, mesh, blocks)
        except Inconsistent as e:
            blocks[e.block] = grow(blocks[e.block], n)
            blocks = merge(blocks, n)
            last = str(e)
            continue
        closed, _ = closed_and_euler(built.faces, len(built.verts))
        if not (closed and one_fan_each(built.faces, np.unique(built.faces[built.ncoarse :]))):
            blocks = merge([grow(b, n) for b in blocks], n)  # the faces of larger blocks may lie where all is plain
            last = "the stitched mesh failed its check (closed, one fan at every vertex)"
            continue
        missed = [_fine_missed(lib, clips, f).count for f in built.fines]
        coarser = [i for i, m in enumerate(missed) if m and blocks[i].r < RMAX]
        if coarser and not finer_tried:
            finer_tried = True
            for i in coarser:
                blocks[i] = Block(blocks[i].lo, blocks[i].hi, min(4 * blocks[i].r, RMAX))
            continue
        return built, None
    return None, f"no consistent stitching in {GROW + 2} tries (the last: {last})"


def _apply(lib, clips, mesh: Mesh, built: _Built) -> None:
    """The refined mesh into `mesh`: its unused vertices (the grid's in the blocks) dropped, the missed detail
    outside the blocks kept and the fine grids' own added, where each block is in the stats."""
    used = np.unique(built.faces)
    remap = np.full(len(built.verts), -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    mesh.vertices, mesh.faces, mesh.cell = built.verts[used], remap[built.faces], built.cell[used]
    grid = mesh.grid
    refined, fine_missed = [], []
    inside_any = np.zeros(0 if mesh.missed is None else mesh.missed.count, dtype=bool)
    for f in built.fines:
        b = f.block
        lo, hi = grid.origin + grid.h * b.lo, grid.origin + grid.h * b.hi
        if mesh.missed is not None:
            inside_any |= ((mesh.missed.middle >= lo) & (mesh.missed.middle <= hi)).all(axis=1)
        fine_missed.append(_fine_missed(lib, clips, f))
        refined.append({"from": [float(v) for v in lo], "to": [float(v) for v in hi], "ratio": b.r,
                        "cells": [int(v) for v in b.hi - b.lo], "fine_cells": b.fine_cells})  # fmt: skip
    if mesh.missed is not None:
        kept = [mesh.missed.keep(~inside_any)] + fine_missed
        fields = ("axis", "edge", "middle", "width")
        mesh.missed = Missed(*(np.concatenate([getattr(m, k) for m in kept]) for k in fields))
        mesh.stats.update(mesh.missed.stats())
    mesh.stats["refined"] = refined
    mesh.stats["refined_cells"] = sum(r["fine_cells"] for r in refined)
    mesh.stats["split_sides"] = mesh.stats.get("split_sides", 0) + built.split
