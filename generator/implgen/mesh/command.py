"""`implgen mesh SPEC.yaml -o OUT.stl|.obj|.ply|.glb`: a watertight mesh of the solid f < 0 (docs/mesh.md).

Also one shape of a scene, by name (`--object NAME`): its params as the scene gives them, meshed in its own
space and placed by its transform. Every output path is checked before any work; the mesh and the report are
written through a temporary file and renamed.
"""

from __future__ import annotations

import json
import math
import sys
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from implgen import validate
from implgen.args import ArgumentParser
from implgen.errors import UserError, printable
from implgen.mesh.budget import MAX_CELLS, MIN_CELLS
from implgen.mesh.pipeline import Result, closed_and_euler, mesh_spec, signed_volume, singular_in_solid
from implgen.mesh.region import parse_clip
from implgen.mesh.write import FORMATS, place, vertex_normals, write_mesh
from implgen.outputs import atomic_write, check_output_file
from implgen.spec.paramvalues import named_items
from implgen.yamlfile import read_yaml

DEFAULT_CELLS = 64
MAX_TIME_LIMIT = 1e6  # seconds
EXAMPLES = (
    ("a torus as binary STL", "implgen mesh examples/shapes/torus_z.yaml -o torus.stl"),
    (
        "Barth's sextic cut by a ball, with its nodes",
        "implgen mesh examples/shapes/barth6.yaml --clip sphere:1.8 --cells 96 -o barth.glb --report barth.json",
    ),
    ("a thinner torus, as OBJ", "implgen mesh examples/shapes/torus_z.yaml --param r=0.1 -o thin.obj"),
    ("one shape of a scene", "implgen mesh examples/scenes/high_degree.yaml --object chmutov8 -o chmutov.ply"),
)


def _parser() -> ArgumentParser:
    ap = ArgumentParser(
        prog="implgen mesh",
        label="mesh",
        description="A watertight triangle mesh of the solid f < 0 of a shape: every grid line is solved exactly "
        "for its crossings, one vertex per sheet of each cell (dual contouring on the exact points and normals), "
        "normals toward f > 0. An unbounded shape needs --clip; the cut is capped.",
        examples=EXAMPLES,
    )
    ap.add_argument("file", metavar="SPEC.yaml|SCENE.yaml")
    ap.add_argument("-o", "--output", required=True, help="the mesh: .stl (binary), .obj, .ply or .glb")
    cells_help = f"cells along the longest side ({MIN_CELLS}..{MAX_CELLS}, default {DEFAULT_CELLS})"
    ap.add_argument("--cells", default=str(DEFAULT_CELLS), help=cells_help)
    ap.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="a param's value (repeat)")
    ap.add_argument("--clip", help="sphere:R (the ball of radius R about the origin) or box:H (the cube [-H, H]^3)")
    ap.add_argument("--object", help="in a scene: the shape to mesh, by its name")
    ap.add_argument("--report", help="a JSON report: sizes, checks, singular points, timings")
    ap.add_argument("--no-singular", action="store_true", help="skip the search for singular points")
    ap.add_argument(
        "--no-refine", action="store_true", help="mesh the grid alone, with no finer blocks where thin detail hides"
    )
    limit_help = "stop, writing nothing, when meshing takes longer (reading the file not counted; default: none)"
    ap.add_argument("--time-limit", metavar="SECONDS", help=limit_help)
    return ap


def _whole(text: str) -> int | str:
    """A whole number written in decimal digits as an int; anything else as it was (validate.whole refuses it)."""
    t = text.strip()
    return int(t) if t.lstrip("+-").isdigit() and t.isascii() and len(t) <= 4000 else text


def _params(spec, pairs: Sequence[str]) -> dict[str, float]:
    """--param NAME=VALUE items: named as `implgen share` names them (spec.paramvalues.named_items), each a
    number or a constant's name, then checked against the shape."""
    out = {
        k: validate.number("--param", k, v.strip(), text_ok=True)
        for k, v in named_items("--param", pairs, spec.name, spec.params).items()
    }
    spec.check_values(out, spec.source, "--param")  # "torus.yaml: --param: ...", as `implgen share` says it
    return out


def _shape(path: Path, obj: str | None):
    """(spec, param values, 3x4 matrix or None) of the spec file, or of the scene's object `obj`."""
    data = read_yaml(path, "spec or scene")
    if isinstance(data, dict) and "objects" in data:
        from implgen.scene.load import load_scene
        from implgen.scene.model import Leaf

        if obj is None:
            raise UserError(str(path), "is a scene: name the shape to mesh with --object NAME")
        leaves = [o for o in load_scene(path).objects if isinstance(o, Leaf) and o.spec.name == obj]
        if not leaves:
            raise UserError(f"--object {obj}", f"no shape of that name at the top level of {path}")
        leaf = leaves[0]
        return leaf.spec, dict(leaf.params), np.asarray(leaf.matrix, dtype=np.float64)
    if obj is not None:
        raise UserError(f"--object {obj}", f"{path} is a spec, not a scene")
    from implgen.spec.entry import load_spec

    return load_spec(path, cache=True), {}, None


def report(
    result: Result, label: str, values: dict[str, float], cells: int, verts: np.ndarray, faces: np.ndarray
) -> dict:
    closed, euler = closed_and_euler(faces, len(verts))
    sing = result.singular
    pts = sing.points if sing is not None else np.zeros((0, 3))
    inside = singular_in_solid(result)
    return {
        "shape": label,
        "params": values,
        "cells": cells,  # along the region's longest side, as asked
        "cell_size": result.mesh.grid.h,
        "grid_cells": list(result.mesh.grid.n),  # the grid's, with its margin of outside vertices
        "vertices": len(verts),
        "triangles": len(faces),
        "closed": closed,
        "euler_characteristic": euler,
        "volume": signed_volume(verts, faces),
        "singular_points": None if sing is None else [[float(v) for v in p] for p in pts],
        "singular_in_clip": None if sing is None else int(inside.sum()),
        "singular_search_complete": None if sing is None else sing.complete,
        "at_singular_points": None if sing is None else result.at_singular,  # what the mesh does at each
        "stats": result.mesh.stats,
        "missed_resolve_cells": None
        if not result.mesh.stats["missed_detail_edges"]
        else resolve_cells(cells, result.mesh.grid.h, result.mesh.stats["missed_widest"]),
        "seconds": {k: round(v, 4) for k, v in result.timings.items()},
    }


def resolve_cells(cells: int, cell_size: float, width: float) -> int:
    """Cells along the region's longest side (cells x cell_size) whose size is half of `width`."""
    return max(cells + 1, math.ceil(2 * cells * cell_size / width))


def _missed_text(rep: dict) -> str:
    """The warning of the stderr line: only when the exact crossings show detail the grid misses (missed.py)."""
    st = rep["stats"]
    if not st["missed_detail_edges"]:
        return ""
    at = ", ".join(f"{v:.3g}" for v in st["missed_at"])
    need = rep["missed_resolve_cells"]
    what = "raise --cells" if need <= MAX_CELLS else f"more than the {MAX_CELLS} allowed: clip the region to it"
    return (
        f"; the exact crossings show detail the grid misses on {st['missed_detail_edges']} grid edge(s), up to "
        f"{st['missed_widest']:.2g} across, near ({at}): about {need} cells would put grid vertices in it ({what})"
    )


def _refined_text(stats: dict) -> str:
    """Where the grid was refined (refine.py), or why not."""
    done = stats.get("refined") or []
    text = ""
    if done:
        text = (
            f"; refined {len(done)} block(s) of cells where thin detail hides ({stats['refined_cells']} fine cells, "
            f"up to 1/{max(b['ratio'] for b in done)} of a cell; the report says where)"
        )
    if stats.get("refine_skipped"):
        text += f"; not refined: {stats['refine_skipped']}"
    return text


def main(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    out = Path(args.output)
    check_output_file(out, "-o", tuple(FORMATS))
    if args.report is not None:
        check_output_file(Path(args.report), "--report", (".json",))
    args.cells = validate.whole("--cells", "", _whole(args.cells), MIN_CELLS, MAX_CELLS)
    limit = None
    if args.time_limit is not None:
        limit = validate.number("--time-limit", "", args.time_limit, 0.0, MAX_TIME_LIMIT, lo_open=True, text_ok=True)
    clips = parse_clip(args.clip) if args.clip is not None else []
    spec, values, matrix = _shape(Path(args.file), args.object)
    values.update(_params(spec, args.param))
    deadline = None if limit is None else time.monotonic() + limit  # counted from here: the file is read
    result = mesh_spec(
        spec,
        values,
        args.cells,
        clips,
        singular=not args.no_singular,
        refine=not args.no_refine,
        what=args.file,
        deadline=deadline,
        seconds=limit,
    )
    verts, faces = result.mesh.vertices, result.mesh.faces
    normals = vertex_normals(result.lib, result.clips, verts)
    if matrix is not None:
        verts, faces, normals = place(matrix, verts, faces, normals)
    rep = report(result, spec.name, {**spec.params, **values}, args.cells, verts, faces)
    write_mesh(out, verts, faces, normals)
    if args.report is not None:
        text = json.dumps(rep, indent=1) + "\n"
        atomic_write(Path(args.report), lambda fh: fh.write(text.encode()))  # type: ignore[attr-defined]
    sing = rep["singular_points"]
    sing_text = "not searched" if sing is None else (
        f"{len(sing)} singular point(s) in the box, {rep['singular_in_clip']} in the solid's region"
        + (": " + " ".join(f"({p[0]:.6g}, {p[1]:.6g}, {p[2]:.6g})" for p in sing[:65]) if sing else "")
    )  # fmt: skip
    parted = rep["stats"]["touching_points"]
    if parted:
        sing_text += (
            f"; {parted} point(s) where sheets touched: {rep['stats']['touching_vertices_split']} vertices moved "
            f"{rep['stats']['split_distance']:.2g} apart, {rep['stats']['island_triangles_dropped']} triangles "
            "of squashed islands dropped (the report says which)"
        )
    hidden_text = _refined_text(rep["stats"]) + _missed_text(rep)
    print(
        f"implgen mesh: {spec.name}: {rep['vertices']} vertices, {rep['triangles']} triangles, "
        f"{'closed' if rep['closed'] else 'NOT closed'}, Euler characteristic {rep['euler_characteristic']}; "
        f"{sing_text}{hidden_text} -> {printable(str(out))}",
        file=sys.stderr,
    )
    return 0
