"""Render every gallery surface (implgen.spec.gallery) small into docs/gallery/surfaces/, and a contact sheet.

    .venv/bin/python bench/surfaces.py [-o DIR] [--size 240x180] [--spp 4] [--threads N]

Each surface is drawn on its own (implgen.scene.preview: its box framed, outside gold, inside blue) with its
default params. Writes DIR/surfaces/<name>.png, DIR/surfaces.png (the contact sheet, titles under the pictures)
and prints a table of the render times, written also as DIR/surfaces/times.md with the machine.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from implgen.imagefile import to_uint8, write_png
from implgen.measure.machine import describe as machine
from implgen.scene.preview import preview_scene
from implgen.scene.render import render
from implgen.spec import gallery

COLUMNS = 6
LABEL = 18  # pixels under each picture for its title


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=Path("docs/gallery"))
    parser.add_argument("--size", default="240x180")
    parser.add_argument("--spp", type=int, default=4)
    parser.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    args = parser.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    folder = args.output / "surfaces"
    folder.mkdir(parents=True, exist_ok=True)
    rows = ["| surface | degree | seconds |", "|---|---|---|"]
    tiles = []
    for e in gallery.entries():
        spec = e.load_framed()
        t0 = time.perf_counter()
        image = render(preview_scene(spec, w, h, args.spp), threads=args.threads)
        seconds = time.perf_counter() - t0  # the first render of a shape includes building its library
        write_png(image, folder / f"{e.name}.png")
        tiles.append((e.title, to_uint8(image)))
        rows.append(f"| {e.title} (`{e.name}`) | {spec.degree} | {seconds:.2f} |")
        print(rows[-1], flush=True)
    sheet = contact_sheet(tiles, w, h)
    sheet.save(args.output / "surfaces.png", optimize=True)
    text = f"Rendered by `bench/surfaces.py` at {w}×{h}, {args.spp} samples, on {machine()}.\n\n" + "\n".join(rows)
    (folder / "times.md").write_text(text + "\n", encoding="utf-8")
    print(f"\nwrote {folder}/*.png, times.md and {args.output / 'surfaces.png'}")
    return 0


def contact_sheet(tiles: list[tuple[str, np.ndarray]], w: int, h: int) -> Image.Image:
    """The pictures in a grid of COLUMNS, each titled underneath."""
    cols = min(COLUMNS, len(tiles))
    nrows = -(-len(tiles) // cols)
    sheet = Image.new("RGB", (cols * w, nrows * (h + LABEL)), (30, 30, 34))
    draw = ImageDraw.Draw(sheet)
    for i, (title, pixels) in enumerate(tiles):
        x, y = (i % cols) * w, (i // cols) * (h + LABEL)
        sheet.paste(Image.fromarray(pixels), (x, y))
        draw.text((x + 6, y + h + 3), title.replace("ß", "ss"), fill=(230, 230, 230))  # Pillow's own font is ASCII
    return sheet


if __name__ == "__main__":
    sys.exit(main())
