"""The two generated front ends agree: the Python module's `intersect` (NumPy coefficients, implgen.raycast's
twin of shape.c, the C solvers) and the C `<name>_intersect` (generated C coefficients, `ig_shape_roots`) give
the same hits on the same rays, for every example shape -- hit or miss, and where they hit, the same t."""

from __future__ import annotations

import numpy as np
import pytest

from conftest import SHAPE_NAMES, CShapes, load_python_shape, random_rays
from implgen.measure.cases.polys import find_shapes_dir
from implgen.roots import raycast
from implgen.spec.entry import load_spec


@pytest.fixture(scope="module")
def cshapes() -> CShapes:
    return CShapes(SHAPE_NAMES)


@pytest.mark.parametrize("name", SHAPE_NAMES)
def test_python_intersect_equals_c_intersect(name, cshapes, rng):
    module = load_python_shape(name)
    spec = load_spec(find_shapes_dir() / f"{name}.yaml")
    params = list(spec.params.values())
    o, d = random_rays(rng, 400, spread=3.0)
    py_first = module.intersect(o, d, 0.0, 50.0)
    box = module.bounds()
    agree = 0
    for i in range(len(o)):
        c_all = cshapes.intersect(name, o[i], d[i], 0.0, 50.0, params)
        p_all = raycast.all_hits(lambda o_, d_: module.coeffs(o_, d_), box, o[i], d[i], 0.0, 50.0)
        if len(c_all) != len(p_all):
            # the coefficients are the same expressions evaluated in another order: only a ray that grazes
            # the surface within rounding may gain or lose a tangent pair
            grazing = np.min(np.abs(module.value(o[i] + np.outer(c_all if len(c_all) else p_all, d[i])))) < 1e-6
            assert grazing, (name, i, c_all, p_all)
            continue
        np.testing.assert_allclose(p_all, c_all, rtol=1e-9, atol=1e-12, err_msg=f"{name} ray {i}")
        assert (py_first[i] == np.inf) == (len(c_all) == 0)
        if len(c_all):
            assert py_first[i] == pytest.approx(c_all[0], rel=1e-9, abs=1e-12)
        agree += 1
    assert agree >= 390
