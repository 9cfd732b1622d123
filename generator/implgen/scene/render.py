"""`render(scene)`: a scene to a float image (imagefile.py writes it as PNG).

The scene is validated (scene/load.py), its shapes generated and compiled into a cached library (build.py), the
scene handed to the C tracer through ctypes, and the image rendered on all cores: the C code runs on its own
pthreads while Python, with the GIL released by ctypes, polls a progress counter for the progress bar.
"""

from __future__ import annotations

import ctypes
import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from implgen import validate
from implgen.scene.build import BuildResult, build_scene
from implgen.scene.load import MAX_DEPTH, MAX_SIZE, MAX_SPP, load_scene, parse_scene
from implgen.scene.model import Scene
from implgen.scene.tracer import CScene

RAY_KINDS = ("primary", "shadow", "secondary")  # the first three stats slots (RT_RAYS_*)
MAX_THREADS = 1024
# The render options a caller may set, as the command line names them, each with its range: render() and
# `implgen render` (animation/command.py) check them through check_options, so both say the same.
OPTION_RANGES = (
    ("width", "--width", 1, MAX_SIZE),
    ("height", "--height", 1, MAX_SIZE),
    ("spp", "--spp", 1, MAX_SPP),
    ("threads", "--threads", 1, MAX_THREADS),
    ("max_depth", "--max-depth", 0, MAX_DEPTH),
)
# Folding constant params into the generated code measured within a few per cent either way
# (docs/tracer.md#folding-constant-params): off.
DEFAULT_FOLD = False


@dataclass
class RenderInfo:
    """What a render did, for the CLI's summary line and for bench_render."""

    seconds: float = 0.0
    rays: dict[str, float] = field(default_factory=dict)
    library: Path | None = None
    threads: int = 1
    nonfinite: int = 0  # samples that came out NaN/inf (rendered as 0); should always be 0


def usable_cores() -> int:
    """The cores this process may run on (a container or `taskset` may allow fewer than the machine has):
    the default thread count, and the count at which the tracer keeps each thread on its own core."""
    try:
        return len(os.sched_getaffinity(0)) or 1
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def check_options(
    *,
    width: int | None = None,
    height: int | None = None,
    spp: int | None = None,
    threads: int | None = None,
    max_depth: int | None = None,
) -> None:
    """Each option given (None: not set) in its range (OPTION_RANGES), in the table's order; a UserError
    names the option."""
    given = {"width": width, "height": height, "spp": spp, "threads": threads, "max_depth": max_depth}
    for name, option, lo, hi in OPTION_RANGES:
        if given[name] is not None:
            validate.whole(option, "", given[name], lo, hi)


def _as_scene(scene: Scene | str | Path | dict) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return parse_scene(scene, "<scene>")
    return load_scene(scene)


def render(
    scene: Scene | str | Path | dict,
    *,
    width: int | None = None,
    height: int | None = None,
    spp: int | None = None,
    threads: int | None = None,
    max_depth: int | None = None,
    seed: int = 0,
    progress: bool = False,
    fold: bool = DEFAULT_FOLD,
    info: RenderInfo | None = None,
    built: BuildResult | None = None,
    rows: tuple[int, int] | None = None,
) -> np.ndarray:
    """Render a scene (a Scene, a scene file path, or a scene mapping) to a float32 array (height, width, 3),
    row 0 at the top, colours linear and not clamped. Options override the scene's `image` settings. `built`:
    the scene library when the caller has it already (the frames of one animation share one). `rows`: only
    the band of rows [y0, y1) of the image (a tile), exactly as those rows of the whole image."""
    sc = _as_scene(scene)
    w = width or sc.width
    h = height or sc.height
    n = spp or sc.spp
    depth = sc.max_depth if max_depth is None else max_depth
    nthreads = threads or usable_cores()
    check_options(width=w, height=h, spp=n, threads=nthreads, max_depth=depth)
    y0, y1 = (0, h) if rows is None else rows
    if not 0 <= y0 < y1 <= h:
        raise ValueError(f"rows {rows} outside the image's {h} rows")
    if built is None:
        built = build_scene(sc, fold=fold)
    cs = CScene(sc, built)
    try:
        ctx = cs.lib.rt_render_new(cs.ptr, w, h, n, depth, nthreads, seed)
        if not ctx:
            raise RuntimeError("rt_render_new failed")
        if rows is not None and cs.lib.rt_render_set_rows(ctx, y0, y1) != 0:
            cs.lib.rt_render_free(ctx)
            raise RuntimeError("rt_render_set_rows failed")
        out = np.zeros((y1 - y0, w, 3), dtype=np.float32)
        result: dict[str, int] = {}
        ptr = out.ctypes.data_as(ctypes.POINTER(ctypes.c_float))

        ends: list[float] = []

        def work() -> None:
            result["code"] = cs.lib.rt_render_run(ctx, ptr)
            ends.append(time.perf_counter())  # here, not after the polling loop: that wakes every 0.1 s

        bar = None
        if progress:  # imported and drawn before the render starts: not beside it, competing for a core
            from tqdm import tqdm

            bar = tqdm(total=y1 - y0, unit="row", desc=Path(sc.source).name, leave=True)
        t0 = time.perf_counter()
        worker = threading.Thread(target=work, name="implgen-render", daemon=True)
        worker.start()
        try:
            done = 0
            while True:
                worker.join(0.1)
                if bar is not None:
                    now = cs.lib.rt_render_progress(ctx)
                    bar.update(now - done)
                    done = now
                if not worker.is_alive():
                    break
        except KeyboardInterrupt:
            cs.lib.rt_render_cancel(ctx)
            worker.join()
            raise
        finally:
            if bar is not None:
                bar.close()
        seconds = (ends[0] if ends else time.perf_counter()) - t0
        if result.get("code", -1) != 0:
            raise RuntimeError(f"render failed (code {result.get('code')})")
        stats = (ctypes.c_double * 4)()
        cs.lib.rt_render_stats(ctx, stats)
        cs.lib.rt_render_free(ctx)
        if info is not None:
            info.seconds = seconds
            info.rays = dict(zip(RAY_KINDS, stats[:3]))
            info.nonfinite = int(stats[3])
            info.library = built.library
            info.threads = nthreads
        return out
    finally:
        cs.close()
