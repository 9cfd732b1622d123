"""Cells → the sheets inside each: one mesh vertex per sheet of the boundary that crosses a cell.

A cell's active edges (ends on opposite sides) are joined across the cell's faces: on a face with two active
edges those two; on an ambiguous face (four active edges, the corners alternating) the solid's true value at the
face centre decides -- inside there, the inside corners are joined across the face and each outside corner is
cut off by one curve (it pairs the two edges next to it), otherwise each inside corner is. Every active edge
then meets exactly two others, so the edges fall into cycles: each cycle is one sheet (a disk) of the boundary
in the cell, and gets one vertex (Manifold Dual Contouring's rule, Schaefer, Ju and Warren 2007). Neighbouring
cells read the same face centre, so they agree on every face: the result is a closed 2-manifold.

Numbering (also used by faces.py): corner c has offsets (c & 1, c >> 1 & 1, c >> 2 & 1); edge 4 a + u + 2 v runs
along axis a from the corner whose offsets along the two other axes (ascending) are (u, v).
"""

from __future__ import annotations

from functools import cache

import numpy as np

# corner c's offsets along the three axes (the numbering above)
CORNER_OFFSETS = np.array([[c & 1, c >> 1 & 1, c >> 2 & 1] for c in range(8)], dtype=np.int64)


def other_axes(a: int) -> tuple[int, int]:
    return tuple(b for b in range(3) if b != a)  # type: ignore[return-value]


def edge_corners(e: int) -> tuple[int, int]:
    a, u, v = e // 4, e % 2, (e // 2) % 2
    b, c = other_axes(a)
    start = (u << b) | (v << c)
    return start, start | (1 << a)


def face_edges(f: int) -> list[int]:
    """The four edges on face f = 2 a + s (the corners with offset s along a)."""
    a, s = f // 2, f % 2
    out = []
    for e in range(12):
        if e // 4 == a:
            continue
        c0, _ = edge_corners(e)
        if (c0 >> a) & 1 == s:
            out.append(e)
    return out


FACE_EDGES = [face_edges(f) for f in range(6)]
FACE_CORNERS = [[c for c in range(8) if (c >> (f // 2)) & 1 == f % 2] for f in range(6)]


def ambiguous_faces(config: int) -> int:
    """Bit f set when face f's corners alternate (two inside, diagonally opposite)."""
    bits = 0
    for f in range(6):
        ins = [c for c in FACE_CORNERS[f] if (config >> c) & 1]
        if len(ins) == 2 and bin(ins[0] ^ ins[1]).count("1") == 2:
            bits |= 1 << f
    return bits


AMBIGUOUS = np.array([ambiguous_faces(c) for c in range(256)], dtype=np.int64)


@cache
def components(key: int) -> tuple[int, ...]:
    """For the cell key = config | face_bits << 8 (config: bit c for an inside corner c; face_bits: bit f when
    the ambiguous face f's centre is inside), the sheet of each of the 12 edges (-1: not active)."""
    config, face_bits = key & 255, key >> 8
    inside = [(config >> c) & 1 for c in range(8)]
    active = [inside[edge_corners(e)[0]] != inside[edge_corners(e)[1]] for e in range(12)]
    parent = list(range(12))

    def find(e: int) -> int:
        while parent[e] != e:
            e = parent[e]
        return e

    def join(e1: int, e2: int) -> None:
        parent[find(e1)] = find(e2)

    for f in range(6):
        on = [e for e in FACE_EDGES[f] if active[e]]
        if len(on) == 2:
            join(on[0], on[1])
        elif len(on) == 4:
            cut_inside = not (face_bits >> f) & 1  # the centre outside: each inside corner is cut off
            for c in FACE_CORNERS[f]:
                if inside[c] == cut_inside:
                    pair = [e for e in on if c in edge_corners(e)]
                    join(pair[0], pair[1])
    out, ids = [], {}
    for e in range(12):
        if not active[e]:
            out.append(-1)
            continue
        r = find(e)
        ids.setdefault(r, len(ids))
        out.append(ids[r])
    return tuple(out)


def cell_table(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For an array of cell keys: (row of each key in the table, table (K, 12) of sheet ids (int8), sheets per
    key)."""
    seen = np.zeros(1 << 14, dtype=bool)  # keys are 8 corner bits and 6 face bits: a table, not a sort
    seen[keys] = True
    uniq = np.flatnonzero(seen)
    row = np.cumsum(seen)[keys] - 1
    table = np.array([components(int(k)) for k in uniq], dtype=np.int8).reshape(-1, 12)
    return row, table, table.max(axis=1) + 1
