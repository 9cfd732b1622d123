"""`render(scene)`: a scene to a float image (imagefile.py writes it as PNG).

The steps: the options over the scene's image settings, checked (`_settings`, one table of ranges for this
and `implgen render`); the shapes generated and compiled into a cached library (build.py); the scene handed to
the C tracer through ctypes (tracer.py); the image rendered on all cores in one render context (renderjob.py):
the C code runs on its own pthreads while Python, with the GIL released by ctypes, polls the progress counter
for the progress bar (`_run_polled`); what the render did, recorded (`_record`).
"""

from __future__ import annotations

import dataclasses
import os
import threading
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from implgen import validate
from implgen.scene.build import BuildResult, build_scene
from implgen.scene.certify import Certificate, object_names, reason_names
from implgen.scene.load import MAX_DEPTH, MAX_SIZE, MAX_SPP, load_scene, parse_scene
from implgen.scene.model import Scene
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene

MAX_THREADS = 1024
# The render options a caller may set, as the command line names them, each with its range: render() and
# `implgen render` (animation/command.py) resolve and check them through image_options, so both say the same.
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


@dataclass(frozen=True)
class ImageOptions:
    """The image one render makes: the scene's `image` settings with the caller's options over them."""

    width: int
    height: int
    spp: int
    max_depth: int
    threads: int | None  # None: every usable core of the machine that renders


def image_options(
    sc: Scene,
    *,
    width: int | None = None,
    height: int | None = None,
    spp: int | None = None,
    max_depth: int | None = None,
    threads: int | None = None,
) -> ImageOptions:
    """The one place where an option given (not None; for a size, spp or threads not 0) wins over the scene's
    own setting, and where the result is checked in the options' ranges (OPTION_RANGES): render(), `implgen
    render` and `implgen bench render` all come here."""
    opts = ImageOptions(
        width=width or sc.width,
        height=height or sc.height,
        spp=spp or sc.spp,
        max_depth=sc.max_depth if max_depth is None else max_depth,
        threads=threads or None,
    )
    check_options(**dataclasses.asdict(opts))
    return opts


def _as_scene(scene: Scene | str | Path | dict) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return parse_scene(scene, "<scene>")
    return load_scene(scene)


@dataclass(frozen=True)
class _Settings:
    """What one render() call renders: the scene's image settings with the options over them, checked."""

    width: int
    height: int
    spp: int
    max_depth: int
    threads: int
    seed: int
    rows: tuple[int, int] | None  # None: the whole image


def _settings(sc: Scene, width, height, spp, threads, max_depth, seed, rows) -> _Settings:
    o = image_options(sc, width=width, height=height, spp=spp, max_depth=max_depth, threads=threads)
    s = _Settings(o.width, o.height, o.spp, o.max_depth, o.threads or usable_cores(), seed=seed, rows=rows)
    y0, y1 = (0, s.height) if rows is None else rows
    if not 0 <= y0 < y1 <= s.height:
        raise ValueError(f"rows {rows} outside the image's {s.height} rows")
    return s


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
    certify: bool = False,
) -> np.ndarray | tuple[np.ndarray, Certificate]:
    """Render a scene (a Scene, a scene file path, or a scene mapping) to a float32 array (height, width, 3),
    row 0 at the top, colours linear and not clamped. Options override the scene's `image` settings. `built`:
    the scene library when the caller has it already (the frames of one animation share one). `rows`: only
    the band of rows [y0, y1) of the image (a tile), exactly as those rows of the whole image. `certify`: also
    the certify pass over the same primary rays (docs/certify.md), returned as (image, Certificate)."""
    sc = _as_scene(scene)
    s = _settings(sc, width, height, spp, threads, max_depth, seed, rows)
    if built is None:
        built = build_scene(sc, fold=fold)
    cs = CScene(sc, built)
    try:
        with RenderJob(cs, s.width, s.height, s.spp, s.max_depth, s.threads, s.seed, rows=s.rows) as job:
            bar = _progress_bar(job, Path(sc.source).name) if progress else None
            try:
                img = _run_polled(job, bar)
            finally:
                if bar is not None:
                    bar.close()
            if info is not None:
                _record(info, job, built, s.threads)
            if certify:
                codes, objects = job.certify()
                names = object_names(sc)
                return img, Certificate(codes, objects, reason_names(cs.lib), names, job.certify_seconds)
            return img
    finally:
        cs.close()


def _progress_bar(job: RenderJob, name: str):
    """A bar over the job's rows, imported and drawn before the render starts: not beside it, competing for
    a core."""
    from tqdm import tqdm

    y0, y1 = job.rows
    return tqdm(total=y1 - y0, unit="row", desc=name, leave=True)


def _run_polled(job: RenderJob, bar) -> np.ndarray:
    """job.run() on a worker thread while this one wakes every 0.1 s to move the bar; Ctrl-C cancels the
    render (the C threads stop after their current row) and is raised again once they have."""
    outcome: dict = {}

    def work() -> None:
        try:
            outcome["image"] = job.run()
        except BaseException as err:  # raised again in the caller's thread
            outcome["error"] = err

    worker = threading.Thread(target=work, name="implgen-render", daemon=True)
    worker.start()
    try:
        done = 0
        while True:
            worker.join(0.1)
            if bar is not None:
                now = job.progress()
                bar.update(now - done)
                done = now
            if not worker.is_alive():
                break
    except KeyboardInterrupt:
        job.cancel()
        worker.join()
        raise
    if "error" in outcome:
        raise outcome["error"]
    if outcome["image"] is None:
        raise RuntimeError("render failed (cancelled)")
    return outcome["image"]


def _record(info: RenderInfo, job: RenderJob, built: BuildResult, threads: int) -> None:
    stats = job.stats()
    info.seconds = job.seconds
    info.rays = stats.rays
    info.nonfinite = stats.nonfinite
    info.library = built.library
    info.threads = threads
