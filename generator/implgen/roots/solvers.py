"""Real roots of polynomials through the C solvers of the runtime (`runtime_c/roots*.c`).

    real_roots(coeffs, lo=-inf, hi=inf, method="auto") -> sorted np.ndarray
    real_roots_batch(coeffs_2d, lo, hi, method) -> (roots padded with NaN, counts)
    first_root(coeffs, lo=-inf, hi=inf, method="auto") -> the smallest root in [lo, hi], or None
    first_root_batch(coeffs_2d, lo, hi, method) -> (roots, NaN where none; counts 0/1)

Coefficients are lowest power first. The C library is compiled on first use into the content-hash build
cache (`implgen.compile.clib`), so a plain `pip install` needs no build step.
"""

from __future__ import annotations

import ctypes
from functools import lru_cache

import numpy as np
from numpy.typing import ArrayLike

from implgen import abi
from implgen.compile import clib
from implgen.errors import UserError
from implgen.resources import BENCH_SOURCES, SOLVER_SOURCES, runtime_dir, runtime_sources

MAX_DEGREE = abi.value("IG_MAX_DEGREE")
METHODS: dict[str, int] = {
    name: abi.value(f"IG_ROOTS_{name.upper()}") for name in ("auto", "closed", "sturm", "bracket", "bernstein")
}
#: bench-only: the classic unpolished closed forms (Schwarze-style), the speed baseline of the report
BENCH_METHODS: dict[str, int] = {**METHODS, "closed_plain": abi.value("IG_ROOTS_CLOSED_PLAIN")}

_DP = ctypes.POINTER(ctypes.c_double)
_IP = ctypes.POINTER(ctypes.c_int)


def solver_sources() -> list:
    """The C sources of the solver library: the solvers and their benchmark timing entry points."""
    return runtime_sources(SOLVER_SOURCES, BENCH_SOURCES)


@lru_cache(maxsize=1)
def library() -> ctypes.CDLL:
    """The compiled solver library (built once, then loaded from the cache)."""
    path = clib.build_shared(solver_sources(), include_dirs=[runtime_dir()], tag="roots")
    lib = clib.load(path)
    lib.ig_real_roots_any.restype = ctypes.c_int
    lib.ig_real_roots_any.argtypes = [_DP, ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_int, _DP]
    lib.ig_real_roots_batch.restype = None
    lib.ig_real_roots_batch.argtypes = [_DP, ctypes.c_int, ctypes.c_long, _DP, _DP, ctypes.c_int, _DP, _IP]
    lib.ig_first_root_batch.restype = None
    lib.ig_first_root_batch.argtypes = [_DP, ctypes.c_int, ctypes.c_long, _DP, _DP, ctypes.c_int, _DP, _IP]
    lib.ig_bench_solve_batch.restype = ctypes.c_double
    lib.ig_bench_solve_batch.argtypes = [_DP, ctypes.c_int, ctypes.c_long, _DP, _DP, ctypes.c_int, _DP, _IP, _DP]
    lib.ig_bench_first_batch.restype = ctypes.c_double
    lib.ig_bench_first_batch.argtypes = [_DP, ctypes.c_int, ctypes.c_long, _DP, _DP, ctypes.c_int, _DP, _IP, _DP]
    lib.ig_bench_fallbacks.restype = None
    lib.ig_bench_fallbacks.argtypes = [_DP, ctypes.c_int, ctypes.c_long, _DP, _DP, ctypes.c_int, ctypes.c_int, _IP]
    return lib


def method_id(method: str, bench: bool = False) -> int:
    """The C id of a method name; UserError naming the choices otherwise."""
    table = BENCH_METHODS if bench else METHODS
    if not isinstance(method, str) or method not in table:
        raise UserError("method", f"unknown root method {method!r}; choose one of: {', '.join(table)}")
    return table[method]


def _coeff_matrix(coeffs: ArrayLike) -> np.ndarray:
    c = np.ascontiguousarray(np.asarray(coeffs, dtype=np.float64))
    if c.ndim != 2 or c.shape[1] < 1:
        raise ValueError(f"coefficients must be a 2-d array (polynomials x (degree+1)), got shape {c.shape}")
    if c.shape[1] - 1 > MAX_DEGREE:
        raise ValueError(f"degree {c.shape[1] - 1} is above the solvers' maximum {MAX_DEGREE}")
    return c


def _bounds(value: ArrayLike, count: int) -> np.ndarray:
    return np.ascontiguousarray(np.broadcast_to(np.asarray(value, dtype=np.float64), (count,)))


def _batch(
    entry: str, coeffs: ArrayLike, lo: ArrayLike, hi: ArrayLike, method: str, first: bool, timed: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Call one of the C batch entry points: (roots, counts, ns per solve, untimed total ns). first: one root per
    polynomial (NaN where none), else a row of degree entries padded with NaN; timed: the bench entry points,
    which also fill ns and return the total (else ns is left empty and the total is 0)."""
    mid = method_id(method, bench=True)
    c = _coeff_matrix(coeffs)
    count, n = c.shape[0], c.shape[1] - 1
    lo_a, hi_a = _bounds(lo, count), _bounds(hi, count)
    roots = np.empty(count if first else (count, n), dtype=np.float64)
    counts = np.empty(count, dtype=np.intc)
    ns = np.empty(count, dtype=np.float64)
    total = 0.0
    if count:
        args = [
            c.ctypes.data_as(_DP),
            n,
            count,
            lo_a.ctypes.data_as(_DP),
            hi_a.ctypes.data_as(_DP),
            mid,
            roots.ctypes.data_as(_DP),
            counts.ctypes.data_as(_IP),
        ]
        if timed:
            args.append(ns.ctypes.data_as(_DP))
        total = getattr(library(), entry)(*args) or 0.0
    return roots, counts.astype(np.int64), ns, float(total)


def real_roots(coeffs: ArrayLike, lo: float = -np.inf, hi: float = np.inf, method: str = "auto") -> np.ndarray:
    """All distinct real roots of c[0] + c[1] t + ... in [lo, hi], ascending (tangent roots once)."""
    c = np.asarray(coeffs, dtype=np.float64)
    if c.ndim != 1:
        raise ValueError(f"coeffs must be 1-d (lowest power first), got shape {c.shape}")
    roots, counts = real_roots_batch(c[None, :], lo, hi, method)
    return roots[0, : counts[0]].copy()


def real_roots_batch(
    coeffs: ArrayLike, lo: ArrayLike = -np.inf, hi: ArrayLike = np.inf, method: str = "auto"
) -> tuple[np.ndarray, np.ndarray]:
    """Roots of many polynomials of one degree at once (the loop runs in C).

    coeffs: shape (count, degree+1), lowest power first; lo, hi: scalars or shape (count,).
    Returns (roots, counts): roots has shape (count, degree), row i ascending in its first counts[i]
    entries and NaN after.
    """
    roots, counts, _, _ = _batch("ig_real_roots_batch", coeffs, lo, hi, method, first=False, timed=False)
    return roots, counts


def first_root(coeffs: ArrayLike, lo: float = -np.inf, hi: float = np.inf, method: str = "auto") -> float | None:
    """The smallest real root of c[0] + c[1] t + ... in [lo, hi] (what real_roots lists first), or None."""
    c = np.asarray(coeffs, dtype=np.float64)
    if c.ndim != 1:
        raise ValueError(f"coeffs must be 1-d (lowest power first), got shape {c.shape}")
    roots, counts = first_root_batch(c[None, :], lo, hi, method)
    return float(roots[0]) if counts[0] else None


def first_root_batch(
    coeffs: ArrayLike, lo: ArrayLike = -np.inf, hi: ArrayLike = np.inf, method: str = "auto"
) -> tuple[np.ndarray, np.ndarray]:
    """first_root over many polynomials of one degree: (roots with NaN where none, counts 0 or 1)."""
    roots, counts, _, _ = _batch("ig_first_root_batch", coeffs, lo, hi, method, first=True, timed=False)
    return roots, counts


def bench_solve_batch(
    coeffs: np.ndarray, lo: ArrayLike, hi: ArrayLike, method: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Like real_roots_batch, plus the time of every solve measured in C (ns) and the total time (ns) of an
    untimed second pass (throughput)."""
    return _batch("ig_bench_solve_batch", coeffs, lo, hi, method, first=False, timed=True)


def bench_first_batch(
    coeffs: np.ndarray, lo: ArrayLike, hi: ArrayLike, method: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """First-root twin of bench_solve_batch (runtime_c/roots_bench.c: ig_bench_first_batch): (roots with NaN
    where none, counts 0/1, ns per solve, total ns of the untimed pass)."""
    return _batch("ig_bench_first_batch", coeffs, lo, hi, method, first=True, timed=True)


def bench_fallbacks(coeffs: np.ndarray, lo: ArrayLike, hi: ArrayLike, method: str, first: bool = False) -> np.ndarray:
    """Per polynomial, how many Bernstein pieces were handed to bracketing (runtime_c/roots_bench.c:
    ig_bench_fallbacks; 0 for the methods without subdivision)."""
    c = _coeff_matrix(coeffs)
    count, n = c.shape[0], c.shape[1] - 1
    lo_a, hi_a = _bounds(lo, count), _bounds(hi, count)
    fb = np.zeros(count, dtype=np.intc)
    if count:
        library().ig_bench_fallbacks(
            c.ctypes.data_as(_DP),
            n,
            count,
            lo_a.ctypes.data_as(_DP),
            hi_a.ctypes.data_as(_DP),
            method_id(method, bench=True),
            int(first),
            fb.ctypes.data_as(_IP),
        )
    return fb.astype(np.int64)
