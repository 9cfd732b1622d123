"""Quads → triangles. Each active grid edge gives one quad, the sheets of its four cells in turn around it; two
triangles on the shorter diagonal, facing f > 0.

One case needs more: two cells that share an ambiguous face and whose two curves on that face both join the
same pair of sheets (a thin tube through the face). The quad complex is still a manifold, but the two quad
sides between those sheets join the same two vertices, so a triangle mesh would hold that edge four times. Each
such side gets a vertex of its own, on the surface between the two crossings its curve joins, keyed by the face
and the corner its curve cuts off; the quads around it are fanned from their own crossing point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from implgen.mesh.dual import piece_mask, project
from implgen.mesh.region import Clip, Grid
from implgen.mesh.shapelib import ShapeLib


@dataclass
class Quads:
    """Quads of all three axes: sheet vertices (M, 4) counter-clockwise about +axis, the axis, the edge's
    lower grid vertex (flat), whether the outside is toward -axis, and the edge's crossing (point, piece)."""

    verts: np.ndarray
    axis: np.ndarray
    edge: np.ndarray
    flip: np.ndarray
    point: np.ndarray
    piece: np.ndarray


# the cells around an edge (contour.AROUND) differ, between turn k and k + 1, along the axis a + 1 + (k % 2);
# the cell pair shares its offset along the remaining axis: AROUND[k]'s offset there
SIDE_NORMAL = (1, 2, 1, 2)


def _doubled_sides(q: np.ndarray, nverts: int, near_amb: np.ndarray):
    """Which quad sides are shared by more than two quads: (dup (quads, 4), the candidate quads -- those next to
    an ambiguous face --, their sides' two ends sorted (cand, 4, 2)); None when no side is."""
    cand = np.nonzero(near_amb[q].any(axis=1))[0]
    if cand.size == 0:
        return None
    qc = q[cand]
    sides = np.sort(np.stack([qc, np.roll(qc, -1, axis=1)], axis=2), axis=2)  # (cand, 4, 2): side k's two ends
    key = sides[:, :, 0] * nverts + sides[:, :, 1]
    _, inv, cnt = np.unique(key.reshape(-1), return_inverse=True, return_counts=True)
    dup = np.zeros((len(q), 4), dtype=bool)
    dup[cand] = (cnt[inv.reshape(-1)] > 2).reshape(-1, 4)
    return (dup, cand, sides) if dup.any() else None


def _cut_corners(quads: Quads, qi, ks, inside: np.ndarray, around, rowof, cell_key) -> tuple[np.ndarray, np.ndarray]:
    """For each doubled side (quad qi, side ks): (the grid corner its curve cuts off, the normal axis of the
    ambiguous face between the side's two cells). Whether that face's centre is inside is bit 8 + f of the key of
    the cell AROUND[k] (contour._face_bits), f its face there: across `normal`, on the edge's side; the corner is
    the edge's end whose flag differs from the centre's."""
    shape = inside.shape
    a = quads.axis[qi]
    normal = (a + np.array(SIDE_NORMAL)[ks]) % 3
    around = np.array(around)
    off_b, off_c = around[ks, 0], around[ks, 1]
    b_axis, c_axis = (a + 1) % 3, (a + 2) % 3
    strides = np.array([shape[1] * shape[2], shape[2], 1])
    cell = quads.edge[qi] - off_b * strides[b_axis] - off_c * strides[c_axis]
    face = 2 * normal + np.where(normal == b_axis, off_b, off_c)
    c_in = ((cell_key[rowof[cell]] >> (8 + face)) & 1).astype(bool)
    lo_in = inside.reshape(-1)[quads.edge[qi]]
    return np.where(lo_in != c_in, quads.edge[qi], quads.edge[qi] + strides[a]), normal


def _fan_triangles(q: np.ndarray, flip: np.ndarray, fan: np.ndarray, mid_id: np.ndarray, centre_id: np.ndarray):
    """Each quad of `fan` as a fan about its centre, through its corners and its sides' midpoints."""
    tris = []
    for j, qn in enumerate(fan):  # few: only quads next to a split side
        poly = []
        for k in range(4):
            poly.append(q[qn, k])
            if mid_id[qn, k] >= 0:
                poly.append(mid_id[qn, k])
        for i in range(len(poly)):
            t = [poly[i], poly[(i + 1) % len(poly)], centre_id[j]]
            tris.append(t[::-1] if flip[qn] else t)
    return np.array(tris, dtype=np.int64)


def triangulate(
    quads: Quads,
    verts: np.ndarray,
    near_amb: np.ndarray,
    inside: np.ndarray,
    grid: Grid,
    lib: ShapeLib,
    clips: list[Clip],
    around,
    rowof: np.ndarray,
    cell_key: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, int]:
    """(vertices with any added, triangles, how many quad sides were split). near_amb: per vertex, whether its
    cell has an ambiguous face (only a quad with all its sides' cells so can hold a doubled side); rowof: the
    row of each cell (by the flat index of its lower corner) in cell_key, the cells' keys (cells.components)."""
    q = quads.verts
    doubled = _doubled_sides(q, len(verts), near_amb)
    if doubled is None:
        return verts, lib.split_quads(q, quads.flip, verts), 0
    dup, cand, sides = doubled
    hit = dup.any(axis=1)
    qi, ks = np.nonzero(dup)
    corner, normal = _cut_corners(quads, qi, ks, inside, around, rowof, cell_key)
    side = sides[np.searchsorted(cand, qi), ks]
    key = np.stack([side[:, 0], side[:, 1], corner, normal], axis=1)
    ukey, mid_of = np.unique(key, axis=0, return_inverse=True)
    mid_of = mid_of.reshape(-1)
    nmid = len(ukey)
    mids = np.zeros((nmid, 3))
    np.add.at(mids, mid_of, quads.point[qi])
    mids /= np.bincount(mid_of, minlength=nmid)[:, None]
    mids, _ = project(lib, clips, mids, piece_mask(mid_of, quads.piece[qi], nmid), grid.h, grid.size)
    mid_id = np.full((len(q), 4), -1, dtype=np.int64)
    mid_id[qi, ks] = len(verts) + mid_of
    fan = np.nonzero(hit)[0]
    fans = _fan_triangles(q, quads.flip, fan, mid_id, len(verts) + nmid + np.arange(fan.size))
    out_verts = np.concatenate([verts, mids, quads.point[fan]])
    keep = ~hit
    return out_verts, np.concatenate([lib.split_quads(q[keep], quads.flip[keep], verts), fans]), nmid
