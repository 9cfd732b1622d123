"""Sheets that touch at a point: distinct mesh vertices at the same place (or within a float's rounding of it).

The mesh is a 2-manifold by its connectivity, but a file holds positions: a reader that merges vertices at equal
positions (trimesh, Blender, a slicer; every STL reader, whose format has no shared vertices) glues two sheets
at a point, and the mesh it reads is pinched there. It happens where two sheets of one cell are put on the same
point: the cones of a node, both snapped onto it (pipeline.snap_to_singular), or two sheets projected onto one
point of the surface near it.

So, after the mesh is made: vertices closer than TOUCH x the region's size (any reader's float32 rounding of
coordinates up to 8 times the region's size, far beyond trimesh's merging tolerance) are one touching group.
  - A closed piece of the mesh of at most ISLAND_FACES triangles that holds such a vertex and less than
    ISLAND_VOLUME of a cell -- the surface around one grid vertex, squashed onto a node's cone -- is dropped.
  - Every other vertex of a group is moved SPLIT x the region's size from the group's point along one of its own
    edges (the one nearest the middle of its edges: along its own sheet; at a node, along a line of the cone
    into its own nappe, on the cone to second order), then by Newton onto f = 0 where it is a vertex of f alone
    and that keeps it about that far from the point and from the others.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from implgen.mesh.dual import NOISE
from implgen.mesh.region import Clip
from implgen.mesh.shapelib import ShapeLib

TOUCH = 1e-6  # of the region's size: vertices closer than this touch
SPLIT = 1e-5  # of the region's size: how far from their common point touching vertices are put
ISLAND_FACES = 64  # a closed piece with at most this many triangles ...
ISLAND_VOLUME = 0.05  # ... and less than this many cells of volume is a squashed island


@dataclass
class Unpinched:
    """What was done: the touching groups' points, how many vertices were moved and islands dropped at each."""

    points: list[np.ndarray] = field(default_factory=list)
    moved: list[int] = field(default_factory=list)
    dropped: list[int] = field(default_factory=list)  # triangles dropped at each group
    off_surface: int = 0  # moved vertices left off f = 0 (a cap's, a rim's, or Newton's step not kept)
    left: int = 0  # touching groups still there afterwards (none expected)


# a direction no plane of the grid or of a box clip is normal to: points on such a plane differ along it
SLANT = np.array([1.0, 0.7548776662466927, 0.5698402909980532])


def touching_groups(verts: np.ndarray, tol: float) -> list[np.ndarray]:
    """Groups of vertex ids, each of at least two, joined by pairs within `tol` of each other along every axis.
    One sort along SLANT; a pair that close is at most |SLANT|_1 tol apart along it, so only neighbours in that
    order that close are compared, k places apart for k = 1, 2, ... while any are."""
    s = verts @ SLANT
    order = np.argsort(s, kind="stable")
    s, p = s[order], verts[order]
    reach = tol * float(SLANT.sum())
    parent: dict[int, int] = {}

    def find(a: int) -> int:
        while parent.setdefault(a, a) != a:
            a = parent[a]
        return a

    for k in range(1, len(p)):
        close = np.flatnonzero(s[k:] - s[:-k] <= reach)
        if close.size == 0:
            break
        near = close[np.abs(p[close + k] - p[close]).max(axis=1) <= tol]
        for a, b in zip(order[near].tolist(), order[near + k].tolist()):
            parent[find(a)] = find(b)
    groups: dict[int, list[int]] = {}
    for a in parent:
        groups.setdefault(find(a), []).append(a)
    return [np.array(sorted(g)) for g in groups.values() if len(g) > 1]


class _Faces:
    """Each vertex's faces, by one sort of the face corners."""

    def __init__(self, faces: np.ndarray):
        flat = faces.reshape(-1)
        self.order = np.argsort(flat, kind="stable")
        self.sorted = flat[self.order]
        self.faces = faces

    def of(self, v: int) -> np.ndarray:
        lo, hi = np.searchsorted(self.sorted, [v, v + 1])
        return self.order[lo:hi] // 3

    def along_edge(self, verts: np.ndarray, v: int, p: np.ndarray) -> np.ndarray:
        """The unit direction from p along the edge of v nearest the middle of v's edges: along v's sheet (at a
        node, along a line of the cone, which lies on a quadric cone all the way to its apex)."""
        ring = np.unique(self.faces[self.of(v)])
        way = verts[ring[ring != v]] - p
        way /= np.maximum(np.linalg.norm(way, axis=1, keepdims=True), 1e-300)
        return way[np.argmax(way @ way.mean(axis=0))]

    def small_piece(self, v: int, cap: int) -> np.ndarray | None:
        """The faces of v's connected piece when it has at most `cap` of them, else None."""
        seen_v, seen_f, todo = {v}, set(), [v]
        while todo:
            for f in self.of(todo.pop()).tolist():
                if f in seen_f:
                    continue
                seen_f.add(f)
                if len(seen_f) > cap:
                    return None
                for w in self.faces[f].tolist():
                    if w not in seen_v:
                        seen_v.add(w)
                        todo.append(w)
        return np.array(sorted(seen_f))


def _volume(verts: np.ndarray, faces: np.ndarray) -> float:
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def _drop_islands(verts, faces, groups, h: float, done: Unpinched) -> np.ndarray:
    """Faces kept: the squashed islands at the groups gone (each group's dropped triangles in `done`)."""
    index = _Faces(faces)
    drop = np.zeros(len(faces), dtype=bool)
    for g in groups:
        gone = 0
        for v in g.tolist():
            piece = index.small_piece(v, ISLAND_FACES)
            if piece is None or drop[piece].any():
                continue
            if abs(_volume(verts, faces[piece])) < ISLAND_VOLUME * h**3:
                drop[piece] = True
                gone += len(piece)
        done.points.append(verts[g].mean(axis=0))
        done.dropped.append(gone)
    return ~drop


def _on_f_alone(clips: list[Clip], p: np.ndarray, margin: float) -> np.ndarray:
    """Whether each point is farther than `margin` inside every clip (to first order): a vertex of f alone."""
    ok = np.ones(len(p), dtype=bool)
    for c in clips:
        ok &= c.value(p) / np.maximum(np.linalg.norm(c.gradient(p), axis=-1), 1e-300) < -margin
    return ok


def _split(lib: ShapeLib, clips: list[Clip], verts: np.ndarray, index: _Faces, g: np.ndarray, step: float):
    """The group's vertices moved `step` from their common point along an edge of their own, then onto f = 0
    where they are vertices of f alone and stay that far apart (in place): how many left off f = 0."""
    p = verts[g].mean(axis=0)
    plain = p + step * np.array([index.along_edge(verts, v, p) for v in g.tolist()])
    on_f = _on_f_alone(clips, verts[g], 2 * step)
    moved = plain.copy()
    if on_f.any():
        size = step / SPLIT
        q, ok = lib.project(plain[on_f], 40, 1e-13 * size, NOISE * size, 2 * step)
        moved[np.flatnonzero(on_f)[ok]] = q[ok]
    gap = np.linalg.norm(moved[:, None, :] - moved[None, :, :], axis=2) + np.eye(len(g)) * step
    far = np.linalg.norm(moved - p, axis=1)
    bad = (gap.min(axis=1) < 0.5 * step) | (far < 0.5 * step) | (far > 2 * step)
    verts[g] = np.where(bad[:, None], plain, moved)
    return int((bad | ~on_f).sum())


def unpinch(lib: ShapeLib, clips: list[Clip], verts: np.ndarray, faces: np.ndarray, size: float, h: float):
    """(vertices, faces, which old vertices are kept, what was done): no two vertices within TOUCH x size of
    each other (see the module's docstring). Nothing changes, and nothing is copied, when none touch."""
    groups = touching_groups(verts, TOUCH * size)
    done = Unpinched()
    if not groups:
        return verts, faces, None, done
    verts = verts.copy()
    keep_faces = _drop_islands(verts, faces, groups, h, done)
    faces = faces[keep_faces]
    used = np.zeros(len(verts), dtype=bool)
    used[faces.reshape(-1)] = True
    index = _Faces(faces)
    for g in groups:
        g = g[used[g]]
        done.moved.append(len(g) if len(g) > 1 else 0)
        done.off_surface += _split(lib, clips, verts, index, g, SPLIT * size) if len(g) > 1 else 0
    new_id = np.cumsum(used) - 1
    verts = verts[used]
    done.left = len(touching_groups(verts, TOUCH * size))
    return verts, new_id[faces], used, done
