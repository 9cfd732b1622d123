"""Generated C intersectors: analytic ray answers, and a sanitizer run of every example shape."""

from __future__ import annotations

import shutil
import subprocess

import numpy as np
import pytest

from conftest import GENERATED, RUNTIME, SHAPE_NAMES, CShapes, runtime_solver_sources
from implgen.spec import load_spec

SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all"]


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
    assert np.allclose(lib.intersect("torus_y", [-5, 0, 0], [2, 0, 0], 0, np.inf, [1.0, 0.25]),
                       [1.875, 2.125, 2.875, 3.125], rtol=1e-14)
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


def test_every_generated_shape_under_sanitizers(tmp_path):
    cc = shutil.which("cc") or shutil.which("gcc")
    specs = [load_spec(p) for p in sorted((GENERATED.parent / "examples" / "shapes").glob("*.yaml"))]
    table = ["#include \"shape.h\""]
    table += [f"#include \"{s.name}.h\"" for s in specs]
    table += [f"static const double params_{s.name}[] = {_params_literal(s.params.values())};" for s in specs]
    table.append("static const struct { const ig_shape *shape; const double *params; } gen_shapes[] = {")
    table += [f"    {{&{s.name}_shape, params_{s.name}}}," for s in specs]
    table.append("};")
    (tmp_path / "gen_shapes_table.h").write_text("\n".join(table) + "\n")
    exe = tmp_path / "gen_check"
    cmd = [cc, "-std=c99", "-O1", "-g", "-Wall", "-Wextra", "-Werror", "-pedantic", *SAN,
           f"-I{tmp_path}", f"-I{GENERATED}", f"-I{RUNTIME}", "-o", str(exe),
           str(GENERATED.parent / "tests" / "c" / "gen_shapes_check.c"),
           *[str(GENERATED / f"{s.name}.c") for s in specs], *map(str, runtime_solver_sources()), "-lm"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    proc = subprocess.run([str(exe)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert f"{len(specs)} passed, 0 failed" in proc.stdout
    print(proc.stdout)
