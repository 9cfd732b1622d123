"""`implgen render SCENE.yaml -o OUT [options]`: a still to a PNG, or an animation's frames to a PNG
sequence, a video or a GIF; here, on a LocalCluster, or on a running Dask cluster.

The output is checked before anything else, then the scene is loaded and every frame validated, and only
then does anything render. A still scene without Dask options takes the path it always took (render.py),
and imports nothing of the batch or of Dask (asyncio and all): `cluster` and `batch` are imported where an
animation, tiles or Dask first need them, so a cached still starts quickly (bench/startup.py).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from implgen import validate
from implgen.animation.frameout import FrameOutput, plan_output
from implgen.animation.frames import FrameOptions, Frames, load_frames, parse_range
from implgen.args import ArgumentParser
from implgen.errors import UserError, printable
from implgen.imagefile import write_grey_png, write_png
from implgen.outputs import atomic_write, check_output_file
from implgen.scene.keys import MAX_FRAMES
from implgen.scene.render import DEFAULT_FOLD, RenderInfo, image_options, render

if TYPE_CHECKING:
    from implgen.animation.batch import Runner

MAX_RETRIES = 100


def _positive(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{v} must be at least 1")
    return v


EXAMPLES = (
    ("a still at the scene's own size", "implgen render examples/scenes/glassware.yaml -o glass.png"),
    (
        "a quick look: 400x300, 1 sample per pixel",
        "implgen render examples/scenes/glassware.yaml -o look.png --width 400 --height 300 --spp 1",
    ),
    ("an animation as a video", "implgen render examples/scenes/torus_opening.yaml -o opening.mp4"),
    ("frames 0 to 9 as PNGs", "implgen render examples/scenes/torus_opening.yaml -o frames/f_%04d.png --frames 0:9"),
    (
        "on a Dask LocalCluster of 4 processes",
        "implgen render examples/scenes/torus_opening.yaml -o opening.gif --local-workers 4",
    ),
    (
        "on a running Dask scheduler, each frame in 8 bands",
        "implgen render examples/scenes/torus_opening.yaml -o opening.webm --cluster tcp://HOST:8786 --tiles 8",
    ),
)


def _parser() -> ArgumentParser:
    ap = ArgumentParser(
        label="render",
        prog="implgen render",
        description="Render a scene file: a still to a PNG, or an animation's frames to PNGs, a video or a GIF; "
        "here, or on Dask (docs/animation.md).",
        examples=EXAMPLES,
    )
    ap.add_argument("scene", type=Path)
    ap.add_argument(
        "-o", "--output", type=Path, required=True, help="OUT.png, a pattern like frames/f_%%04d.png, .mp4, .webm, .gif"
    )
    ap.add_argument("--width", type=_positive)
    ap.add_argument("--height", type=_positive)
    ap.add_argument("--spp", type=_positive, help="samples per pixel (stratified)")
    ap.add_argument("--threads", type=_positive, help="render threads per frame (default: all cores)")
    ap.add_argument("--max-depth", type=int, dest="max_depth", metavar="N")
    ap.add_argument("--fold", action="store_true", help="fold constant shape params into the generated code")
    ap.add_argument("--frames", metavar="A:B", help="render frames A to B of an animation (both included)")
    where = ap.add_mutually_exclusive_group()
    where.add_argument("--local-workers", type=_positive, metavar="N", help="a Dask LocalCluster of N processes")
    where.add_argument("--cluster", metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://host:8786")
    ap.add_argument("--tiles", type=_positive, metavar="K", help="render each frame as K bands of rows (K tasks)")
    ap.add_argument("--retries", type=int, default=3, help="reruns of a failed task (default 3)")
    ap.add_argument("--keep-frames", action="store_true", help="keep a video's or GIF's frame PNGs")
    ap.add_argument("--certify", type=Path, metavar="MAP.png", help="a still only: its primary rays' certify map")
    ap.add_argument("--report", type=Path, metavar="R.json", help="with --certify: counts per reason and per object")
    ap.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    return ap


def _check_certify(args: argparse.Namespace) -> None:
    """--certify MAP.png and --report R.json: checked before the scene is read."""
    if args.report is not None and args.certify is None:
        raise UserError(f"--report {args.report}", "needs --certify MAP.png")
    if args.certify is not None:
        check_output_file(args.certify, "--certify", (".png",))
        if args.certify.resolve() == args.output.resolve():
            raise UserError(f"--certify {args.certify}", "is the same file as -o")
    if args.report is not None:
        check_output_file(args.report, "--report", (".json",))


def main(argv: Sequence[str]) -> int:
    args = _parser().parse_args(list(argv))
    validate.whole("--retries", "", args.retries, 0, MAX_RETRIES)
    _check_certify(args)
    address = _check_dask(args)
    plan_output(args.output, 1, MAX_FRAMES - 1, 2, 2)  # the path alone, before reading the scene
    frames = load_frames(args.scene)
    todo = parse_range(args.frames, frames.count) if args.frames is not None else range(frames.count)
    opts = _options(args, frames)
    out = plan_output(args.output, len(todo), todo[-1], opts.width, opts.height)
    out.check_fps(frames.fps, frames.source)
    if args.fold and frames.params_vary:
        raise UserError("--fold", "the scene's shape params change from frame to frame; they cannot be folded")
    if args.tiles is not None:
        validate.whole("--tiles", "", args.tiles, 1, opts.height)
    distributed = args.local_workers is not None or address is not None
    still = out.kind == "still" and args.tiles is None and not distributed
    if args.certify is not None and not still:
        raise UserError("--certify", "only a still image rendered here is certified (no animation, --tiles or Dask)")
    if still:
        return _still(args, frames, todo[0], opts, out)
    return _many(args, frames, todo, opts, out, address)


def _check_dask(args: argparse.Namespace) -> str | None:
    """The Dask options, checked before the scene is read; the scheduler's address, or None. Only they import
    `cluster` (Dask's side: asyncio and all), so that a still does not."""
    if args.cluster is None and args.local_workers is None:
        return None
    from implgen.animation import cluster

    if args.local_workers is not None:
        validate.whole("--local-workers", "", args.local_workers, 1, cluster.MAX_LOCAL_WORKERS)
    return cluster.check_address(args.cluster) if args.cluster is not None else None


def _many(
    args: argparse.Namespace, frames: Frames, todo: range, opts: FrameOptions, out: FrameOutput, address: str | None
) -> int:
    """Frames, tiles or Dask: through the batch (animation/batch.py), imported only here."""
    from implgen.animation import cluster
    from implgen.animation.batch import Runner

    if args.local_workers is not None and args.threads is None:
        opts = dataclasses.replace(opts, threads=cluster.local_threads(args.local_workers))
    if args.local_workers is None and address is None:
        return _run(args, frames, todo, opts, out, Runner(retries=args.retries))
    with cluster.connect(args.local_workers, address) as client:
        label = "--cluster" if address is not None else "--local-workers"
        return _run(args, frames, todo, opts, out, Runner(client=client, retries=args.retries, label=label))


def _options(args: argparse.Namespace, frames: Frames) -> FrameOptions:
    o = image_options(
        frames.first, width=args.width, height=args.height, spp=args.spp, max_depth=args.max_depth, threads=args.threads
    )
    return FrameOptions(**dataclasses.asdict(o))


def _still(args: argparse.Namespace, frames: Frames, frame: int, opts: FrameOptions, out: FrameOutput) -> int:
    """One image in this process, with a progress bar over rows (what `implgen render` always did)."""
    info = RenderInfo()
    got = render(
        frames.scene(frame),
        width=opts.width,
        height=opts.height,
        spp=opts.spp,
        threads=opts.threads,
        max_depth=opts.max_depth,
        progress=not args.quiet,
        fold=args.fold or DEFAULT_FOLD,
        info=info,
        certify=args.certify is not None,
    )
    img, cert = got if args.certify is not None else (got, None)
    try:
        write_png(img, out.target)
    except OSError as err:  # what the early check could not foresee: a full disk, a folder removed meanwhile
        raise UserError(f"-o {args.output}", f"cannot write: {err.strerror or err}") from None
    if cert is not None:
        _write_certificate(args, cert)
    total = sum(info.rays.values())
    print(
        f"implgen: wrote {printable(str(out.target))} ({img.shape[1]}x{img.shape[0]}, {info.seconds:.3f} s on "
        f"{info.threads} threads, {total / max(info.seconds, 1e-9) / 1e6:.2f} Mrays/s)"
    )
    return 0


def _write_certificate(args: argparse.Namespace, cert) -> None:
    """The certify map and its report, and one line saying how many pixels are certified."""
    option, path = "--certify", args.certify
    try:
        write_grey_png(cert.codes, args.certify)
        if args.report is not None:
            option, path = "--report", args.report
            text = json.dumps(cert.report(), indent=1) + "\n"
            atomic_write(args.report, lambda fh: fh.write(text.encode()))
    except OSError as err:
        raise UserError(f"{option} {path}", f"cannot write: {err.strerror or err}") from None
    rep = cert.report()
    print(
        f"implgen: certified {rep['certified']} of {rep['pixels']} pixels ({rep['not_certified']} not: "
        f"{printable(str(args.certify))}; certify pass {cert.seconds:.3f} s)"
    )


def _run(
    args: argparse.Namespace, frames: Frames, todo: range, opts: FrameOptions, out: FrameOutput, runner: Runner
) -> int:
    from implgen.animation.batch import render_frames

    tiles = args.tiles or 1
    report = render_frames(
        frames,
        todo,
        opts,
        out,
        runner,
        tiles=tiles,
        fold=args.fold,
        progress=not args.quiet,
        keep_frames=args.keep_frames,
    )
    where = "this process" if runner.client is None else f"{runner.workers()} Dask workers"  # those there now
    n = len(report.written)
    skipped = f", {len(report.skipped)} already there" if report.skipped else ""
    cut = f" in {tiles} tiles each" if tiles > 1 else ""
    k = len(report.replaced)
    again = f"; {k} frame{'' if k == 1 else 's'} there rendered again ({report.replaced_why})" if k else ""
    print(
        f"implgen: wrote {n} frame{'' if n == 1 else 's'}{skipped} of {opts.width}x{opts.height}{cut} "
        f"to {printable(str(out.target))} in {report.seconds:.1f} s ({where}){again}"
    )
    return 0
