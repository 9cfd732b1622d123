"""runtime_c/mesh_kernels.c (the mesh's dual vertices and triangles): tests/c/test_mesh_kernels.c's named cases
under ASan + UBSan, each a pytest case of its own."""

from __future__ import annotations

import pytest

from cdriver import CDriver, case_names
from conftest import CDIR, RUNTIME

SOURCE = CDIR / "test_mesh_kernels.c"


@pytest.fixture(scope="module")
def driver(tmp_path_factory) -> CDriver:
    return CDriver.build(
        tmp_path_factory.mktemp("mesh_kernels") / "test_mesh_kernels", [SOURCE, RUNTIME / "mesh_kernels.c"]
    )


@pytest.mark.parametrize("case", case_names(SOURCE))
def test_mesh_kernels_case(driver, case):
    driver.check(case)
