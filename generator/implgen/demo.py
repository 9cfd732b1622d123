"""`implgen demo` (what `make demo` runs): generate every example shape, compile the C against the runtime,
cast a fan of rays at each through the generated Python, then render the showcase scene if there is one."""

from __future__ import annotations

import importlib.util
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from implgen.args import ArgumentParser
from implgen.codegen.derive import derive
from implgen.codegen.emit import derivation_ops, generate
from implgen.compile.clib import WARNING_FLAGS, build_shared
from implgen.errors import UserError, printable
from implgen.outputs import write_text_files
from implgen.resources import SHAPE_SOURCES, SOLVER_SOURCES, gallery_dir, runtime_dir, runtime_sources
from implgen.spec.entry import load_spec

SHOWCASE = Path("examples/scenes/glassware.yaml")
EXAMPLE_SHAPES = Path("examples/shapes")


def _import(path: Path):
    spec = importlib.util.spec_from_file_location(f"_demo_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _ray_fan(module, box) -> tuple[int, int]:
    """Rays from a point outside the box towards a grid over it; returns (hits, rays)."""
    box = np.where(np.isfinite(box), box, np.sign(box) * 2.0) if box is not None else np.array([-2, -2, -2, 2, 2, 2.0])
    centre = (box[:3] + box[3:]) / 2
    size = float(np.max(box[3:] - box[:3]))
    eye = centre + np.array([0.3, 0.4, 3.0]) * size
    u, v = np.meshgrid(np.linspace(-0.5, 0.5, 24), np.linspace(-0.5, 0.5, 24))
    targets = centre + size * np.stack([u, v, np.zeros_like(u)], axis=-1).reshape(-1, 3)
    t = module.intersect(np.broadcast_to(eye, targets.shape), targets - eye, 0.0, np.inf)
    return int(np.count_nonzero(np.isfinite(t))), len(targets)


EXAMPLES = (
    ("what `make demo` runs, in the repository's root (elsewhere: the shapes installed with it)", "implgen demo"),
    ("your own shapes, into another folder", "implgen demo --shapes my_shapes -o out/mine"),
)


def main(argv: Sequence[str]) -> int:
    parser = ArgumentParser(prog="implgen demo", description=__doc__, examples=EXAMPLES)
    parser.add_argument(
        "--shapes",
        type=Path,
        default=None,
        help="folder of shape specs (default: examples/shapes, else the ones installed with implgen)",
    )
    parser.add_argument("-o", "--output", type=Path, default=Path("out"), help="output folder (default: out)")
    args = parser.parse_args(list(argv))
    if args.shapes is None:  # from a clone, its examples; installed with pip anywhere else, the same specs
        args.shapes = EXAMPLE_SHAPES if EXAMPLE_SHAPES.is_dir() else gallery_dir()
    specs = sorted(args.shapes.glob("*.yaml"))
    if not specs:
        raise UserError(args.shapes, "no *.yaml shape specs here (run `make demo` from the repository)")
    gen_dir = args.output / "generated"
    print(f"Generating {len(specs)} example shapes into {gen_dir}/\n")
    print(f"{'shape':<14} {'degree':>6} {'params':<18} {'coeff ops':>9} {'gen ms':>7} {'rays hit':>9}")
    rows = []
    for path in specs:
        start = time.perf_counter()
        spec = load_spec(path)
        derivation = derive(spec)
        write_text_files(generate(spec, ("c", "python"), derivation), gen_dir)
        ms = (time.perf_counter() - start) * 1000
        rows.append((spec, derivation_ops(derivation, "coeffs"), ms))
    build_shared(
        [gen_dir / f"{s.name}.c" for s, _, _ in rows] + runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES),
        include_dirs=[gen_dir, runtime_dir()],
        tag="demo",
    )
    for spec, ops, ms in rows:
        module = _import(gen_dir / f"{spec.name}.py")
        hits, total = _ray_fan(module, module.bounds())
        params = ", ".join(f"{k}={v:g}" for k, v in spec.params.items()) or "-"
        print(f"{spec.name:<14} {spec.degree:>6} {params:<18} {ops:>9} {ms:>7.0f} {hits:>4}/{total}")
    print(f"\nAll generated C compiled with {' '.join(WARNING_FLAGS)} against the runtime.")
    if SHOWCASE.exists():
        try:
            from implgen.animation.command import main as render_main
        except ImportError:
            return 0
        out = args.output / "glassware.png"
        print(f"\nRendering {SHOWCASE} -> {printable(str(out))}")
        return render_main([str(SHOWCASE), "-o", str(out)])
    return 0
