"""The standalone C drivers of the root solvers and the shape intersection (tests/c/), built with ASan +
UBSan (any report aborts) and run; and every runtime source compiles clean on its own with -O2."""

from __future__ import annotations

import pytest

from cdriver import CDriver, case_names
from conftest import CDIR, RUNTIME, compile_c
from implgen.resources import (
    EMBREE_SOURCES,
    MESH_SOURCES,
    SHAPE_SOURCES,
    SOLVER_SOURCES,
    TRACER_SOURCES,
    runtime_sources,
)

SOLVERS = runtime_sources(SOLVER_SOURCES)


ROOTS_SOURCE = CDIR / "test_roots.c"


@pytest.fixture(scope="module")
def roots_driver(tmp_path_factory) -> CDriver:
    return CDriver.build(tmp_path_factory.mktemp("roots") / "test_roots", [ROOTS_SOURCE, *SOLVERS])


@pytest.mark.parametrize("case", case_names(ROOTS_SOURCE))
def test_roots_hard_cases_under_sanitizers(roots_driver, case):
    """tests/c/test_roots.c's named cases, each on every method it names."""
    roots_driver.check(case)


REFINE_SOURCE = CDIR / "test_refine.c"
TORUS_SOURCE = CDIR / "test_shape_torus.c"
BATCH_SOURCE = CDIR / "test_shape_batch.c"
TORUS_FIXTURE = [CDIR / "shape_torus_fixture.c", *runtime_sources(SHAPE_SOURCES), *SOLVERS]


@pytest.fixture(scope="module")
def refine_driver(tmp_path_factory) -> CDriver:
    return CDriver.build(tmp_path_factory.mktemp("refine") / "test_refine", [REFINE_SOURCE, *SOLVERS])


@pytest.mark.parametrize("case", case_names(REFINE_SOURCE))
def test_refinement_batched_equals_single_under_sanitizers(refine_driver, case):
    """tests/c/test_refine.c's named cases: batched refinement bitwise the single one, both at the known roots."""
    refine_driver.check(case)


@pytest.fixture(scope="module")
def torus_driver(tmp_path_factory) -> CDriver:
    return CDriver.build(tmp_path_factory.mktemp("torus") / "test_shape_torus", [TORUS_SOURCE, *TORUS_FIXTURE])


@pytest.mark.parametrize("case", case_names(TORUS_SOURCE))
def test_far_torus_matches_near_torus_under_sanitizers(torus_driver, case):
    """tests/c/test_shape_torus.c's named cases: the far torus is the near one; the normal's hard points."""
    torus_driver.check(case)


def _runtime_source(path):
    """Each runtime C file, the Embree adapter marked as needing Embree's header."""
    marks = [pytest.mark.needs_library("embree3")] if path.name in EMBREE_SOURCES else []
    return pytest.param(path, id=path.name, marks=marks)


@pytest.mark.parametrize("src", [_runtime_source(p) for p in sorted(RUNTIME.glob("*.c"))])
def test_runtime_sources_compile_clean(tmp_path, src):
    assert src.name in (
        *SOLVER_SOURCES,
        *SHAPE_SOURCES,
        *MESH_SOURCES,
        *TRACER_SOURCES,
        *EMBREE_SOURCES,
        "roots_bench.c",
    )
    compile_c(tmp_path / "x.o", [src], sanitize=False, flags=["-c"])


@pytest.fixture(scope="module")
def batch_driver(tmp_path_factory) -> CDriver:
    return CDriver.build(tmp_path_factory.mktemp("batch") / "test_shape_batch", [BATCH_SOURCE, *TORUS_FIXTURE])


@pytest.mark.parametrize("case", case_names(BATCH_SOURCE))
def test_shape_batch_equals_one_by_one_under_sanitizers(batch_driver, case):
    """tests/c/test_shape_batch.c's named cases: the batch entry points bit for bit the single calls."""
    batch_driver.check(case)
