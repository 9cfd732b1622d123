"""Generated C intersectors: analytic ray answers, and a sanitizer run of every example shape."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from cdriver import CDriver
from conftest import CDIR, GENERATED, SHAPE_FILES, SHAPE_NAMES, CShapes, runtime_solver_sources
from implgen.spec.entry import load_spec


@pytest.fixture(scope="module")
def lib() -> CShapes:
    return CShapes(SHAPE_NAMES)


def test_sphere_hits_are_exact(lib):
    # From (0, 0, -5) with d = (0, 0, 2) a sphere of radius 1 is met at z = -1 and z = 1: t = 2 and 3.
    assert np.array_equal(lib.intersect("sphere", [0, 0, -5], [0, 0, 2], 0, np.inf, [1.0]), [2.0, 3.0])
    # Starting inside: only the exit.
    assert np.allclose(lib.intersect("sphere", [0, 0, 0.5], [0, 0, 1], 0, np.inf, [1.0]), [0.5], rtol=1e-15)


def test_torus_four_hits_along_its_plane(lib):
    t = lib.intersect("torus_z", [-5, 0, 0], [1, 0, 0], 0, np.inf, [1.0, 0.25])
    assert np.allclose(t, [3.75, 4.25, 5.75, 6.25], rtol=1e-14)
    # Suffern's torus about y, a ray along x in the plane y = 0 and one grazing the tube's top (y = b).
    assert np.allclose(
        lib.intersect("torus_y", [-5, 0, 0], [2, 0, 0], 0, np.inf, [1.0, 0.25]),
        [1.875, 2.125, 2.875, 3.125],
        rtol=1e-14,
    )
    graze = lib.intersect("torus_y", [-5, 0.25, 0], [1, 0, 0], 0, np.inf, [1.0, 0.25])
    assert np.allclose(graze, [4.0, 6.0], rtol=1e-6)  # double roots at x = -1 and x = 1: tangent hits


def test_piriform_ray_with_no_x_component(lib):
    # d_x = 0: the quartic drops to a quadratic. At x = 1/2, y^2 = x^3 - x^4 = 1/16: y = -1/4 and 1/4.
    assert np.allclose(lib.intersect("piriform", [0.5, -1, 0], [0, 1, 0], 0, np.inf), [0.75, 1.25], rtol=1e-14)


def test_cylinder_ray_parallel_to_axis(lib):
    assert lib.intersect("cylinder", [0.2, -3, 0.1], [0, 1, 0], 0, np.inf, [1.0]).size == 0
    assert np.allclose(lib.intersect("cylinder", [-3, 7, 0], [1, 0, 0], 0, np.inf, [1.0]), [2.0, 4.0], rtol=1e-15)


def test_far_away_torus_gives_the_same_hits(lib):
    near = lib.intersect("torus_z", [-5, 0.1, 0.05], [1, 0, 0], 0, np.inf, [1.0, 0.25])
    far = lib.intersect("torus_z", [-1e4, 0.1, 0.05], [1, 0, 0], 0, np.inf, [1.0, 0.25])
    assert near.size == 4 and np.allclose(far - (1e4 - 5), near, rtol=0, atol=1e-9 * 1e4)


def _first_hit(lib: CShapes, name: str, o, d, tmin, tmax, params=()) -> tuple[int, float]:
    """<name>_first_hit through ctypes: (return value, t); t starts as a sentinel the function must not touch
    on a miss."""
    fn = getattr(lib.lib, f"{name}_first_hit")
    fn.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p]
    t = ctypes.c_double(-12345.0)
    got = fn(lib._arr(o), lib._arr(d), tmin, tmax, lib._arr(params), ctypes.byref(t))
    return got, t.value


def test_first_hit_is_the_nearest_root(lib):
    assert _first_hit(lib, "sphere", [0, 0, -5], [0, 0, 2], 0, np.inf, [1.0]) == (1, 2.0)
    assert _first_hit(lib, "sphere", [0, 0, -5], [0, 0, 2], 2.5, np.inf, [1.0]) == (1, 3.0)  # tmin past the entry
    assert _first_hit(lib, "sphere", [0, 0, -5], [0, 0, 2], 0, 2.0, [1.0]) == (1, 2.0)  # root exactly at tmax
    got, t = _first_hit(lib, "sphere", [0, 0, 0.5], [0, 0, 1], 0, np.inf, [1.0])  # inside: the exit
    assert got == 1 and t == pytest.approx(0.5, rel=1e-15)
    got, t = _first_hit(lib, "torus_z", [-5, 0, 0], [1, 0, 0], 0, np.inf, [1.0, 0.25])
    assert got == 1 and t == pytest.approx(3.75, rel=1e-14)
    got, t = _first_hit(lib, "torus_y", [-5, 0.25, 0], [1, 0, 0], 0, np.inf, [1.0, 0.25])  # tangent: double root
    assert got == 1 and t == pytest.approx(4.0, rel=1e-6)
    got, t = _first_hit(lib, "piriform", [0.5, -1, 0], [0, 1, 0], 0, np.inf)  # degree drop to 2
    assert got == 1 and t == pytest.approx(0.75, rel=1e-14)
    near = _first_hit(lib, "torus_z", [-5, 0.1, 0.05], [1, 0, 0], 0, np.inf, [1.0, 0.25])
    far = _first_hit(lib, "torus_z", [-1e4, 0.1, 0.05], [1, 0, 0], 0, np.inf, [1.0, 0.25])  # origin shift
    assert near[0] == far[0] == 1 and abs((far[1] - (1e4 - 5)) - near[1]) <= 1e-9 * 1e4, (near, far)


def test_first_hit_misses_leave_t_alone(lib):
    assert _first_hit(lib, "sphere", [0, 0, -5], [0, 0, 2], 0, 1.5, [1.0]) == (0, -12345.0)  # stops short
    assert _first_hit(lib, "sphere", [0, 3, -5], [0, 0, 1], 0, np.inf, [1.0]) == (0, -12345.0)  # passes by
    assert _first_hit(lib, "sphere", [0, 0, -5], [0, 0, 2], 1.0, 0.0, [1.0]) == (0, -12345.0)  # tmin > tmax
    assert _first_hit(lib, "sphere", [0, 0, -5], [0, 0, 0], 0, np.inf, [1.0]) == (0, -12345.0)  # d = 0
    assert _first_hit(lib, "sphere", [0, 0, np.nan], [0, 0, 1], 0, np.inf, [1.0]) == (0, -12345.0)
    assert _first_hit(lib, "cylinder", [0.2, -3, 0.1], [0, 1, 0], 0, np.inf, [1.0]) == (0, -12345.0)  # in the wall


def test_first_hit_is_intersects_first_root_on_random_rays(lib, rng):
    """Every example shape, rays from around its box with non-unit directions, random [tmin, tmax]."""
    from conftest import random_rays

    for path in sorted((GENERATED.parent / "examples" / "shapes").glob("*.yaml")):
        spec = load_spec(path)
        params = [float(v) for v in spec.params.values()]
        flag, box = lib.bounds(spec.name, params)
        box = np.where(np.isfinite(box), box, [-2.0, -2.0, -2.0, 2.0, 2.0, 2.0])
        target = box[:3] + rng.random((400, 3)) * (box[3:] - box[:3])  # rays through points of the box
        o, d = random_rays(rng, 400, spread=3.0)
        o = target - 2.0 * d
        hits = 0
        for i in range(len(o)):
            tmin, tmax = (0.0, np.inf) if i % 2 else sorted(rng.uniform(-2, 8, 2))
            roots = lib.intersect(spec.name, o[i], d[i], tmin, tmax, params)
            got, t = _first_hit(lib, spec.name, o[i], d[i], tmin, tmax, params)
            assert got == (roots.size > 0), (spec.name, i, roots, t)
            if not got:
                assert t == -12345.0
                continue
            hits += 1
            assert t == roots[0], (spec.name, i, t, roots)  # bitwise: the same clip, shift and first root
        assert hits >= 100, (spec.name, hits)


def test_singular_normals_are_zero_not_nan(lib):
    flag, n = lib.normal("cone", [0, 0, 0])
    assert flag == 0 and np.array_equal(n, [0, 0, 0])
    flag, n = lib.normal("piriform", [0, 0, 0])
    assert flag == 0 and np.array_equal(n, [0, 0, 0])
    flag, n = lib.normal("piriform", [1, 0, 0])  # the tip: grad = (4 - 3, 0, 0)
    assert flag == 1 and np.array_equal(n, [1, 0, 0])


def _params_literal(values) -> str:
    inner = ", ".join(repr(float(v)) for v in values) or "0.0"
    return "{" + inner + "}"


def _gen_shapes_table(path, specs) -> None:
    """gen_shapes_table.h: each shape's header and default params, and GEN_SHAPES(X), X(name) for each shape
    (tests/c/gen_shapes_check.c makes a case of each). The names are the specs' validated names."""
    table = ['#include "shape.h"']
    table += [f'#include "{s.name}.h"' for s in specs]
    table += [f"static const double params_{s.name}[] = {_params_literal(s.params.values())};" for s in specs]
    table.append("#define GEN_SHAPES(X) " + " ".join(f"X({s.name})" for s in specs))
    path.write_text("\n".join(table) + "\n")


@pytest.fixture(scope="module")
def gen_shapes_driver(tmp_path_factory) -> CDriver:
    """tests/c/gen_shapes_check.c built with every example shape, ASan + UBSan."""
    specs = [load_spec(p) for p in SHAPE_FILES]
    assert [s.name for s in specs] == SHAPE_NAMES
    tmp = tmp_path_factory.mktemp("gen_check")
    _gen_shapes_table(tmp / "gen_shapes_table.h", specs)
    sources = [CDIR / "gen_shapes_check.c", *[GENERATED / f"{s.name}.c" for s in specs], *runtime_solver_sources()]
    return CDriver.build(tmp / "gen_check", sources, include=[tmp])


@pytest.mark.parametrize("shape", SHAPE_NAMES)
def test_every_generated_shape_under_sanitizers(gen_shapes_driver, shape):
    """One named case per example shape: 20000 random rays, intersect exactly ig_shape_roots, first_hit its
    first root, every root's backward error, ascending order and normal, and at least 1000 hits."""
    print(gen_shapes_driver.check(shape))
