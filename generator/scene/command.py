"""`implgen render SCENE.yaml -o OUT.png [--width W --height H --spp N --threads T --max-depth N]`.

The output is checked before anything else, then the scene is loaded, rendered (scene/render.py) and the
PNG written atomically.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

from implgen.cli import ArgumentParser
from implgen.errors import UserError
from implgen.outputs import check_output_file
from implgen.scene.load import load_scene
from implgen.scene.render import DEFAULT_FOLD, RenderInfo, render, write_png


def _positive(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{v} must be at least 1")
    return v


def main(argv: Sequence[str]) -> int:
    ap = ArgumentParser(label="render", prog="implgen render", description="Render a scene file to a PNG.")
    ap.add_argument("scene", type=Path)
    ap.add_argument("-o", "--output", type=Path, required=True, help="PNG to write")
    ap.add_argument("--width", type=_positive)
    ap.add_argument("--height", type=_positive)
    ap.add_argument("--spp", type=_positive, help="samples per pixel (stratified)")
    ap.add_argument("--threads", type=_positive, help="default: all cores")
    ap.add_argument("--max-depth", type=int, dest="max_depth", metavar="N")
    ap.add_argument("--fold", action="store_true", help="fold constant shape params into the generated code")
    ap.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    args = ap.parse_args(list(argv))
    check_output_file(args.output, "-o", (".png",))
    scene = load_scene(args.scene)
    info = RenderInfo()
    img = render(
        scene,
        width=args.width,
        height=args.height,
        spp=args.spp,
        threads=args.threads,
        max_depth=args.max_depth,
        progress=not args.quiet,
        fold=args.fold or DEFAULT_FOLD,
        info=info,
    )
    try:
        write_png(img, args.output)
    except OSError as err:  # what the early check could not foresee: a full disk, a folder removed meanwhile
        raise UserError(f"-o {args.output}", f"cannot write: {err.strerror or err}") from None
    total = sum(info.rays.values())
    print(
        f"implgen: wrote {args.output} ({img.shape[1]}x{img.shape[0]}, {info.seconds:.3f} s on "
        f"{info.threads} threads, {total / max(info.seconds, 1e-9) / 1e6:.2f} Mrays/s)"
    )
    return 0
