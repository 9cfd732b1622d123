"""Render every bench and example scene with a given copy of runtime_c, and compare two such sets pixel by pixel.

Used to check that a tracer change leaves pictures unchanged:

    python bench/picture_diff.py render --runtime /tmp/base/runtime_c --out /tmp/pics_before
    python bench/picture_diff.py render --runtime runtime_c --out /tmp/pics_after
    python bench/picture_diff.py compare /tmp/pics_before /tmp/pics_after

`render` writes, per scene, the float32 image (<scene>.npy, the exact colours) and the PNG. `compare` reports,
per scene, how many pixels differ in the float image and in the 8-bit PNG, and lists the first differing ones.
The scenes render at half their own size (at least 200 wide) with their own samples and depth.

`time` times the render loop of each scene given (one thread, the C loop alone, as `implgen bench render`
does) with a base runtime and with this one, interleaved run by run, and prints the medians and their ratio:

    python bench/picture_diff.py time bench/scenes/heart.yaml --base /tmp/base/runtime_c --runs 7

`callgrind` runs the render loop of one scene at 1 thread under valgrind (collecting only inside the render
worker) and prints the instruction count:

    python bench/picture_diff.py callgrind bench/scenes/heart.yaml --runtime runtime_c --width 400 --height 300
"""

from __future__ import annotations

import argparse
import contextlib
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = sorted((ROOT / "bench" / "scenes").glob("*.yaml")) + sorted((ROOT / "examples" / "scenes").glob("*.yaml"))


@contextlib.contextmanager
def runtime_restored():
    """What `_use_runtime` changes, put back on leaving: a caller in a longer process (a test) must not leave
    its compiles pointed at a runtime folder that is gone."""
    import implgen.compile.clib as cbuild
    import implgen.compile.library as library
    import implgen.resources as resources
    import implgen.scene.build as build

    missing = object()
    places = [(build, "runtime_dir"), (resources, "runtime_dir"), (library, "runtime_dir"), (cbuild, "BASE_FLAGS")]
    saved = [getattr(module, name, missing) for module, name in places]
    try:
        yield
    finally:
        for (module, name), value in zip(places, saved):
            if value is missing:
                if hasattr(module, name):
                    delattr(module, name)
            else:
                setattr(module, name, value)


def _use_runtime(runtime: Path) -> None:
    """Compile scenes against `runtime` (a runtime_c folder: its sources and headers) instead of the installed
    package's; with $PICTURE_DIFF_DEBUG set, with -g too (same code, line-level callgrind annotation). The
    source lists are this checkout's (implgen.resources): to compare across a change of the file list, render
    each side from its own checkout."""
    import os

    import implgen.compile.clib as cbuild
    import implgen.compile.library as library
    import implgen.resources as resources
    import implgen.scene.build as build

    runtime = runtime.resolve()
    build.runtime_dir = lambda: runtime  # type: ignore[assignment]
    resources.runtime_dir = lambda: runtime  # type: ignore[assignment]
    # the include folder too: its headers are part of every object's key, so a source file that is the same in
    # both runtimes gets an object of its own for each (else one built against the other runtime's headers)
    library.runtime_dir = lambda: runtime  # type: ignore[assignment]
    if os.environ.get("PICTURE_DIFF_DEBUG") and "-g" not in cbuild.BASE_FLAGS:
        cbuild.BASE_FLAGS = (*cbuild.BASE_FLAGS, "-g")


def _render_one(scene: Path, runtime: Path, width: int | None, height: int | None, threads: int):
    _use_runtime(runtime)
    from implgen.scene.load import load_scene
    from implgen.scene.render import render

    sc = load_scene(scene)
    w = width or max(200, sc.width // 2)
    h = height or max(1, round(w * sc.height / sc.width))
    return render(sc, width=w, height=h, threads=threads)


def cmd_render(args: argparse.Namespace) -> int:
    from implgen.imagefile import write_png

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for scene in SCENES:
        img = _render_one(scene, Path(args.runtime), None, None, args.threads)
        name = f"{scene.parent.parent.name}_{scene.stem}"
        np.save(out / f"{name}.npy", img)
        write_png(img, out / f"{name}.png")
        print(f"{name}: {img.shape[1]}x{img.shape[0]}", flush=True)
    return 0


def cmd_compare(args: argparse.Namespace) -> int:
    from implgen.imagefile import to_uint8

    a_dir, b_dir = Path(args.a), Path(args.b)
    bad = 0
    for fa in sorted(a_dir.glob("*.npy")):
        fb = b_dir / fa.name
        if not fb.exists():
            print(f"{fa.stem}: missing in {b_dir}")
            bad += 1
            continue
        a, b = np.load(fa), np.load(fb)
        if a.shape != b.shape:
            print(f"{fa.stem}: shapes differ {a.shape} {b.shape}")
            bad += 1
            continue
        fdiff = np.any(a != b, axis=2)
        pdiff = np.any(to_uint8(a) != to_uint8(b), axis=2)
        print(f"{fa.stem}: {int(fdiff.sum())} pixels differ (float), {int(pdiff.sum())} (PNG) of {fdiff.size}")
        for y, x in list(zip(*np.nonzero(fdiff)))[: args.show]:
            print(f"    (x={x}, y={y}) {a[y, x].tolist()} -> {b[y, x].tolist()}")
        bad += int(fdiff.any())
    return 1 if bad else 0


def cmd_callgrind(args: argparse.Namespace) -> int:
    scene = Path(args.scene)
    # compile outside valgrind first, so the measured run finds the library in the cache
    _render_one(scene, Path(args.runtime), 8, 6, 1)
    out = Path(args.out or f"/tmp/callgrind.{scene.stem}.out")
    cmd = [
        "valgrind",
        "--tool=callgrind",
        "--toggle-collect=worker",
        f"--callgrind-out-file={out}",
        sys.executable,
        __file__,
        "_render",
        str(scene),
        "--runtime",
        args.runtime,
        "--width",
        str(args.width),
        "--height",
        str(args.height),
    ]
    res = subprocess.run(cmd, capture_output=True, text=True, check=False)
    m = re.search(r"Collected : (\d+)", res.stderr)
    if res.returncode != 0 or not m:
        sys.stderr.write(res.stderr)
        return 1
    print(f"{scene.stem}: {int(m.group(1)):,} instructions ({out})")
    return 0


def cmd_time(args: argparse.Namespace) -> int:
    import statistics

    from implgen.measure.render import _measure
    from implgen.scene.build import build_scene
    from implgen.scene.load import load_scene
    from implgen.scene.tracer import CScene

    size = argparse.Namespace(width=args.width, height=args.height, spp=1)
    for scene in map(Path, args.scenes):
        sides = []
        for runtime in (args.base, args.runtime):
            _use_runtime(Path(runtime))
            sc = load_scene(scene)
            sides.append((CScene(sc, build_scene(sc)), sc))
        seconds: list[list[float]] = [[], []]
        for _ in range(args.runs):
            for k, (cs, sc) in enumerate(sides):
                seconds[k].append(_measure(cs, sc, size, 1)[0])
        base, new = (statistics.median(s) for s in seconds)
        line = f"{scene.stem}: base {base * 1e3:.1f} ms, this {new * 1e3:.1f} ms, this/base {new / base:.3f}"
        print(line, flush=True)
        for cs, _ in sides:
            cs.close()
    return 0


def cmd_inner_render(args: argparse.Namespace) -> int:
    _render_one(Path(args.scene), Path(args.runtime), args.width, args.height, 1)
    return 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render")
    r.add_argument("--runtime", default=str(ROOT / "runtime_c"))
    r.add_argument("--out", required=True)
    r.add_argument("--threads", type=int, default=2)
    r.set_defaults(func=cmd_render)
    c = sub.add_parser("compare")
    c.add_argument("a")
    c.add_argument("b")
    c.add_argument("--show", type=int, default=10)
    c.set_defaults(func=cmd_compare)
    t = sub.add_parser("time")
    t.add_argument("scenes", nargs="+")
    t.add_argument("--base", required=True, help="the runtime_c folder to compare against")
    t.add_argument("--runtime", default=str(ROOT / "runtime_c"))
    t.add_argument("--width", type=int, default=800)
    t.add_argument("--height", type=int, default=600)
    t.add_argument("--runs", type=int, default=7)
    t.set_defaults(func=cmd_time)
    g = sub.add_parser("callgrind")
    g.add_argument("scene")
    g.add_argument("--runtime", default=str(ROOT / "runtime_c"))
    g.add_argument("--width", type=int, default=400)
    g.add_argument("--height", type=int, default=300)
    g.add_argument("--out")
    g.set_defaults(func=cmd_callgrind)
    i = sub.add_parser("_render")
    i.add_argument("scene")
    i.add_argument("--runtime", required=True)
    i.add_argument("--width", type=int)
    i.add_argument("--height", type=int)
    i.set_defaults(func=cmd_inner_render)
    args = p.parse_args()
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
