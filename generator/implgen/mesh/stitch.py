"""How a refined block (refine.py) meets the grid's cells around it.

Stitching (the octree dual contouring of Ju et al. 2002, on two levels): each active edge gives one polygon
joining the vertices of the cells around it, the smallest cells that hold it. A fine edge inside a block: four
fine cells, a quad. A fine edge on a block's face: the fine cells inside and, outside, the grid cells there --
one cell where the edge lies inside a face of that cell (a triangle), two or three where it lies on the cell's
edge (a quad); the grid's edges on or inside a block give no quad of their own. An outside cell's vertex for
a fine crossing is its sheet that holds the crossing: on the cell's edge, that edge's sheet; inside its face,
the sheet of the cell's edges where the fine curve through the crossing (the fine squares of that face joined
as cells.py joins a cell's edges, an ambiguous square by f at its centre) ends. That is consistent only when
the block's faces show what the grid there shows: each grid edge on them holds at most one fine crossing (one
where it is active), and every fine curve inside a grid face ends, at both ends, on edges of one sheet of the
outside cell. Where not, the block grows by a cell on every side and is meshed again (refine.GROW).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from implgen.mesh import cells
from implgen.mesh.contour import AROUND, Mesh, Parts
from implgen.mesh.crossings import Crossings, inside_flags
from implgen.mesh.faces import Quads, triangulate
from implgen.mesh.region import Grid


class Inconsistent(Exception):
    """A block's faces show the surface otherwise than the grid there (it is grown)."""

    def __init__(self, block: int, why: str):
        super().__init__(why)
        self.block = block


@dataclass(frozen=True)
class SubGrid(Grid):
    """The fine grid of a block: vertex i at base + h (offset + i), so that the vertices it shares with the grid
    (h a power-of-2 fraction of the grid's, offset a multiple of the ratio) are the grid's own doubles."""

    base: np.ndarray = field(default_factory=lambda: np.zeros(3))
    offset: np.ndarray = field(default_factory=lambda: np.zeros(3, dtype=np.int64))
    whole: float = 1.0  # the region's size: the tolerances stay the grid's

    def coords(self, axis: int) -> np.ndarray:
        return self.base[axis] + self.h * (self.offset[axis] + np.arange(self.n[axis] + 1)).astype(np.float64)

    def point(self, flat: np.ndarray) -> np.ndarray:
        idx = np.stack(np.unravel_index(flat, self.shape), axis=1)
        return self.base + self.h * (self.offset + idx).astype(np.float64)

    @property
    def size(self) -> float:
        return self.whole


@dataclass
class Block:
    lo: np.ndarray  # (3,) first grid cell
    hi: np.ndarray  # (3,) past the last
    r: int

    @property
    def fine_cells(self) -> int:
        return int(np.prod(self.hi - self.lo)) * self.r**3


@dataclass
class Fine:
    """One block meshed on its fine grid."""

    block: Block
    grid: SubGrid
    inside: np.ndarray
    cross: list[Crossings]
    cells: object  # contour._Cells
    strides: np.ndarray
    verts: np.ndarray
    rowof: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))


def _coarse_sheet(parts: Parts, ccell: np.ndarray, a: int, gb: int, gc: int, r: int, bi: int) -> int:
    """The vertex of the grid cell `ccell` (index) for a fine crossing on its edge along a, the fine edge's
    global fine coordinates gb, gc along a + 1, a + 2 (multiples of r)."""
    b, c = (a + 1) % 3, (a + 2) % 3
    row = _row(parts, ccell, bi)
    ub, uc = gb // r - int(ccell[b]), gc // r - int(ccell[c])
    lo_ax, _ = cells.other_axes(a)
    u, v = (ub, uc) if lo_ax == b else (uc, ub)
    sheet = int(parts.cells.sheets[row, 4 * a + u + 2 * v])
    if sheet < 0:
        raise Inconsistent(bi, "a fine crossing on a grid edge without one")
    return int(parts.cells.base[row]) + sheet


def _row(parts: Parts, ccell: np.ndarray, bi: int) -> int:
    row = int(parts.rowof[int(np.dot(ccell, parts.strides))])
    if row < 0:
        raise Inconsistent(bi, "a fine crossing next to a grid cell without sheets")
    return row


# a fine square's corners in turn, (along q, along s), and its edges: edge k from corner k to corner k + 1
_SQUARE = ((0, 0), (1, 0), (1, 1), (0, 1))


class _Union:
    def __init__(self):
        self.parent: dict = {}

    def find(self, x):
        self.parent.setdefault(x, x)
        while self.parent[x] != x:
            self.parent[x] = self.parent[self.parent[x]]
            x = self.parent[x]
        return x

    def join(self, x, y):
        self.parent[self.find(x)] = self.find(y)


def _square_edges(fine: Fine, p: int, at: int, sq: tuple[int, int], q: int, s: int) -> list:
    """The fine edges of one square of the plane p = at (local), lower corner sq along (q, s): per edge k its
    key (axis, global fine lower vertex) and whether it is active; and the corners' flags."""
    flags, keys = [], []
    for dq, ds in _SQUARE:
        idx = [0, 0, 0]
        idx[p], idx[q], idx[s] = at, sq[0] + dq, sq[1] + ds
        flags.append(bool(fine.inside[tuple(idx)]))
    for k in range(4):
        (q0, s0), (q1, s1) = _SQUARE[k], _SQUARE[(k + 1) % 4]
        idx = [0, 0, 0]
        idx[p], idx[q], idx[s] = at, sq[0] + min(q0, q1), sq[1] + min(s0, s1)
        axis = q if q0 != q1 else s
        keys.append((axis, *(int(v) for v in fine.grid.offset + np.array(idx))))
    return [flags, keys]


def _join_square(fine: Fine, lib, clips, uf: _Union, face, p, at, sq, q, s) -> None:
    """Join the active edges of one fine square as cells.py joins a cell's edges on a face."""
    flags, keys = _square_edges(fine, p, at, sq, q, s)
    active = [k for k in range(4) if flags[k] != flags[(k + 1) % 4]]
    if len(active) == 2:
        uf.join((face, keys[active[0]]), (face, keys[active[1]]))
    elif len(active) == 4:
        idx = np.zeros(3)
        idx[p], idx[q], idx[s] = at, sq[0] + 0.5, sq[1] + 0.5
        centre_in = bool(inside_flags(lib, clips, (fine.grid.origin + fine.grid.h * idx)[None])[0][0])
        for k in range(4):  # corner k lies between edges k - 1 and k
            if flags[k] != centre_in:
                uf.join((face, keys[(k - 1) % 4]), (face, keys[k]))
    else:
        for k in active:
            uf.find((face, keys[k]))


def _plane_squares(fine: Fine, p: int, at: int, q: int, s: int) -> list[tuple[int, int]]:
    """The squares of the plane p = at whose corners differ."""
    sl = [slice(None)] * 3
    sl[p] = at
    flags = fine.inside[tuple(sl)]
    if q > s:
        flags = flags.T
    f = flags.astype(np.uint8)
    conf = f[:-1, :-1] | f[1:, :-1] << 1 | f[1:, 1:] << 2 | f[:-1, 1:] << 3
    i, j = np.nonzero((conf != 0) & (conf != 15))
    return list(zip(i.tolist(), j.tolist()))


def face_sheets(lib, clips, parts: Parts, fine: Fine, bi: int) -> dict:
    """For each active fine edge inside a grid face on the block's faces: the vertex of the outside cell's sheet
    it belongs to, by the fine curve through it (see the module's docstring). Inconsistent when a curve closes
    inside the face or ends on two sheets."""
    blk, r = fine.block, fine.block.r
    uf = _Union()
    for p in range(3):
        q, s = cells.other_axes(p)
        for side, at in ((0, 0), (1, fine.grid.n[p])):
            for sq in _plane_squares(fine, p, at, q, s):
                cq, cs_ = (int(fine.grid.offset[q]) + sq[0]) // r, (int(fine.grid.offset[s]) + sq[1]) // r
                face = (p, side, cq, cs_)
                _join_square(fine, lib, clips, uf, face, p, at, sq, q, s)
    groups: dict = {}
    for node in list(uf.parent):
        groups.setdefault(uf.find(node), []).append(node)
    out = {}
    for nodes in groups.values():
        (p, side, cq, cs_), _ = nodes[0]
        q, s = cells.other_axes(p)
        ccell = np.zeros(3, dtype=np.int64)
        ccell[p], ccell[q], ccell[s] = (blk.lo[p] - 1 if side == 0 else blk.hi[p]), cq, cs_
        ends = set()
        for _, (axis, *g) in nodes:
            across = q if axis == s else s
            if g[across] % r == 0:
                ends.add(_coarse_sheet(parts, ccell, axis, g[(axis + 1) % 3], g[(axis + 2) % 3], r, bi))
        if len(ends) != 1:
            raise Inconsistent(bi, "a fine curve on a block's face that the grid's cell there does not hold")
        vid = ends.pop()
        for _, key in nodes:
            out[key] = vid
    return out


def _positions(fine: Fine, a: int, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For the active fine edges along a (local lower vertices idx): the vertex of each fine cell around it, in
    contour.AROUND's order, and which of the four cells are inside the block."""
    b, c = (a + 1) % 3, (a + 2) % 3
    lo_ax, _ = cells.other_axes(a)
    nf = np.array(fine.grid.n)
    ids = np.full((len(idx), 4), -1, dtype=np.int64)
    inb = np.zeros((len(idx), 4), dtype=bool)
    for k, (db, dc) in enumerate(AROUND):
        cell = idx.copy()
        cell[:, b] -= db
        cell[:, c] -= dc
        ok = ((cell >= 0) & (cell < nf)).all(axis=1)
        row = fine.rowof[cell[ok] @ fine.strides]
        u, v = (db, dc) if lo_ax == b else (dc, db)
        ids[ok, k] = fine.cells.base[row] + fine.cells.sheets[row, 4 * a + u + 2 * v]
        inb[:, k] = ok
    return ids, inb


def _outside_vertex(parts, fine, sheets: dict, a, gidx, cell_local, bi, on_edges: dict) -> int:
    """The grid cell's vertex for one position around a fine edge on the block's face (global lower vertex gidx)."""
    r = fine.block.r
    ccell = (fine.grid.offset + cell_local) // r
    b, c = (a + 1) % 3, (a + 2) % 3
    key = (a, *(int(v) for v in gidx))
    if gidx[b] % r == 0 and gidx[c] % r == 0:  # on a grid edge: one fine crossing on it at most
        ekey = (a, int(gidx[a]) // r, int(gidx[b]) // r, int(gidx[c]) // r)
        if on_edges.setdefault(ekey, key) != key:
            raise Inconsistent(bi, "a grid edge on a block's face with more than one fine crossing")
        return _coarse_sheet(parts, ccell, a, int(gidx[b]), int(gidx[c]), r, bi)
    if key not in sheets:
        raise Inconsistent(bi, "a fine crossing on a block's face on no fine curve")
    return sheets[key]


def _polygon(ids: list[int], flip: bool) -> list[list[int]]:
    """Triangles of one polygon (3 or 4 distinct vertices, in turn about +axis), facing f > 0."""
    ring = [v for k, v in enumerate(ids) if v != ids[k - 1]] if len(set(ids)) > 1 else ids[:1]
    if len(ring) < 3:
        raise ValueError("a polygon of fewer than 3 vertices")
    tris = [[ring[0], ring[k], ring[k + 1]] for k in range(1, len(ring) - 1)]
    return [t[::-1] for t in tris] if flip else tris


def block_faces(lib, clips, parts: Parts, fine: Fine, bi: int, foff: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The block's triangles (global vertex ids: the grid's sheets first, the block's from foff): its inner
    quads through faces.triangulate, the polygons on its faces stitched to the grid's cells. Also the block's
    vertices with those triangulate() added, and how many quad sides it split."""
    sheets = face_sheets(lib, clips, parts, fine, bi)
    inner, stitched, on_edges = [], [], {}
    for a in range(3):
        edges = fine.cross[a].edges
        idx = np.stack(np.unravel_index(edges, fine.inside.shape), axis=1)
        ids, inb = _positions(fine, a, idx)
        flip = ~fine.inside.reshape(-1)[edges]
        whole = inb.all(axis=1)
        cr = fine.cross[a]
        inner.append((ids[whole], np.full(int(whole.sum()), a), edges[whole], flip[whole], cr.points[whole],
                      cr.piece[whole]))  # fmt: skip
        b, c = (a + 1) % 3, (a + 2) % 3
        for e in np.flatnonzero(~whole).tolist():
            gidx = fine.grid.offset + idx[e]
            ring = []
            for k, (db, dc) in enumerate(AROUND):
                if inb[e, k]:
                    ring.append(foff + int(ids[e, k]))
                    continue
                cell = idx[e].copy()
                cell[b] -= db
                cell[c] -= dc
                ring.append(_outside_vertex(parts, fine, sheets, a, gidx, cell, bi, on_edges))
            stitched.extend(_polygon(ring, bool(flip[e])))
    quads = Quads(*(np.concatenate([p[i] for p in inner]) for i in range(6)))
    near_amb = np.repeat(cells.AMBIGUOUS[fine.cells.conf] != 0, fine.cells.count)
    verts, tris, split = triangulate(quads, fine.verts, near_amb, fine.inside, fine.grid, lib, clips, AROUND,
                                     fine.rowof, fine.cells.key)  # fmt: skip
    tris = np.concatenate([tris + foff, np.array(stitched, dtype=np.int64).reshape(-1, 3)])
    return verts, tris, split


def coarse_faces(lib, clips, mesh: Mesh, blocks: list[Block]) -> tuple[np.ndarray, np.ndarray, int]:
    """The grid's quads of edges with no cell in a block, triangulated: (vertices, triangles, sides split)."""
    parts, grid = mesh.parts, mesh.grid
    in_block = np.zeros(grid.shape, dtype=bool)  # by each cell's lower corner
    for blk in blocks:
        in_block[tuple(slice(int(lo), int(hi)) for lo, hi in zip(blk.lo, blk.hi))] = True
    flat_in = in_block.reshape(-1)
    q = parts.quads
    drop = np.zeros(len(q.edge), dtype=bool)
    for db, dc in AROUND:
        b, c = (q.axis + 1) % 3, (q.axis + 2) % 3
        drop |= flat_in[q.edge - db * parts.strides[b] - dc * parts.strides[c]]
    keep = Quads(*(getattr(q, k)[~drop] for k in ("verts", "axis", "edge", "flip", "point", "piece")))
    cs = parts.cells
    near_amb = np.repeat(cells.AMBIGUOUS[cs.conf] != 0, cs.count)
    return triangulate(keep, parts.sheet_verts, near_amb, parts.inside, grid, lib, clips, AROUND, parts.rowof, cs.key)
