"""`implgen mesh` against the usual route: scikit-image's marching_cubes on the same grid, f sampled through the
generated Python module.

    nice .venv/bin/python bench/mesh.py [--runs 3] [--cells 128] [-o bench/results/mesh.md]

Per surface: the time at --cells (median of --runs, the two methods interleaved run by run; the shape's library
is built once before, as a second `implgen mesh` of it finds it cached; marching cubes is timed with its
sampling), the largest and median distance of a vertex to the solid's boundary (|g| / |grad g| with
g = max(f, clips), in doubles through the compiled shape), whether each mesh is closed (every edge in two faces,
trimesh's is_watertight after merging equal vertices), and its Euler characteristic against the known one; then
the smallest grid of GRIDS at which each gets the topology right (closed and the right Euler characteristic).
"""

from __future__ import annotations

import argparse
import functools
import importlib.util
import io
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh
from skimage.measure import marching_cubes

from implgen.codegen.emit import generate
from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results
from implgen.mesh.contour import contour
from implgen.mesh.crossings import boundary_value_gradient
from implgen.mesh.pipeline import closed_and_euler, mesh_spec
from implgen.mesh.refine import refine
from implgen.mesh.region import make_grid, parse_clip
from implgen.mesh.shapelib import ShapeLib
from implgen.mesh.singular import find_singular
from implgen.mesh.write import mesh_bytes
from implgen.spec.entry import load_spec

ROOT = Path(__file__).resolve().parents[1]
GRIDS = (4, 6, 8, 12, 16, 24, 32, 48, 64, 96, 128)
# (label, spec, clip, Euler characteristic and where it comes from; None: not a manifold)
SURFACES = (
    ("torus", "examples/shapes/torus_z.yaml", None, 0, "a torus"),
    ("heart", "examples/shapes/heart.yaml", None, 2, "a sphere"),
    ("Barth sextic in a ball of 1.8", "examples/shapes/barth6.yaml", "sphere:1.8", None, "50 nodes on it"),
    ("Chmutov 8", "examples/shapes/chmutov8.yaml", None, -160, "Morse: 2(b^3 - 3ab^2), b = 4, a = 3"),
    ("tanglecube", "examples/mesh/tanglecube.yaml", None, -8, "genus 5"),
    ("Chmutov 12 (degree 12)", "examples/mesh/chmutov12.yaml", None, -648, "Morse, b = 6, a = 5"),
    ("Chmutov 20 (degree 20)", "examples/mesh/chmutov20.yaml", None, -3400, "Morse, b = 10, a = 9"),
    ("Cassini, neck of radius 0.03", "tests/data/cassini_neck.yaml", None, 2, "one piece: two lobes and the neck"),
    ("two balls 0.02 apart", "tests/data/two_balls_gap.yaml", None, 4, "two spheres"),
    ("Kummer quartic in a ball of 2", "examples/mesh/kummer.yaml", "sphere:2", None, "16 nodes on it"),
)
NODAL_GRIDS = (16, 24, 32, 48, 64, 96, 128)  # the nodal surfaces' meshes as written, read back


def python_module(spec, folder: Path):
    """The generated Python module of the spec (what a user of the marching-cubes route would call)."""
    path = folder / f"{spec.name}.py"
    path.write_text(generate(spec, langs=("python",))[f"{spec.name}.py"])
    mod_spec = importlib.util.spec_from_file_location(f"_bench_mesh_{spec.name}", path)
    module = importlib.util.module_from_spec(mod_spec)
    mod_spec.loader.exec_module(module)
    return module


def boundary_distance(lib: ShapeLib, clips, verts: np.ndarray) -> np.ndarray:
    f, g = boundary_value_gradient(lib, clips, verts)
    return np.abs(f) / np.maximum(np.linalg.norm(g, axis=1), 1e-300)


def ours(lib, clips, grid, stats=None, refined=True, nodes=None):
    """`implgen mesh`'s contour, then its local refinement (mesh/refine.py) unless `refined` is False (the grid
    alone, as before refinement). The singular points (`nodes`, found beforehand on the nodal surfaces, untimed: a
    phase of its own in `implgen mesh`) are set aside as the pipeline does: no refinement within two cells."""
    m = contour(lib, clips, grid)
    t = time.perf_counter()
    nodes = np.zeros((0, 3)) if nodes is None else nodes
    if refined:
        if m.missed is not None:
            m.missed = m.missed.away_from(nodes, 2 * grid.h)
        refine(lib, clips, m, nodes)
    m.parts = None
    if stats is not None:
        stats.append({**m.stats, "seconds": {**m.stats["seconds"], "refine": time.perf_counter() - t}})
    return m.vertices, m.faces


def grid_alone(lib, clips, grid, stats=None):
    return ours(lib, clips, grid, stats, refined=False)


def nodes_of(lib, grid, euler) -> np.ndarray | None:
    """The singular points in the grid's box on a nodal surface (no known Euler characteristic), else None."""
    if euler is not None:
        return None
    return find_singular(lib, grid.origin, grid.origin + grid.h * np.array(grid.n)).points


def marching(module, params, clips, grid):
    x, y, z = (grid.coords(a) for a in range(3))
    pts = np.stack(np.meshgrid(x, y, z, indexing="ij"), axis=-1)
    g = module.value(pts, **params)
    for c in clips:
        g = np.maximum(g, c.value(pts))
    verts, faces, _, _ = marching_cubes(g, level=0.0, spacing=(grid.h,) * 3)
    return verts + grid.origin, faces


def topology(verts, faces, merge: bool):
    if len(faces) == 0:
        return False, None
    if merge:
        tm = trimesh.Trimesh(verts, faces, process=True)
        return bool(tm.is_watertight), int(tm.euler_number)
    closed, euler = closed_and_euler(faces, len(verts))
    return closed, euler


def timed(fn, *args):
    t = time.perf_counter()
    out = fn(*args)
    return time.perf_counter() - t, out


def run_surface(label, path, clip_text, euler, runs, cells, folder):
    spec = load_spec(ROOT / path, cache=True)
    lib = ShapeLib(spec, list(spec.params.values()))
    module = python_module(spec, folder)
    user = parse_clip(clip_text) if clip_text else []
    row = {"label": label, "degree": spec.degree}
    smallest = {"ours": None, "grid": None, "mc": None}
    right_at = {"ours": [], "grid": [], "mc": []}
    row["grids"] = {}  # n: (the grid alone's Euler, MC's, its edges with crossings their ends do not show, missed)
    row["refined"] = {}  # n: (ours' Euler, blocks refined, fine cells)
    for n in GRIDS:
        grid, clips = make_grid(spec.box(), user, n, path)
        seen = {}
        nodes = nodes_of(lib, grid, euler)
        methods = (("ours", functools.partial(ours, nodes=nodes), False), ("grid", grid_alone, False))
        for name, fn, merge in (*methods, ("mc", marching, True)):
            stats = []
            args = (lib, clips, grid, stats) if name != "mc" else (module, spec.params, clips, grid)
            try:
                verts, faces = fn(*args)
            except ValueError:  # marching cubes: no grid vertex inside
                verts, faces = np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64)
            closed, e = topology(verts, faces, merge)
            seen[name] = e if closed else None
            if stats and name == "grid":
                seen["hidden"] = stats[0]["hidden_crossing_edges"]
                seen["missed"] = stats[0]["missed_detail_edges"]
            if stats and name == "ours":
                refined = stats[0]["refined"]
                row["refined"][n] = (e if closed else None, len(refined), sum(b["fine_cells"] for b in refined))
            ok = closed and euler is not None and e == euler
            if ok:
                right_at[name].append(n)
                if smallest[name] is None:
                    smallest[name] = n
            if n == cells:
                d = boundary_distance(lib, clips, verts)
                row[name] = {"closed": closed, "euler": e, "max": float(d.max()), "median": float(np.median(d))}
                row["size"] = grid.size
        row["grids"][n] = (seen["grid"], seen["mc"], seen["hidden"], seen["missed"])
    grid, clips = make_grid(spec.box(), user, cells, path)
    t_ours, t_grid, t_mc, stats = [], [], [], []
    nodes = nodes_of(lib, grid, euler)
    for _ in range(runs):  # interleaved
        t_ours.append(timed(ours, lib, clips, grid, stats, True, nodes)[0])
        t_grid.append(timed(grid_alone, lib, clips, grid)[0])
        t_mc.append(timed(marching, module, spec.params, clips, grid)[0])
    row["t_ours"], row["t_grid"], row["t_mc"] = (statistics.median(t) for t in (t_ours, t_grid, t_mc))
    row["refined_at_cells"] = bool(stats[0]["refined"])
    row["phases"] = {k: statistics.median(st["seconds"][k] for st in stats) for k in stats[0]["seconds"]}
    row["smallest"] = smallest
    row["right_at"] = right_at
    row["stays"] = {k: stays_right(v) for k, v in right_at.items()}
    return row


def stays_right(right_at: list[int]) -> int | None:
    """The smallest grid of GRIDS from which every grid is right (None: not right at the largest)."""
    out = None
    for n in reversed(GRIDS):
        if n not in right_at:
            break
        out = n
    return out


def yn(v: bool) -> str:
    return "yes" if v else "no"


def table(rows, cells: int) -> list[str]:
    out = [
        f"| surface | degree | time ours / grid alone / MC (s), N = {cells} | ours / MC | ours / grid alone "
        "| max distance ours / MC (of the box) | median ours / MC | closed ours / MC | Euler ours / MC (known) "
        "| smallest right grid ours / grid alone / MC | right from (every grid after it) ours / grid alone / MC |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        o, m, s = r["ours"], r["mc"], r["size"]
        known = "n/a" if r["known"] is None else str(r["known"])
        small = " / ".join(str(r["smallest"][k] or "-") for k in ("ours", "grid", "mc"))
        stays = " / ".join(str(r["stays"][k] or "-") for k in ("ours", "grid", "mc"))
        times = f"{r['t_ours']:.2f} / {r['t_grid']:.2f} / {r['t_mc']:.2f}"
        ratios = f"{r['t_ours'] / r['t_mc']:.2f} | {r['t_ours'] / r['t_grid']:.2f}"
        out.append(
            f"| {r['label']} | {r['degree']} | {times} | {ratios} "
            f"| {o['max'] / s:.1e} / {m['max'] / s:.1e} | {o['median'] / s:.1e} / {m['median'] / s:.1e} "
            f"| {yn(o['closed'])} / {yn(m['closed'])} | {o['euler']} / {m['euler']} ({known}) | {small} | {stays} |"
        )
    return out


def phase_table(rows, cells: int) -> list[str]:
    """Where our time goes: each phase of contour() (its stats' seconds), median over the timed runs."""
    names = list(rows[0]["phases"])
    out = [
        f"| surface | {' | '.join(names)} | total (s), N = {cells} |",
        "|---|" + "---|" * (len(names) + 1),
    ]
    for r in rows:
        ph = r["phases"]
        out.append(f"| {r['label']} | " + " | ".join(f"{ph[k]:.3f}" for k in names) + f" | {sum(ph.values()):.3f} |")
    return out


def _euler(e) -> str:
    return "not closed" if e is None else str(e)


def coarse_table(rows) -> list[str]:
    """Below the smallest right grid: what each method got, and how many grid edges held crossings that their
    two ends did not show (ours; the detail both methods miss)."""
    out = [
        "| surface | grids where both are closed: with the same Euler characteristic | largest wrong grid below the "
        "grid alone's smallest right one | Euler there grid alone / MC (known) "
        "| edges with crossings their ends do not show there | of them, detail the grid misses (the warning) |",
        "|---|---|---|---|---|---|",
    ]
    for r in rows:
        if r["known"] is None:
            continue
        g = r["grids"]
        both = [(o, m) for o, m, *_ in g.values() if o is not None and m is not None]
        agree = f"{len(both)} of {len(g)}: {sum(1 for o, m in both if o == m)}"
        small = r["smallest"]["grid"]
        below = [n for n in g if small is None or n < small]
        if below:
            n = max(below)
            o, m, hidden, missed = g[n]
            out.append(
                f"| {r['label']} | {agree} | {n} | {_euler(o)} / {_euler(m)} ({r['known']}) | {hidden} | {missed} |"
            )
        else:
            out.append(f"| {r['label']} | {agree} | - (right at {small}) | | | |")
    return out


def warning_table(rows) -> list[str]:
    """Where the warning of detail the grid misses spoke: on the grids where our topology was right (it should
    not) and where it was wrong (it should, when a grid line crosses what was missed)."""
    out = [
        "| surface | grids right: warned | grids wrong: warned | wrong and silent at |",
        "|---|---|---|---|",
    ]
    total = [0, 0, 0, 0]
    for r in rows:
        if r["known"] is None:
            continue
        g = r["grids"]
        right = [n for n in g if n in r["right_at"]["grid"]]
        wrong = [n for n in g if n not in r["right_at"]["grid"]]
        warned_right = [n for n in right if g[n][3]]
        warned_wrong = [n for n in wrong if g[n][3]]
        silent = [n for n in wrong if not g[n][3]]
        for k, part in enumerate((right, warned_right, wrong, warned_wrong)):
            total[k] += len(part)
        out.append(
            f"| {r['label']} | {len(warned_right)} of {len(right)}"
            + (f" ({', '.join(map(str, warned_right))})" if warned_right else "")
            + f" | {len(warned_wrong)} of {len(wrong)} | {', '.join(map(str, silent)) or '-'} |"
        )
    out.append(f"| all | {total[1]} of {total[0]} | {total[3]} of {total[2]} | |")
    return out


def fans(faces: np.ndarray) -> int:
    """How many fans of triangles meet at the vertices of a closed mesh (each edge in two faces, once each way):
    at vertex a each face (a, b, c) takes the link edge b to c; the cycles of those are the fans, counted by
    pointer doubling (one per vertex on a 2-manifold)."""
    f = np.asarray(faces, dtype=np.int64)
    n = int(f.max()) + 1
    a, b, c = f.reshape(-1), f[:, [1, 2, 0]].reshape(-1), f[:, [2, 0, 1]].reshape(-1)
    key = a * n + b
    order = np.argsort(key)
    succ = order[np.searchsorted(key[order], a * n + c)]  # the corner whose link edge starts where this one ends
    low = np.arange(len(key))
    for _ in range(int(np.ceil(np.log2(max(len(key), 2)))) + 1):
        low = np.minimum(low, low[succ])
        succ = succ[succ]
    return int((low == np.arange(len(key))).sum())


def nodal_rows(label: str, path: str, clip_text: str, folder: Path) -> list[str]:
    """A nodal surface meshed as `implgen mesh` does (singular points, parted sheets) and written as STL, and
    marching cubes' mesh, each read back by trimesh (equal positions merged): closed, a 2-manifold (one fan of
    triangles at each vertex), the Euler characteristic against the one reported."""
    spec = load_spec(ROOT / path, cache=True)
    module = python_module(spec, folder)
    user = parse_clip(clip_text)
    out = []
    for n in NODAL_GRIDS:
        result = mesh_spec(spec, {}, n, user)
        v, f = result.mesh.vertices, result.mesh.faces
        _, euler = closed_and_euler(f, len(v))
        back = trimesh.load(io.BytesIO(mesh_bytes("stl", v, f, None)), file_type="stl")
        st = result.mesh.stats
        grid, clips = make_grid(spec.box(), user, n, path)
        mv, mf = marching(module, spec.params, clips, grid)
        mc = trimesh.Trimesh(mv, mf, process=True)
        ours_ok, mc_ok = (m.is_watertight and fans(m.faces) == len(m.vertices) for m in (back, mc))
        touched = f"{st['touching_points']} ({st['touching_vertices_split']} moved, "
        touched += f"{st['island_triangles_dropped']} triangles dropped)"
        out.append(
            f"| {label} | {n} | {euler} / {back.euler_number} | {yn(back.is_watertight)} | {yn(ours_ok)} | {touched} "
            f"| {mc.euler_number} | {yn(mc.is_watertight)} | {yn(mc_ok)} |"
        )
    return out


def nodal_table(folder: Path) -> list[str]:
    out = [
        "| surface | N | Euler reported / read back from the STL | closed | a 2-manifold | points where sheets "
        "touched | MC: Euler | closed | a 2-manifold |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for label, path, clip, euler, _ in SURFACES:
        if euler is None:
            out += nodal_rows(label, path, clip, folder)
    return out


def targets(rows) -> list[str]:
    known = [r for r in rows if r["known"] is not None]
    every = [r["label"] for r in known if not set(r["right_at"]["mc"]) <= set(r["right_at"]["ours"])]
    calm = [(r["label"], r["t_ours"] / r["t_grid"]) for r in rows if not r["refined_at_cells"]]
    coarser = [
        r["label"]
        for r in known
        if r["smallest"]["ours"] is not None
        and (r["smallest"]["mc"] is None or r["smallest"]["ours"] < r["smallest"]["mc"])
    ]
    err = [(r["label"], r["mc"]["max"] / max(r["ours"]["max"], 1e-300)) for r in rows]
    slow = [(r["label"], r["t_ours"] / r["t_mc"]) for r in rows if r["t_ours"] > 2 * r["t_mc"]]
    lines = [
        "Targets (time, topology, vertex error, coarser grid):",
        "",
        "- topology right at every grid where marching cubes gets it right: "
        + ("met on every surface with a known Euler characteristic" if not every else "missed on " + ", ".join(every)),
        f"- right at a coarser grid than marching cubes on at least half of them: {len(coarser)} of {len(known)} "
        f"({', '.join(coarser) or 'none'}): " + ("met" if 2 * len(coarser) >= len(known) else "missed"),
        "- largest vertex error at least 1000x smaller: "
        + ", ".join(f"{label} {ratio:.1e}x" for label, ratio in err)
        + (": met" if all(ratio >= 1000 for _, ratio in err) else ": missed where below 1000x"),
        "- time within 2x of marching cubes: "
        + ("met on every surface" if not slow else "missed on " + ", ".join(f"{name} ({x:.1f}x)" for name, x in slow)),
        "- where nothing is refined, at most 1.5x the time of the grid alone (the search for thin features is the "
        "cost): "
        + ", ".join(f"{name} {x:.2f}x" for name, x in calm)
        + (": met" if all(x <= 1.5 for _, x in calm) else ": missed where above 1.5x"),
        *thin_targets(known),
    ]
    return lines


def thin_targets(known) -> list[str]:
    """The warning silent on right meshes; the thin neck and the gap right at every grid from 16 cells on."""
    warned = sum(1 for r in known for n in r["right_at"]["grid"] if r["grids"][n][3])
    right = sum(len(r["right_at"]["grid"]) for r in known)
    thin = [r for r in known if r["label"].startswith(("Cassini", "two balls"))]
    return [
        f"- the warning of detail the grid misses silent on the grid's meshes whose topology is right: spoke on "
        f"{warned} of {right}: " + ("met" if warned == 0 else "missed"),
        "- thin neck and near-touching shapes right at every grid from 16 cells on, and from at most half the cells "
        "marching cubes needs: "
        + ", ".join(
            f"{r['label']} right from {r['stays']['ours'] or '-'} (the grid alone {r['stays']['grid'] or '-'}, "
            f"MC {r['stays']['mc'] or '-'})"
            for r in thin
        )
        + (": met" if all(_thin_ok(r) for r in thin) else ": missed"),
    ]


def _thin_ok(r) -> bool:
    ours, mc = r["stays"]["ours"] or 999, r["stays"]["mc"] or 999
    return ours <= 16 and 2 * ours <= mc


def refine_table(rows) -> list[str]:
    """Per grid, on the surfaces where anything was refined: the Euler characteristic of the grid alone, ours (its
    blocks and fine cells), marching cubes'."""
    out = [
        "| surface | N | Euler grid alone / ours / MC (known) | blocks refined | fine cells |",
        "|---|---|---|---|---|",
    ]
    for r in rows:
        if r["known"] is None or not any(v[1] for v in r["refined"].values()):
            continue
        for n, (e, blocks, fine) in r["refined"].items():
            g = r["grids"][n]
            out.append(f"| {r['label']} | {n} | {_euler(g[0])} / {_euler(e)} / {_euler(g[1])} ({r['known']}) "
                       f"| {blocks} | {fine} |")  # fmt: skip
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--cells", type=int, default=128, choices=GRIDS)
    ap.add_argument("-o", "--output", default=str(ROOT / "bench/results/mesh.md"))
    args = ap.parse_args()
    args.load_before = load_average()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for label, path, clip, euler, why in SURFACES:
            row = run_surface(label, path, clip, euler, args.runs, args.cells, Path(tmp))
            row["known"], row["why"] = euler, why
            rows.append(row)
            print(table([row], args.cells)[-1], flush=True)
        lines = report(rows, args, Path(tmp))
    write_results(Path(args.output), "\n".join(lines))
    print("\n".join(lines))
    return 0


def report(rows, args, tmp: Path) -> list[str]:
    """The results file's lines: the comparison, then the topology's tables."""
    return [
        "# implgen mesh against marching cubes",
        "",
        f"Machine: {machine()}; load average at the start {args.load_before}, at the end {load_average()}.",
        f"Written by `nice .venv/bin/python bench/mesh.py --runs {args.runs} --cells {args.cells}`.",
        "",
        "Ours: `implgen mesh`'s contour (exact crossings on every grid line, one vertex per sheet, Newton onto the "
        "surface) and its local refinement; the grid alone: the contour without refinement (`--no-refine`). "
        "MC: scikit-image `marching_cubes` on the same grid, f (and the clip) sampled through the "
        "generated Python module, the sampling timed with it. Distances are |g| / |grad g| at each vertex, "
        "g = max(f, clips), as a fraction of the grid's size; ours sit at f's rounding in doubles. "
        "Closed: every edge in exactly two faces (marching cubes' vertices merged first). Smallest right grid: the "
        f"first of {', '.join(map(str, GRIDS))} cells along the longest side at which the mesh is closed with "
        "the known Euler characteristic.",
        "",
        *table(rows, args.cells),
        "",
        "Where our time goes (seconds per phase of the contour, medians of the timed runs): signs -- f at every "
        "grid vertex; crossings -- every root on every grid line (the certified solver) and the gradient at each "
        "edge's crossing; missed -- the test of the intervals between two crossings on one grid edge (the warning of "
        "detail the grid misses); sheets -- cells' corner patterns, ambiguous faces' centres, the sheet table; qef -- "
        "each sheet's point (one C loop over the cells); projection -- Newton onto the surface (C for f alone); "
        "faces -- quads into triangles; refine -- the search for thin features (critical points of f) and, where "
        "any is found, the refined blocks.",
        "",
        *phase_table(rows, args.cells),
        "",
        *topology_report(rows, tmp),
    ]


def topology_report(rows, tmp: Path) -> list[str]:
    """Below the smallest right grids, the warning, the nodal surfaces, the targets."""
    return [
        "Local refinement (`mesh/refine.py`): where a critical point of f has a feature less than half a cell "
        "across, or the exact crossings show an interval the grid misses, a block of cells is meshed again on a "
        "finer grid and stitched to the rest. On the surfaces where it refined anything, grid by grid:",
        "",
        *refine_table(rows),
        "",
        "Why the grid alone is not coarser than marching cubes: both read the signs at the same grid vertices. "
        "Below the grid alone's smallest right grid, what each got and how many grid edges held two (or more) "
        "crossings with both ends on one side -- a thin neck or handle between two grid vertices, which the exact "
        "crossings see and no sign shows:",
        "",
        *coarse_table(rows),
        "",
        "The warning of detail the grid misses (`mesh/missed.py`: an interval between two crossings on a grid "
        "edge that no grid vertex of its phase reaches, or that joins parts the grid keeps apart, or a gap the "
        f"grid bridges), over the grids {', '.join(map(str, GRIDS))}: it should be silent where our topology is "
        "right, and speak where it is wrong when a grid line crosses what the grid missed (one that no grid line "
        "crosses is not seen):",
        "",
        *warning_table(rows),
        "",
        "Nodal surfaces, meshed as `implgen mesh` does (the singular points found and the node's cells put on "
        "them, touching sheets parted, `mesh/unpinch.py`), written as STL and read back by trimesh (vertices at "
        "equal positions merged, as every STL reader does); marching cubes' mesh with its vertices merged. A "
        "2-manifold: closed, and one fan of triangles at every vertex (no two sheets touching at a point).",
        "",
        *nodal_table(tmp),
        "",
        "Known Euler characteristics: " + "; ".join(f"{r['label']}: {r['why']}" for r in rows) + ".",
        "Barth's sextic and the Kummer quartic have no Euler characteristic to check against: their nodes make them "
        "not manifolds, and a mesh either joins or separates the solid at each of them, as the grid falls.",
        "",
        *targets(rows),
        "",
    ]


if __name__ == "__main__":
    sys.exit(main())
