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
    dup = np.zeros((len(q), 4), dtype=bool)
    cand = np.nonzero(near_amb[q].any(axis=1))[0]
    if cand.size == 0:
        return verts, lib.split_quads(q, quads.flip, verts), 0
    qc = q[cand]
    sides = np.sort(np.stack([qc, np.roll(qc, -1, axis=1)], axis=2), axis=2)  # (cand, 4, 2): side k's two ends
    key = sides[:, :, 0] * len(verts) + sides[:, :, 1]
    _, inv, cnt = np.unique(key.reshape(-1), return_inverse=True, return_counts=True)
    dup[cand] = (cnt[inv.reshape(-1)] > 2).reshape(-1, 4)
    hit = dup.any(axis=1)
    if not hit.any():
        return verts, lib.split_quads(q, quads.flip, verts), 0
    shape = inside.shape
    qi, ks = np.nonzero(dup)
    a = quads.axis[qi]
    normal = (a + np.array(SIDE_NORMAL)[ks]) % 3
    # the face between the two cells of this side is ambiguous: whether its centre is inside is bit 8 + f of
    # the key of the cell AROUND[k] (contour._face_bits), f its face there: across `normal`, on the edge's side
    around = np.array(around)
    off_b, off_c = around[ks, 0], around[ks, 1]
    b_axis, c_axis = (a + 1) % 3, (a + 2) % 3
    strides = np.array([shape[1] * shape[2], shape[2], 1])
    cell = quads.edge[qi] - off_b * strides[b_axis] - off_c * strides[c_axis]
    face = 2 * normal + np.where(normal == b_axis, off_b, off_c)
    c_in = ((cell_key[rowof[cell]] >> (8 + face)) & 1).astype(bool)
    # the corner the side's curve cuts off: the edge's end whose flag differs from the centre's
    lo_in = inside.reshape(-1)[quads.edge[qi]]
    corner = np.where(lo_in != c_in, quads.edge[qi], quads.edge[qi] + strides[a])
    side = sides[np.searchsorted(cand, qi), ks]
    key = np.stack([side[:, 0], side[:, 1], corner, normal], axis=1)
    ukey, mid_of = np.unique(key, axis=0, return_inverse=True)
    mid_of = mid_of.reshape(-1)
    nmid = len(ukey)
    mids = np.zeros((nmid, 3))
    np.add.at(mids, mid_of, quads.point[qi])
    mids /= np.bincount(mid_of, minlength=nmid)[:, None]
    mask = piece_mask(mid_of, quads.piece[qi], nmid)
    mids, _ = project(lib, clips, mids, mask, grid.h, grid.size)
    mid_id = np.full((len(q), 4), -1, dtype=np.int64)
    mid_id[qi, ks] = len(verts) + mid_of
    fan = np.nonzero(hit)[0]
    centre_id = len(verts) + nmid + np.arange(fan.size)
    tris = []
    for j, qn in enumerate(fan):  # few: only quads next to a split side
        poly = []
        for k in range(4):
            poly.append(q[qn, k])
            if mid_id[qn, k] >= 0:
                poly.append(mid_id[qn, k])
        for i in range(len(poly)):
            t = [poly[i], poly[(i + 1) % len(poly)], centre_id[j]]
            tris.append(t[::-1] if quads.flip[qn] else t)
    out_verts = np.concatenate([verts, mids, quads.point[fan]])
    keep = ~hit
    faces = np.concatenate([lib.split_quads(q[keep], quads.flip[keep], verts), np.array(tris, dtype=np.int64)])
    return out_verts, faces, nmid
