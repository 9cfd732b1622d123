"""Shared test helpers: where things are, and loading generated C and Python shapes."""

from __future__ import annotations

import ctypes
import importlib.util
import os
import subprocess
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

from implgen.compile.clib import SANITIZE_FLAGS
from implgen.resources import SHAPE_SOURCES, SOLVER_SOURCES, runtime_sources

ROOT = Path(__file__).resolve().parents[1]
SHAPES_DIR = ROOT / "examples" / "shapes"
GENERATED = ROOT / "generated"
RUNTIME = ROOT / "runtime_c"
SHAPE_FILES = sorted(SHAPES_DIR.glob("*.yaml"))
SHAPE_NAMES = [p.stem for p in SHAPE_FILES]


# @pytest.mark.needs_program(...): skipped when a Debian package's program is missing, failed instead when
# IMPLGEN_REQUIRE_ALL is set (CI)
pytest_plugins = ["needs_program"]


CDIR = ROOT / "tests" / "c"
C_SANITIZE = list(SANITIZE_FLAGS)


def compile_c(out: Path, sources, *, include=(), sanitize: bool = True, shared: bool = False, flags=()) -> Path:
    """Compile C sources into `out` (an executable, or a shared library with shared=True) with the project's
    warnings as errors, against the runtime, the generated shapes and tests/c; ASan + UBSan unless told not
    to (any report aborts). The compiler is $CC, else cc (implgen.compile.clib.compiler)."""
    from implgen.compile.clib import WARNING_FLAGS, compiler

    cmd = [compiler(), *WARNING_FLAGS, *(C_SANITIZE if sanitize else ["-O2"]), "-pthread", *flags]
    cmd += ["-shared", "-fPIC"] if shared else []
    cmd += [f"-I{d}" for d in (*include, RUNTIME, GENERATED, CDIR)]
    cmd += ["-o", str(out), *map(str, sources), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return out


def run_c(exe: Path, *args: str, timeout: float = 300) -> str:
    """Run a compiled driver; it must exit 0 (a sanitizer report exits non-zero). Returns its stdout."""
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1", UBSAN_OPTIONS="print_stacktrace=1")
    proc = subprocess.run([str(exe), *args], capture_output=True, text=True, timeout=timeout, env=env)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    return proc.stdout


def load_python_shape(name: str, folder: Path = GENERATED) -> ModuleType:
    """Import generated/<name>.py under a private module name."""
    spec = importlib.util.spec_from_file_location(f"_generated_{folder.name}_{name}", folder / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    assert spec.loader is not None
    spec.loader.exec_module(module)
    return module


def runtime_solver_sources() -> list[Path]:
    """The runtime's solver and shape sources (what a generated intersector links against)."""
    return runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES)


class CShapes:
    """Generated C shapes compiled into one shared library (through the package's build cache)."""

    def __init__(self, names: list[str], folder: Path = GENERATED, with_runtime: bool = True) -> None:
        from implgen.compile.clib import build_shared, load

        sources = [folder / f"{n}.c" for n in names]
        if with_runtime:
            sources += runtime_solver_sources()
        self.lib = load(build_shared(sources, include_dirs=[folder, RUNTIME], tag="test-shapes"))
        self.names = names

    def _fn(self, name: str, what: str):
        return getattr(self.lib, f"{name}_{what}")

    @staticmethod
    def _arr(values) -> ctypes.Array:
        values = [float(v) for v in values]
        return (ctypes.c_double * max(len(values), 1))(*values)

    def coeffs(self, name: str, degree: int, o, d, params=()) -> np.ndarray:
        out = (ctypes.c_double * (degree + 1))()
        self._fn(name, "coeffs")(self._arr(o), self._arr(d), self._arr(params), out)
        return np.array(out[:])

    def value(self, name: str, p, params=()) -> float:
        fn = self._fn(name, "value")
        fn.restype = ctypes.c_double
        return fn(self._arr(p), self._arr(params))

    def gradient(self, name: str, p, params=()) -> np.ndarray:
        out = (ctypes.c_double * 3)()
        self._fn(name, "gradient")(self._arr(p), self._arr(params), out)
        return np.array(out[:])

    def bounds(self, name: str, params=()) -> tuple[int, np.ndarray]:
        out = (ctypes.c_double * 6)()
        flag = self._fn(name, "bounds")(self._arr(params), out)
        return flag, np.array(out[:])

    def intersect(self, name: str, o, d, tmin, tmax, params=()) -> np.ndarray:
        out = (ctypes.c_double * 32)()
        fn = self._fn(name, "intersect")
        fn.argtypes = [
            ctypes.c_void_p,
            ctypes.c_void_p,
            ctypes.c_double,
            ctypes.c_double,
            ctypes.c_void_p,
            ctypes.c_void_p,
        ]
        count = fn(self._arr(o), self._arr(d), tmin, tmax, self._arr(params), out)
        return np.array(out[:count])

    def normal(self, name: str, p, params=()) -> tuple[int, np.ndarray]:
        out = (ctypes.c_double * 3)()
        flag = self._fn(name, "normal")(self._arr(p), self._arr(params), out)
        return flag, np.array(out[:])


def random_rays(rng: np.random.Generator, n: int, spread: float = 2.0) -> tuple[np.ndarray, np.ndarray]:
    """Origins in a box, directions of random (non-unit) length 0.1 .. 10."""
    o = rng.uniform(-spread, spread, (n, 3))
    d = rng.normal(size=(n, 3))
    d *= (10.0 ** rng.uniform(-1, 1, (n, 1))) / np.linalg.norm(d, axis=1, keepdims=True)
    return o, d


@pytest.fixture(scope="session")
def rng() -> np.random.Generator:
    return np.random.default_rng(20261121)


# ------------------------------------------------------------------------------------------ Hypothesis

# `make test` runs the "ci" profile: a modest, fixed number of examples, derandomized and without an example
# database, so a run is reproducible and quick. HYPOTHESIS_PROFILE=long searches much longer, at random, for
# a deep local run (docs/testing.md#fuzzing).
from hypothesis import HealthCheck  # noqa: E402
from hypothesis import settings as _hsettings  # noqa: E402

_QUIET = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much, HealthCheck.large_base_example]
_hsettings.register_profile("ci", derandomize=True, database=None, deadline=None, suppress_health_check=_QUIET)
_hsettings.register_profile("long", derandomize=False, deadline=None, suppress_health_check=_QUIET, print_blob=True)
HYPOTHESIS_PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "ci")
_hsettings.load_profile(HYPOTHESIS_PROFILE)
FUZZ_SCALE = int(os.environ.get("IMPLGEN_FUZZ_SCALE", "50" if HYPOTHESIS_PROFILE == "long" else "1"))


def fuzz_settings(examples: int):
    """Settings for one fuzz property: `examples` in the ci profile, FUZZ_SCALE times as many otherwise."""
    return _hsettings(max_examples=examples * FUZZ_SCALE)
