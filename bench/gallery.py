"""Render every scene in examples/scenes/ at its own size into docs/gallery/, and write the timings.

    .venv/bin/python bench/gallery.py [--scenes DIR] [-o DIR] [--threads N]   (or: make gallery)

Prints a Markdown table (scene, size, samples, seconds, threads, rays by kind) and writes it next to the
images as times.md, with the machine it ran on.
"""

from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
from pathlib import Path

from implgen.scene.load import load_scene
from implgen.scene.render import RenderInfo, render, write_png


def machine() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
        model = next(line.split(":", 1)[1].strip() for line in out.splitlines() if line.startswith("Model name"))
    except (OSError, StopIteration):
        model = platform.processor() or "unknown CPU"
    return f"{model}, {os.cpu_count()} cores"


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


if __name__ == "__main__":
    sys.exit(main())
