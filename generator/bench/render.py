"""`implgen bench render [SCENE.yaml ...] [--width 800 --height 600 --spp 1] [--fold-compare]`

Renders each scene (default: examples/scenes/*.yaml) on 1 thread and on all threads (best of --repeat runs,
default 3: other work on the machine only ever adds time), and prints a Markdown table of the wall time and
rays per second by kind (primary, shadow, secondary). The library is
built before timing, so compilation is not measured. With --fold-compare it also renders every scene with
the shape params folded into the generated code as constants, to see whether that pays (1 thread,
interleaved, best of 3).
"""

from __future__ import annotations

import os
import platform
from collections.abc import Sequence
from pathlib import Path

from implgen.cli import ArgumentParser
from implgen.errors import UserError
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.render import RenderInfo, render


def _default_scenes() -> list[Path]:
    here = Path.cwd() / "examples" / "scenes"
    return sorted(here.glob("*.yaml"))


def _cpu() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main(argv: Sequence[str]) -> int:
    ap = ArgumentParser(prog="implgen bench render")
    ap.add_argument("scenes", nargs="*", type=Path)
    ap.add_argument("--width", type=int, default=800)
    ap.add_argument("--height", type=int, default=600)
    ap.add_argument("--spp", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3, help="best of this many runs per row (default 3)")
    ap.add_argument("--fold-compare", action="store_true")
    args = ap.parse_args(list(argv))
    scenes = args.scenes or _default_scenes()
    if not scenes:
        raise UserError("bench render", "no scenes given and none in ./examples/scenes")
    ncpu = os.cpu_count() or 1
    print(f"{args.width}x{args.height}, {args.spp} sample(s) per pixel; {_cpu()}, {ncpu} cores\n")
    print("| scene | threads | time (s) | primary Mrays/s | shadow Mrays/s | secondary Mrays/s | all Mrays/s |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    fold_rows = []
    for path in scenes:
        sc = load_scene(path)
        build_scene(sc)  # compile before timing
        for threads in sorted({1, ncpu}):
            t = float("inf")
            for _ in range(max(1, args.repeat)):
                info = RenderInfo()
                render(sc, width=args.width, height=args.height, spp=args.spp, threads=threads, info=info)
                t = min(t, info.seconds)
            r = info.rays
            print(
                f"| {path.stem} | {threads} | {t:.2f} | {r['primary'] / t / 1e6:.2f} | "
                f"{r['shadow'] / t / 1e6:.2f} | {r['secondary'] / t / 1e6:.2f} | {sum(r.values()) / t / 1e6:.2f} |"
            )
        if args.fold_compare:
            # interleaved, best of 3 each, so a load change on the machine hits both variants alike
            build_scene(load_scene(path), fold=True)
            best = {False: float("inf"), True: float("inf")}
            for _ in range(3):
                for fold in (False, True):
                    info = RenderInfo()
                    render(
                        load_scene(path),
                        width=args.width,
                        height=args.height,
                        spp=args.spp,
                        threads=1,
                        fold=fold,
                        info=info,
                    )
                    best[fold] = min(best[fold], info.seconds)
            fold_rows.append((path.stem, best[False], best[True]))
    if fold_rows:
        print("\n| scene | params at run time (s) | params folded (s) | change |")
        print("|---|---:|---:|---:|")
        for name, a, b in fold_rows:
            print(f"| {name} | {a:.3f} | {b:.3f} | {100 * (b - a) / a:+.1f}% |")
    return 0
