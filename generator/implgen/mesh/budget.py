"""What one mesh may cost, checked before and while it runs: the cells (a cap), the memory (an upper estimate from
the grid, known before any work), the time (a deadline) and a stop from outside (the viewer's page closed).

The time is checked between the pipeline's phases and inside its long loops: every batch entry of the compiled
shape (ShapeLib) runs its C loop in slices -- a batch of grid lines, a slab of the grid, a chunk of points --
and looks at the budget between them, so a mesh stops within one slice of its deadline. A mesh over its budget
raises `OverBudget`, a UserError in one line ("mesh: over its time budget of 2 s at 192 cells ...; try fewer
cells"); a stopped one raises `Stopped`.

The memory estimate bounds the pipeline's peak (NumPy's arrays, traced by tracemalloc; bench/mesh_budget.py
measures it) by two terms:
  - per grid vertex, the values of f and the clips, the sign flags, the cell configurations and the cell rows:
    GRID_BYTES;
  - per active edge, what the edge carries through the phases (its candidates, crossing, normal, the sheets of
    its cells, the QEF, the projection, its two triangles, the STL): EDGE_BYTES. The active edges are not known
    before the crossings are, but along one grid line the solid's boundary is met at most (the degree of f + the
    clips' crossings) times, and each active edge holds one such point: lines x min(cells along the line, that
    count) bounds them.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

from implgen.errors import UserError
from implgen.mesh.region import Clip, Grid, HalfSpace, Sphere, make_grid

MIN_CELLS, MAX_CELLS = 4, 256
# fitted over 18 runs by bench/mesh_budget.py: 12.5 bytes a grid vertex and 592 an active edge; with these, every
# run's peak is at most 0.77 of GRID_BYTES V + EDGE_BYTES E (bench/results/mesh_budget.md)
GRID_BYTES = 24
EDGE_BYTES = 800


class OverBudget(UserError):
    """A mesh stopped by its deadline."""

    def __init__(self, seconds: float, cells: int, phase: str):
        self.seconds, self.cells, self.phase = seconds, cells, phase
        super().__init__("mesh", f"over its time budget of {seconds:.3g} s at {cells} cells ({phase}); try fewer cells")


class Stopped(Exception):
    """A mesh stopped from outside (its `cancel` event set)."""


@dataclass
class Budget:
    """The deadline (time.monotonic(), or None) and the stop of one mesh. `phase` names what runs, for the
    message; `seconds` is the budget the message names: the seconds the deadline was given (by default how far
    off it is when the Budget is made, which a pause before it would shorten)."""

    deadline: float | None = None
    cancel: threading.Event | None = None
    cells: int = 0
    phase: str = "starting"
    seconds: float | None = None

    def __post_init__(self) -> None:
        if self.seconds is None and self.deadline is not None:
            self.seconds = max(0.0, self.deadline - time.monotonic())

    def check(self) -> None:
        """Raise Stopped when cancelled, OverBudget past the deadline."""
        if self.cancel is not None and self.cancel.is_set():
            raise Stopped
        if self.deadline is not None and time.monotonic() > self.deadline:
            raise OverBudget(self.seconds or 0.0, self.cells, self.phase)


def check_cells(cells: int, source: str = "--cells") -> int:
    """The cells along the longest side, within [MIN_CELLS, MAX_CELLS] (a UserError naming `source`)."""
    if isinstance(cells, bool) or not isinstance(cells, int) or not MIN_CELLS <= cells <= MAX_CELLS:
        raise UserError(source, f"expected a whole number of cells in [{MIN_CELLS}, {MAX_CELLS}], not {cells!r}")
    return cells


def _crossings_per_line(clips: list[Clip], degree: int, axis: int) -> int:
    """At most how many boundary points of the solid a line along `axis` meets: f's roots and the clips'."""
    count = degree
    for c in clips:
        if isinstance(c, Sphere):
            count += 2
        elif isinstance(c, HalfSpace) and c.axis == axis:
            count += 1
    return count


def grid_bytes(grid: Grid, clips: list[Clip], degree: int) -> int:
    """The upper estimate of a mesh's peak memory on this grid (see the module's docstring)."""
    n = grid.n
    verts = (n[0] + 1) * (n[1] + 1) * (n[2] + 1)
    edges = 0
    for a in range(3):
        lines = verts // (n[a] + 1)
        edges += lines * min(n[a], _crossings_per_line(clips, degree, a))
    return GRID_BYTES * verts + EDGE_BYTES * edges


def estimate_bytes(box: list[float] | None, degree: int, user_clips: list[Clip], cells: int, what: str) -> int:
    """grid_bytes for the grid `mesh_spec` would make (box: the spec's, at the param values meshed)."""
    grid, clips = make_grid(box, user_clips, check_cells(cells), what)
    return grid_bytes(grid, clips, degree)
