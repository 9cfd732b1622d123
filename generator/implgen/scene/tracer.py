"""The C tracer through ctypes: its signatures (tracer.h), and a committed scene to render or query.

`CScene(scene, built)` hands a validated scene model to a scene library built by scene/build.py: materials,
leaves with their params and matrices, CSG nodes, lights, camera. Struct layouts and enum values come from
the headers (implgen.abi), never from numbers copied here.
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence

import numpy as np

from implgen import abi
from implgen.compile import clib
from implgen.scene.build import BuildResult, leaf_params
from implgen.scene.model import Leaf, Material, Node, Scene

OPS = {
    "union": abi.value("RT_UNION"),
    "intersection": abi.value("RT_INTERSECTION"),
    "difference": abi.value("RT_DIFFERENCE"),
}
CLIPS = {"sphere": abi.value("RT_CLIP_SPHERE"), "box": abi.value("RT_CLIP_BOX")}

_d = ctypes.c_double
_pd = ctypes.POINTER(ctypes.c_double)


RtHit = abi.ctypes_struct("rt_hit")  # t, p, n, err, po, no, object, leaf, face, material, entering, singular


def bind(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Declare the tracer's C signatures (tracer.h) on a loaded scene library."""
    vp = ctypes.c_void_p
    sig = {
        "rt_scene_new": (vp, []),
        "rt_scene_free": (None, [vp]),
        "rt_scene_add_material": (ctypes.c_int, [vp, _pd]),
        "rt_scene_add_leaf": (ctypes.c_int, [vp, vp, _pd, ctypes.c_int, _pd, ctypes.c_int]),
        "rt_scene_add_csg": (ctypes.c_int, [vp, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int]),
        "rt_scene_add_object": (ctypes.c_int, [vp, ctypes.c_int]),
        "rt_scene_set_clip": (ctypes.c_int, [vp, ctypes.c_int, ctypes.c_int, _pd, _d]),
        "rt_scene_add_light": (ctypes.c_int, [vp, _pd, _pd]),
        "rt_scene_set_camera": (None, [vp, _pd, _pd, _pd, _d]),
        "rt_scene_set_background": (None, [vp, _pd]),
        "rt_scene_commit": (ctypes.c_int, [vp]),
        "rt_scene_error": (ctypes.c_char_p, [vp]),
        "rt_scene_shape": (vp, [ctypes.c_int]),
        "rt_scene_nshapes": (ctypes.c_int, []),
        "rt_render_new": (
            vp,
            [vp, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_int, ctypes.c_ulong],
        ),
        "rt_render_free": (None, [vp]),
        "rt_render_set_rows": (ctypes.c_int, [vp, ctypes.c_int, ctypes.c_int]),
        "rt_render_set_pass": (ctypes.c_int, [vp, ctypes.c_int, ctypes.c_int, ctypes.c_int, _pd]),
        "rt_render_run": (ctypes.c_int, [vp, ctypes.POINTER(ctypes.c_float)]),
        "rt_render_progress": (ctypes.c_int, [vp]),
        "rt_render_cancel": (None, [vp]),
        "rt_render_stats": (None, [vp, _pd]),
        "rt_render_certify": (ctypes.c_int, [vp, ctypes.POINTER(ctypes.c_uint8), ctypes.POINTER(ctypes.c_int)]),
        "rt_certify_ray": (ctypes.c_int, [vp, _pd, _pd, ctypes.POINTER(ctypes.c_int)]),
        "rt_certify_reason": (ctypes.c_char_p, [ctypes.c_int]),
        "rt_trace_ray": (None, [vp, _pd, _pd, ctypes.c_int, _pd, _pd]),
        "rt_scene_intersect": (ctypes.c_int, [vp, _pd, _pd, _d, _d, ctypes.POINTER(RtHit)]),
        "rt_spawn_origin": (None, [ctypes.POINTER(RtHit), _pd, _pd]),
    }
    for name, (res, args) in sig.items():
        fn = getattr(lib, name)
        fn.restype = res
        fn.argtypes = args
    return lib


def load_bound(built: BuildResult) -> ctypes.CDLL:
    """The scene library of `built`, checked against its seal, loaded and bound: what a CScene renders with.
    Many scenes may share one (the frames of an animation: CScene's `lib`)."""
    return bind(clib.load(built.library))


def darr(values) -> ctypes.Array:
    vals = [float(v) for v in values]
    return (ctypes.c_double * max(1, len(vals)))(*vals)


class CScene:
    """A committed rt_scene in a loaded scene library; freed with the object. `lib`: that library as
    `load_bound(built)` gave it, when the caller has it already (else it is loaded and checked here)."""

    def __init__(self, scene: Scene, built: BuildResult, lib: ctypes.CDLL | None = None):
        self.lib = lib if lib is not None else load_bound(built)
        self.ptr = self.lib.rt_scene_new()
        if not self.ptr:
            raise MemoryError("rt_scene_new failed")
        self._materials: dict[int, int] = {}
        self._built = built
        self.leaf_nodes: dict[int, Leaf] = {}  # C node index -> the leaf it was made from (RtHit.leaf)
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
            self._materials[id(m)] = self._check(
                self.lib.rt_scene_add_material(self.ptr, darr(m.packed())), "a material"
            )
        return self._materials[id(m)]

    def _node(self, n: Node, inherited: Material) -> int:
        if isinstance(n, Leaf):
            entry_i = self._built.leaf_index[id(n)]
            entry = self._built.entries[entry_i]
            shape = self.lib.rt_scene_shape(entry_i)
            params = leaf_params(entry, n)
            mat = self._material(n.material or inherited)
            k = self._check(
                self.lib.rt_scene_add_leaf(self.ptr, shape, darr(params), len(params), darr(n.matrix.reshape(-1)), mat),
                n.where,
            )
            if n.clip is not None:
                c = n.clip
                self._check(self.lib.rt_scene_set_clip(self.ptr, k, CLIPS[c.kind], darr(c.center), c.size), n.where)
            self.leaf_nodes[k] = n
            return k
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

    def intersect(self, o: Sequence[float], d: Sequence[float], tmin: float = 0.0, tmax: float = float("inf")):
        """The closest hit as an RtHit (t, p, n, err, object, leaf, face, entering, ...), or None."""
        hit = RtHit()
        if self.lib.rt_scene_intersect(self.ptr, darr(o), darr(d), tmin, tmax, ctypes.byref(hit)):
            return hit
        return None

    def certify(self, o: Sequence[float], d: Sequence[float]) -> tuple[int, int]:
        """The certificate of one ray o + t d, t > 0 (runtime_c/certify.h): (code, object; -1 for none)."""
        obj = ctypes.c_int(-1)
        code = self.lib.rt_certify_ray(self.ptr, darr(o), darr(d), ctypes.byref(obj))
        return code, obj.value

    def close(self) -> None:
        if getattr(self, "ptr", None):
            self.lib.rt_scene_free(self.ptr)
            self.ptr = None

    def __del__(self) -> None:
        self.close()
