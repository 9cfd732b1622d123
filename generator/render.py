"""`implgen render SCENE.yaml -o OUT.png [--width W --height H --spp N --threads T]` and `render(scene)`.

The scene is validated (scene.py), its shapes generated and compiled into a cached library (build.py), the
scene handed to the C tracer through ctypes, and the image rendered on all cores: the C code runs on its own
pthreads while Python, with the GIL released by ctypes, polls a progress counter for the progress bar.
"""

from __future__ import annotations

import argparse
import ctypes
import os
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from . import cbuild, validate
from .build import BuildResult, bind, build_scene, darr, leaf_params
from .errors import UserError
from .outputs import atomic_write, check_output_file
from .scene import MAX_DEPTH, MAX_SIZE, MAX_SPP, Csg, Leaf, Material, Node, Scene, load_scene, parse_scene

OPS = {"union": 1, "intersection": 2, "difference": 3}
RAY_KINDS = ("primary", "shadow", "secondary")
MAX_THREADS = 1024
DEFAULT_FOLD = False   # folding constant params into the code: measured (README.md, "Rendering scenes"), within +-4%: off


@dataclass
class RenderInfo:
    """What a render did, for the CLI's summary line and for bench_render."""
    seconds: float = 0.0
    rays: dict[str, float] = field(default_factory=dict)
    library: Path | None = None
    threads: int = 1
    nonfinite: int = 0       # samples that came out NaN/inf (rendered as 0); should always be 0


class CScene:
    """A committed rt_scene in a loaded scene library; freed with the object."""

    def __init__(self, scene: Scene, built: BuildResult):
        self.lib = bind(cbuild.load(built.library))
        self.ptr = self.lib.rt_scene_new()
        if not self.ptr:
            raise MemoryError("rt_scene_new failed")
        self._materials: dict[int, int] = {}
        self._built = built
        try:
            self._fill(scene)
        except BaseException:
            self.close()
            raise

    def _check(self, k: int, what: str) -> int:
        if k < 0:
            msg = self.lib.rt_scene_error(self.ptr).decode()
            raise RuntimeError(f"tracer rejected {what}: {msg}")
        return k

    def _material(self, m: Material) -> int:
        if id(m) not in self._materials:
            self._materials[id(m)] = self._check(self.lib.rt_scene_add_material(self.ptr, darr(m.packed())),
                                                 "a material")
        return self._materials[id(m)]

    def _node(self, n: Node, inherited: Material) -> int:
        if isinstance(n, Leaf):
            entry_i = self._built.leaf_index[id(n)]
            entry = self._built.entries[entry_i]
            shape = self.lib.rt_scene_shape(entry_i)
            params = leaf_params(entry, n)
            mat = self._material(n.material or inherited)
            return self._check(self.lib.rt_scene_add_leaf(self.ptr, shape, darr(params), len(params),
                                                          darr(n.matrix.reshape(-1)), mat), n.where)
        mat = n.material or inherited
        left = self._node(n.left, mat)
        right = self._node(n.right, mat)
        return self._check(self.lib.rt_scene_add_csg(self.ptr, OPS[n.op], left, right, -1), n.where)

    def _fill(self, scene: Scene) -> None:
        default = Material()
        for obj in scene.objects:
            self._check(self.lib.rt_scene_add_object(self.ptr, self._node(obj, default)), "an object")
        for light in scene.lights:
            self._check(self.lib.rt_scene_add_light(self.ptr, darr(light.position), darr(light.color)), "a light")
        cam = scene.camera
        self.lib.rt_scene_set_camera(self.ptr, darr(cam.position), darr(cam.look_at), darr(cam.up), cam.fov)
        self.lib.rt_scene_set_background(self.ptr, darr(scene.background))
        self._check(self.lib.rt_scene_commit(self.ptr), "the scene")

    def trace(self, o: Sequence[float], d: Sequence[float], max_depth: int = 8) -> np.ndarray:
        """Colour along one ray (for tests and exploration)."""
        rgb = (ctypes.c_double * 3)()
        self.lib.rt_trace_ray(self.ptr, darr(o), darr(d), max_depth, rgb, None)
        return np.array(rgb[:])

    def intersect(self, o: Sequence[float], d: Sequence[float], tmin: float = 0.0,
                  tmax: float = float("inf")):
        """The closest hit as a build.RtHit (t, p, n, err, object, leaf, face, entering, ...), or None."""
        from .build import RtHit

        hit = RtHit()
        if self.lib.rt_scene_intersect(self.ptr, darr(o), darr(d), tmin, tmax, ctypes.byref(hit)):
            return hit
        return None

    def spawn(self, hit, d: Sequence[float]) -> list[float]:
        """Origin of a secondary ray leaving `hit` in direction d (offset by the hit's error bound)."""
        out = (ctypes.c_double * 3)()
        self.lib.rt_spawn_origin(ctypes.byref(hit), darr(d), out)
        return list(out)

    def close(self) -> None:
        if getattr(self, "ptr", None):
            self.lib.rt_scene_free(self.ptr)
            self.ptr = None

    def __del__(self) -> None:
        self.close()


def _as_scene(scene: Scene | str | Path | dict) -> Scene:
    if isinstance(scene, Scene):
        return scene
    if isinstance(scene, dict):
        return parse_scene(scene, "<scene>")
    return load_scene(scene)


def render(scene: Scene | str | Path | dict, *, width: int | None = None, height: int | None = None,
           spp: int | None = None, threads: int | None = None, max_depth: int | None = None, seed: int = 0,
           progress: bool = False, fold: bool = DEFAULT_FOLD, info: RenderInfo | None = None) -> np.ndarray:
    """Render a scene (a Scene, a scene file path, or a scene mapping) to a float32 array (height, width, 3),
    row 0 at the top, colours linear and not clamped. Options override the scene's `image` settings."""
    sc = _as_scene(scene)
    w = width or sc.width
    h = height or sc.height
    n = spp or sc.spp
    depth = sc.max_depth if max_depth is None else max_depth
    nthreads = threads or os.cpu_count() or 1
    for option, v, lo, hi in (("--width", w, 1, MAX_SIZE), ("--height", h, 1, MAX_SIZE), ("--spp", n, 1, MAX_SPP),
                              ("--threads", nthreads, 1, MAX_THREADS), ("--max-depth", depth, 0, MAX_DEPTH)):
        validate.whole(option, "", v, lo, hi)
    built = build_scene(sc, fold=fold)
    cs = CScene(sc, built)
    try:
        ctx = cs.lib.rt_render_new(cs.ptr, w, h, n, depth, nthreads, seed)
        if not ctx:
            raise RuntimeError("rt_render_new failed")
        out = np.zeros((h, w, 3), dtype=np.float32)
        result: dict[str, int] = {}
        ptr = out.ctypes.data_as(ctypes.POINTER(ctypes.c_float))

        ends: list[float] = []

        def work() -> None:
            result["code"] = cs.lib.rt_render_run(ctx, ptr)
            ends.append(time.perf_counter())  # here, not after the polling loop: that wakes every 0.1 s

        t0 = time.perf_counter()
        worker = threading.Thread(target=work, name="implgen-render", daemon=True)
        worker.start()
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=h, unit="row", desc=Path(sc.source).name, leave=True)
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


def to_uint8(img: np.ndarray) -> np.ndarray:
    return (np.clip(np.nan_to_num(img, nan=0.0), 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def write_png(img: np.ndarray, path: Path) -> None:
    """Write atomically (outputs.atomic_write): a failure leaves nothing half-written."""
    from PIL import Image

    picture = Image.fromarray(to_uint8(img), mode="RGB")
    atomic_write(Path(path), lambda fh: picture.save(fh, format="PNG"))


def _positive(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if v < 1:
        raise argparse.ArgumentTypeError(f"{v} must be at least 1")
    return v


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> Any:  # one line, exit 2, through UserError like every bad input
        raise UserError("render", message)


def main(argv: Sequence[str]) -> int:
    ap = _Parser(prog="implgen render", description="Render a scene file to a PNG.")
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
    img = render(scene, width=args.width, height=args.height, spp=args.spp, threads=args.threads,
                 max_depth=args.max_depth, progress=not args.quiet, fold=args.fold or DEFAULT_FOLD, info=info)
    write_png(img, args.output)
    total = sum(info.rays.values())
    print(f"implgen: wrote {args.output} ({img.shape[1]}x{img.shape[0]}, {info.seconds:.3f} s on "
          f"{info.threads} threads, {total / max(info.seconds, 1e-9) / 1e6:.2f} Mrays/s)")
    return 0
