"""Render every scene in examples/scenes/ at its own size into docs/gallery/, and write the timings.

    .venv/bin/python bench/gallery.py [--scenes DIR] [-o DIR] [--threads N]   (or: make gallery)

Prints a Markdown table (scene, size, samples, seconds, threads, rays by kind) and writes it next to the
images as times.md, with the machine it ran on. An animated scene (docs/animation.md) becomes a GIF of all
its frames at half its size (GIF_SCALE), to stay small enough for the README.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from implgen.animation.batch import Runner, render_frames
from implgen.animation.frameout import plan_output
from implgen.animation.frames import FrameOptions, load_frames
from implgen.imagefile import write_png
from implgen.measure.machine import describe as machine
from implgen.scene.load import load_scene
from implgen.scene.render import RenderInfo, render

GIF_SCALE = 2  # an animation's GIF is its image size divided by this


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", type=Path, default=Path("examples/scenes"))
    parser.add_argument("-o", "--output", type=Path, default=Path("docs/gallery"))
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    args.output.mkdir(parents=True, exist_ok=True)
    rows = [
        "| scene | size | samples/pixel | seconds | threads | primary / shadow / secondary rays |",
        "|---|---|---|---|---|---|",
    ]
    for path in sorted(args.scenes.glob("*.yaml")):
        frames = load_frames(path)
        if frames.animated:
            rows.append(animation_row(path, frames, args))
            print(rows[-1], flush=True)
            continue
        scene = load_scene(path)
        info = RenderInfo()
        image = render(scene, threads=args.threads, progress=sys.stderr.isatty(), info=info)
        write_png(image, args.output / f"{path.stem}.png")
        rays = " / ".join(f"{info.rays.get(k, 0) / 1e6:.2f} M" for k in ("primary", "shadow", "secondary"))
        rows.append(
            f"| [{path.name}](../../{path.as_posix()}) | {scene.width}×{scene.height} | {scene.spp} | "
            f"{info.seconds:.1f} | {info.threads} | {rays} |"
        )
        print(rows[-1], flush=True)
    text = f"Rendered by `make gallery` on {machine()}.\n\n" + "\n".join(rows) + "\n"
    (args.output / "times.md").write_text(text, encoding="utf-8")
    print(f"\nwrote {args.output}/*.png and times.md")
    return 0


def animation_row(path: Path, frames, args: argparse.Namespace) -> str:
    """All frames of an animated scene as docs/gallery/<name>.gif (made afresh: old frames are not reused)."""
    sc = frames.first
    w, h = sc.width // GIF_SCALE // 2 * 2, sc.height // GIF_SCALE // 2 * 2
    opts = FrameOptions(width=w, height=h, spp=sc.spp, max_depth=sc.max_depth, threads=args.threads)
    target = args.output / f"{path.stem}.gif"
    out = plan_output(target, frames.count, frames.count - 1, w, h)
    for f in range(frames.count):
        out.path(f).unlink(missing_ok=True)
    report = render_frames(frames, range(frames.count), opts, out, Runner(), progress=sys.stderr.isatty())
    size = target.stat().st_size / 1e6
    return (
        f"| [{path.name}](../../{path.as_posix()}) | {frames.count} frames of {w}×{h}, {size:.1f} MB GIF | "
        f"{sc.spp} | {report.seconds:.1f} | {args.threads} | - |"
    )


if __name__ == "__main__":
    sys.exit(main())
