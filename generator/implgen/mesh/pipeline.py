"""One shape → a mesh and what is known of it: the library, the region, the contour, the singular points, the
mesh's own checks (edges each shared by two faces, Euler characteristic, volume), timings. The cells are checked
before any work; a `deadline` and a `cancel` event are checked between the phases and inside their long loops
(budget.py)."""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from implgen.errors import UserError
from implgen.mesh.budget import MAX_CELLS, Budget, check_cells
from implgen.mesh.contour import Mesh, contour
from implgen.mesh.crossings import clip_values
from implgen.mesh.manifold import closed_and_euler as closed_and_euler  # where the callers find it
from implgen.mesh.probe import cells_to_see, probe_region
from implgen.mesh.refine import refine as refine_mesh
from implgen.mesh.region import Clip, make_grid, region_box
from implgen.mesh.shapelib import ShapeLib
from implgen.mesh.singular import Singular, find_singular
from implgen.mesh.unpinch import SPLIT, Unpinched, unpinch
from implgen.spec.model import Spec


@dataclass
class Result:
    mesh: Mesh
    lib: ShapeLib
    clips: list[Clip]
    singular: Singular | None
    timings: dict[str, float] = field(default_factory=dict)
    at_singular: list[str] = field(default_factory=list)  # what the mesh does at each singular point


def signed_volume(verts: np.ndarray, faces: np.ndarray) -> float:
    a, b, c = verts[faces[:, 0]], verts[faces[:, 1]], verts[faces[:, 2]]
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def mesh_spec(
    spec: Spec,
    values: Mapping[str, float],
    cells: int,
    user_clips: list[Clip],
    singular: bool = True,
    what: str = "",
    deadline: float | None = None,
    cancel: threading.Event | None = None,
    cells_name: str = "--cells",
    seconds: float | None = None,
    refine: bool = True,
) -> Result:
    """Mesh the solid f < 0 (∩ the spec's box, ∩ the user's clip) of `spec` with these param values. Past
    `deadline` (a time.monotonic() value) it raises budget.OverBudget, once `cancel` is set budget.Stopped.
    A mesh with no faces is a UserError: no real points in the region, or (crossings on the grid lines but no
    grid vertex in the solid) too few cells, the option named by `cells_name`. `seconds`, the budget the deadline
    was given, is what OverBudget's message names (by default, how far off the deadline is at the start)."""
    budget = Budget(deadline, cancel, check_cells(cells, cells_name), "building the shape", seconds)
    budget.check()
    t0 = time.perf_counter()
    full = {**spec.params, **values}
    lib = ShapeLib(spec, [full[k] for k in spec.params])
    t1 = time.perf_counter()
    grid, clips = make_grid(spec.box(dict(values)), user_clips, cells, what or spec.source)
    budget.check()
    budget.phase = "meshing"
    lib.budget = budget
    mesh = contour(lib, clips, grid)
    if len(mesh.faces) == 0:
        box = region_box(spec.box(dict(values)), user_clips, what or spec.source)
        raise _empty(lib, clips, box, mesh, what or spec.source, cells_name, cells)
    t2 = time.perf_counter()
    sing = None
    if singular:
        budget.phase = "finding singular points"
        budget.check()
        hi = grid.origin + grid.h * np.array(grid.n)
        sing = find_singular(lib, grid.origin, hi)
        if sing.complete:  # isolated points (a curve's sample would only crumple the mesh along it)
            snap_to_singular(mesh, sing.points, clips)
        if mesh.missed is not None:  # what the grid misses next to a node is the node's own
            mesh.missed = mesh.missed.away_from(sing.points, 2 * grid.h)
            mesh.stats.update(mesh.missed.stats())
    t3 = time.perf_counter()
    if refine:
        budget.phase = "refining"
        budget.check()
        refine_mesh(lib, clips, mesh, result_points(sing))
    mesh.parts = None
    t3r = time.perf_counter()
    budget.phase = "parting touching sheets"
    through = _vertices_on(mesh.vertices, result_points(sing))
    done = _unpinch(mesh, lib, clips)
    lib.budget = None  # the caller's own uses (normals) are not timed
    t4 = time.perf_counter()
    seconds = {"build": t1 - t0, "mesh": t2 - t1, "singular": t3 - t2, "refine": t3r - t3, "unpinch": t4 - t3r}
    return Result(mesh, lib, clips, sing, seconds, at_singular(result_points(sing), through, done, mesh.grid.h))


def result_points(sing: Singular | None) -> np.ndarray:
    """The singular points found, (k, 3); none when the search was skipped."""
    return sing.points if sing is not None else np.zeros((0, 3))


def _vertices_on(verts: np.ndarray, points: np.ndarray) -> np.ndarray:
    """How many vertices sit exactly on each point."""
    if not len(points):
        return np.zeros(0, dtype=np.int64)
    at = {tuple(p): 0 for p in points.tolist()}
    for v in verts[np.isin(verts[:, 0], points[:, 0])].tolist():
        if tuple(v) in at:
            at[tuple(v)] += 1
    return np.array([at[tuple(p)] for p in points.tolist()], dtype=np.int64)


def _unpinch(mesh: Mesh, lib: ShapeLib, clips: list[Clip]) -> Unpinched:
    """Touching sheets apart, squashed islands dropped (unpinch.py); the mesh updated in place, its stats."""
    verts, faces, used, done = unpinch(lib, clips, mesh.vertices, mesh.faces, mesh.grid.size, mesh.grid.h)
    if used is not None:
        mesh.vertices, mesh.faces = verts, faces
        if mesh.cell is not None:
            mesh.cell = mesh.cell[used]
    mesh.stats["touching_points"] = len(done.points)
    mesh.stats["touching_vertices_split"] = int(sum(done.moved))
    mesh.stats["island_triangles_dropped"] = int(sum(done.dropped))
    mesh.stats["split_off_surface"] = done.off_surface
    mesh.stats["touching_left"] = done.left
    mesh.stats["split_distance"] = SPLIT * mesh.grid.size
    return done


def at_singular(points: np.ndarray, through: np.ndarray, done: Unpinched, h: float) -> list[str]:
    """What the mesh does at each singular point, in words: the sheets that touched there split apart, an island
    dropped, or it passes through the point, or no vertex of it is there."""
    said = []
    centres = np.array(done.points).reshape(-1, 3)
    for k, p in enumerate(points):
        idx = np.flatnonzero(np.abs(centres - p).max(axis=1) <= h)  # the groups in the point's cell or next to it
        moved = sum(done.moved[i] for i in idx)
        dropped = sum(done.dropped[i] for i in idx)
        parts = []
        if dropped:
            parts.append(f"an island of {dropped} triangles squashed onto it dropped")
        if moved:
            parts.append(f"{moved} sheets that touched there moved {SPLIT:.0e} of the region apart")
        if not parts:
            parts.append("the mesh passes through it" if through[k] else "no vertex on it (its cell holds none)")
        said.append("; ".join(parts))
    return said


def _empty(lib: ShapeLib, clips: list[Clip], box, mesh: Mesh, where: str, cells_name: str, cells: int) -> UserError:
    """Why a mesh has no faces: no boundary point on the grid's lines nor on probe lines across the region (no
    real points, naming `where`), or a grid too coarse for the region (naming the cells) -- its cell size, the
    solid's thickness along the probes, and the cells that would put grid vertices in it."""
    hidden = mesh.stats["hidden_crossing_edges"]
    lo, hi = box
    found = probe_region(lib, clips, lo, hi, mesh.grid)
    if not hidden and not found.points:
        return UserError(where, "no real points of the surface in the region meshed: nothing to mesh")
    seen = f"{hidden} grid edges hold crossings" if hidden else "no grid line meets the solid"
    text = f"no grid vertex lies in the solid, so the mesh is empty ({seen}): the grid is too coarse for the region"
    text += f" (its cells are {mesh.grid.h:.3g} wide"
    if found.thickness <= 0:
        return UserError(f"{cells_name} {cells}", text + "): raise it")
    need = max(cells_to_see(float((hi - lo).max()), found.thickness), cells + 1)
    text += f"; {found.lines} lines across it find the solid {found.thickness:.3g} thick): about {need:.3g} cells"
    if need <= MAX_CELLS:
        return UserError(f"{cells_name} {cells}", text + f" would put grid vertices in it: raise {cells_name}")
    tail = f" would, more than the {MAX_CELLS} allowed: shrink the spec's bounds or clip the region to the surface"
    return UserError(f"{cells_name} {cells}", text + tail)


def snap_to_singular(mesh: Mesh, points: np.ndarray, clips: list[Clip]) -> None:
    """Put the vertices of the cell that holds a singular point (inside every clip) on it: the mesh then passes
    through each node whose cell holds a vertex, its cones meeting there. How many moved:
    mesh.stats["snapped_to_singular"]."""
    moved = 0
    if len(points) and mesh.cell is not None:
        cv = clip_values(clips, points)
        inside = (cv <= 0).all(axis=0) if len(cv) else np.ones(len(points), dtype=bool)
        g = mesh.grid
        idx = np.floor((points[inside] - g.origin) / g.h).astype(np.int64)
        ok = ((idx >= 0) & (idx < np.array(g.n))).all(axis=1)
        flat = np.ravel_multi_index(tuple(idx[ok].T), g.shape)
        where = {int(f): p for f, p in zip(flat, points[inside][ok])}
        for v in np.nonzero(np.isin(mesh.cell, flat))[0]:
            mesh.vertices[v] = where[int(mesh.cell[v])]
            moved += 1
    mesh.stats["snapped_to_singular"] = moved


def singular_in_solid(result: Result) -> np.ndarray:
    """Which singular points lie in the clipped region (every clip <= 0 there)."""
    if result.singular is None or not len(result.singular.points):
        return np.zeros(0, dtype=bool)
    cv = clip_values(result.clips, result.singular.points)
    return (cv <= 0).all(axis=0) if len(cv) else np.ones(len(result.singular.points), dtype=bool)
