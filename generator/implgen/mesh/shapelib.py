"""One shape compiled with the runtime (compile/library.py, cached), and its batch entry points
(runtime_c/shape_batch.c) and the mesh's loops (runtime_c/mesh_kernels.c) bound with ctypes: every root of f
along many rays at once, and f with its gradient at many points at once. Each call is one C loop; Python never
loops per ray or per point. With a `budget` (budget.py) the C loop runs in slices (ROWS rays, POINTS points, a
slab of about POINTS grid vertices) and the budget is checked before each: a mesh stops within one slice of its
deadline, or of its stop."""

from __future__ import annotations

import ctypes
from collections.abc import Sequence

import numpy as np

from implgen import abi
from implgen.compile import clib
from implgen.compile.library import ShapeEntry, build_library
from implgen.mesh.budget import Budget
from implgen.spec.model import Spec

MAX_DEGREE = abi.value("IG_MAX_DEGREE")
AUTO = abi.value("IG_ROOTS_AUTO")

_DP = ctypes.POINTER(ctypes.c_double)
_IP = ctypes.POINTER(ctypes.c_int)
_VP = ctypes.c_void_p
_LONG = np.dtype(f"i{ctypes.sizeof(ctypes.c_long)}")  # C's long, as NumPy holds it
ROWS = 4096  # rays a slice


class _MeshSheets(ctypes.Structure):
    """runtime_c/mesh_kernels.h's ig_mesh_sheets, field for field."""

    _fields_ = [
        ("ncells", ctypes.c_long),
        ("corner", _VP),
        ("sheets", _VP),
        ("first", _VP),
        ("strides", _VP),
        ("nvertices", ctypes.c_long),
        ("origin", _VP),
        ("h", ctypes.c_double),
        ("ncross", ctypes.c_long),
        ("keys", _VP),
        ("points", _VP),
        ("normals", _VP),
        ("piece", _VP),
        ("crease", ctypes.c_double),
        ("drop", ctypes.c_double),
        ("nverts", ctypes.c_long),
        ("out", _VP),
        ("mask", _VP),
        ("nearest", _VP),
    ]


POINTS = 1 << 18  # points, grid vertices, cells or quads a slice


def _ptr(a: np.ndarray):
    return a.ctypes.data_as(_DP)


class ShapeLib:
    """The compiled shape `spec` with these param values (in the spec's order)."""

    def __init__(self, spec: Spec, params: Sequence[float]):
        path, _ = build_library([ShapeEntry(spec=spec, c_name=spec.name, folded=False)])
        lib = clib.load(path)
        lib.rt_scene_shape.restype = _VP
        lib.rt_scene_shape.argtypes = [ctypes.c_int]
        lib.ig_shape_roots_many.restype = None
        lib.ig_shape_roots_many.argtypes = [_VP, _DP, ctypes.c_long, _DP, _DP, _DP, _DP, ctypes.c_int, _DP, _IP]
        lib.ig_shape_eval_many.restype = None
        lib.ig_shape_eval_many.argtypes = [_VP, _DP, ctypes.c_long, _DP, _DP, _DP]
        lib.ig_shape_values_grid.restype = None
        lib.ig_shape_values_grid.argtypes = [_VP, _DP, _DP, ctypes.c_long, _DP, ctypes.c_long, _DP, ctypes.c_long, _DP]
        lib.ig_shape_project_many.restype = None
        lib.ig_shape_project_many.argtypes = [_VP, _DP, ctypes.c_long, _DP, ctypes.c_int, ctypes.c_double,
                                              ctypes.c_double, ctypes.c_double, _VP]  # fmt: skip
        lib.ig_mesh_sheet_points.restype = None
        lib.ig_mesh_sheet_points.argtypes = [ctypes.POINTER(_MeshSheets)]
        lib.ig_mesh_split_quads.restype = None
        lib.ig_mesh_split_quads.argtypes = [ctypes.c_long, _VP, _VP, _DP, _VP]
        self._lib = lib
        self._shape = lib.rt_scene_shape(0)
        self._params = np.ascontiguousarray(np.asarray(list(params) or [0.0], dtype=np.float64))
        self.budget: Budget | None = None  # checked before each slice of a batch call

    def check(self) -> None:
        """The budget's check, when there is one (between the phases of the contour)."""
        if self.budget is not None:
            self.budget.check()

    def _slices(self, n: int, size: int):
        """[(start, stop)] covering range(n): one slice without a budget, else slices of `size`, the budget
        checked before each."""
        if self.budget is None:
            yield 0, n
            return
        for start in range(0, n, max(1, size)):
            self.budget.check()
            yield start, min(n, start + size)

    def roots(self, o: np.ndarray, d: np.ndarray, tmin: np.ndarray, tmax: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """All distinct roots in [tmin, tmax] of each ray o + t d: (roots (n, IG_MAX_DEGREE), NaN past each
        count; counts (n,))."""
        o = np.ascontiguousarray(o, dtype=np.float64).reshape(-1, 3)
        n = o.shape[0]
        d = np.ascontiguousarray(np.broadcast_to(np.asarray(d, dtype=np.float64), (n, 3)))
        t0 = np.ascontiguousarray(np.broadcast_to(np.asarray(tmin, dtype=np.float64), (n,)))
        t1 = np.ascontiguousarray(np.broadcast_to(np.asarray(tmax, dtype=np.float64), (n,)))
        out = np.full((n, MAX_DEGREE), np.nan)
        counts = np.zeros(n, dtype=np.intc)
        for a, b in self._slices(n, ROWS):  # rows of C-ordered arrays: each slice is contiguous
            self._lib.ig_shape_roots_many(
                self._shape, _ptr(self._params), b - a, _ptr(o[a:b]), _ptr(d[a:b]), _ptr(t0[a:b]), _ptr(t1[a:b]),
                AUTO, _ptr(out[a:b]), counts[a:b].ctypes.data_as(_IP),
            )  # fmt: skip
        out[np.arange(MAX_DEGREE)[None, :] >= counts[:, None]] = np.nan
        return out, counts

    def value(self, p: np.ndarray) -> np.ndarray:
        """f at each point (p: (..., 3)), shape p.shape[:-1]."""
        p = np.ascontiguousarray(p, dtype=np.float64)
        f = np.empty(p.shape[:-1])
        pf, ff = p.reshape(-1, 3), f.reshape(-1)
        for a, b in self._slices(ff.size, POINTS):
            self._lib.ig_shape_eval_many(self._shape, _ptr(self._params), b - a, _ptr(pf[a:b]), _ptr(ff[a:b]), None)
        return f

    def value_gradient(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(f, grad f) at each point (p: (..., 3))."""
        p = np.ascontiguousarray(p, dtype=np.float64)
        f = np.empty(p.shape[:-1])
        g = np.empty(p.shape)
        pf, ff, gf = p.reshape(-1, 3), f.reshape(-1), g.reshape(-1, 3)
        for a, b in self._slices(ff.size, POINTS):
            self._lib.ig_shape_eval_many(
                self._shape, _ptr(self._params), b - a, _ptr(pf[a:b]), _ptr(ff[a:b]), _ptr(gf[a:b])
            )
        return f, g

    def gradient_jacobian(self, p: np.ndarray, eps: float) -> np.ndarray:
        """The Jacobian of grad f at each point (p: (n, 3)) by central differences of step `eps`: (n, 3, 3),
        column k the change of the gradient along axis k (f's Hessian, up to the differences' error)."""
        jac = np.empty((len(p), 3, 3))
        for k in range(3):
            dp = np.zeros(3)
            dp[k] = eps
            _, gp = self.value_gradient(p + dp)
            _, gm = self.value_gradient(p - dp)
            jac[:, :, k] = (gp - gm) / (2 * eps)
        return jac

    def values_grid(self, x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """f at every (x[i], y[j], z[k]), shape (len(x), len(y), len(z))."""
        x, y, z = (np.ascontiguousarray(v, dtype=np.float64) for v in (x, y, z))
        f = np.empty((x.size, y.size, z.size))
        for a, b in self._slices(x.size, POINTS // max(1, y.size * z.size)):  # slabs of x: contiguous in f
            self._lib.ig_shape_values_grid(
                self._shape, _ptr(self._params), _ptr(x[a:b]), b - a, _ptr(y), y.size, _ptr(z), z.size, _ptr(f[a:b])
            )
        return f

    def project(
        self, p: np.ndarray, steps: int, tol: float, noise: float, reach: float
    ) -> tuple[np.ndarray, np.ndarray]:
        """Each point moved onto f = 0 by at most `steps` Newton steps of least norm: (points, converged flags);
        converged: a step at most `tol`, or at most `noise` and no longer halving (f's rounding), or a last step
        at most `noise`, and moved at most `reach` along each axis (ig_shape_project_many)."""
        out = np.array(p, dtype=np.float64, order="C").reshape(-1, 3)
        ok = np.zeros(len(out), dtype=np.uint8)
        for a, b in self._slices(len(out), POINTS):
            self._lib.ig_shape_project_many(
                self._shape, _ptr(self._params), b - a, _ptr(out[a:b]), steps, tol, noise, reach, ok[a:b].ctypes.data
            )
        return out, ok.astype(bool)

    def sheet_points(self, corner, sheets, first, strides, nvertices: int, keys, points, normals, piece, origin,
                     h: float, crease: float, drop: float, nverts: int):  # fmt: skip
        """The dual vertex of every sheet of every active cell (ig_mesh_sheet_points, runtime_c/mesh_kernels.h):
        (points (nverts, 3), piece masks, index of the nearest crossing). Not f's: the shape's library holds it."""

        def longs(a):
            return np.ascontiguousarray(a, dtype=_LONG)

        corner, first, strides, keys = longs(corner), longs(first), longs(strides), longs(keys)
        sheets = np.ascontiguousarray(sheets, dtype=np.int8)
        points, normals, origin = (np.ascontiguousarray(a, dtype=np.float64) for a in (points, normals, origin))
        piece = np.ascontiguousarray(piece, dtype=np.intc)
        n, m = len(corner), len(keys)  # what the C reads: every shape checked, and the keys ascending
        if not (
            corner.shape == first.shape == (n,)
            and sheets.shape == (n, 12)
            and strides.shape == origin.shape == (3,)
            and points.shape == normals.shape == (m, 3)
            and piece.shape == (m,)
            and bool(np.all(keys[1:] >= keys[:-1]))
        ):
            raise ValueError("sheet_points: array shapes disagree, or the crossing keys are not ascending")
        out = np.zeros((nverts, 3))
        mask = np.zeros(nverts, dtype=_LONG)
        nearest = np.full(nverts, -1, dtype=_LONG)
        args = _MeshSheets(
            strides=strides.ctypes.data, nvertices=nvertices, origin=origin.ctypes.data, h=h, ncross=len(keys),
            keys=keys.ctypes.data, points=points.ctypes.data, normals=normals.ctypes.data, piece=piece.ctypes.data,
            crease=crease, drop=drop, nverts=nverts, out=out.ctypes.data, mask=mask.ctypes.data,
            nearest=nearest.ctypes.data,
        )  # fmt: skip
        for a, b in self._slices(len(corner), POINTS):  # each cell writes its own vertices (first[c] + sheet)
            args.ncells = b - a
            args.corner, args.sheets = corner[a:b].ctypes.data, sheets[a:b].ctypes.data
            args.first = first[a:b].ctypes.data
            self._lib.ig_mesh_sheet_points(ctypes.byref(args))
        return out, mask.astype(np.int64), nearest.astype(np.int64)

    def split_quads(self, quads: np.ndarray, flip: np.ndarray, verts: np.ndarray) -> np.ndarray:
        """Quads (m, 4) into triangles (2 m, 3) on their shorter diagonals, reversed where flip
        (ig_mesh_split_quads)."""
        quads = np.ascontiguousarray(quads, dtype=_LONG).reshape(-1, 4)
        flip = np.ascontiguousarray(flip, dtype=np.uint8)
        verts = np.ascontiguousarray(verts, dtype=np.float64)
        if len(flip) != len(quads) or (quads.size and not 0 <= quads.min() <= quads.max() < len(verts)):
            raise ValueError("split_quads: quads and flags disagree, or a vertex id is out of range")
        m = len(quads)
        tris = np.empty((2 * m, 3), dtype=_LONG)
        for a, b in self._slices(m, POINTS):  # a slice's first triangles, then its second: placed as in one call
            part = tris if b - a == m else np.empty((2 * (b - a), 3), dtype=_LONG)
            self._lib.ig_mesh_split_quads(
                b - a, quads[a:b].ctypes.data, flip[a:b].ctypes.data, _ptr(verts), part.ctypes.data
            )
            if part is not tris:
                tris[a:b], tris[m + a : m + b] = part[: b - a], part[b - a :]
        return tris.astype(np.int64, copy=False)
