"""The tracer's C tests: standalone drivers in tests/c/tracer_*.c, built with the sanitizers and run here.

tracer_rays.c + tracer_rays_optics.c (one driver) check ray-level answers against analytic values (sphere
distances, Snell, TIR, Fresnel, CSG event sequences, a transformed torus against the inverse-transformed ray,
the piriform in the paper's basis form); tracer_render_rows.c checks that a band of rows renders exactly those
rows of the whole image. Both are named cases (tests/c/ctest.h), each a pytest case (tests/cdriver.py).
tracer_offsets.c measures secondary-ray robustness on every example shape at scales 1e-3 .. 1e3; it takes its
size and seed as arguments and prints a row of counts per shape, which the tests here judge shape by shape.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from cdriver import CDriver, case_names
from conftest import CDIR, GENERATED, ROOT, compile_c, run_c
from implgen.resources import SHAPE_SOURCES, SOLVER_SOURCES, TRACER_SOURCES, runtime_sources


def runtime_c_sources() -> list[Path]:
    """The runtime's C files a scene library links (solvers, shape layer, tracer)."""
    return runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES, TRACER_SOURCES)


def example_shapes() -> list[str]:
    names = []
    for spec in sorted((ROOT / "examples" / "shapes").glob("*.yaml")):
        if (GENERATED / f"{spec.stem}.c").exists():
            names.append(spec.stem)
    return names


def run(exe: Path, *args: str, timeout: float = 300) -> str:
    out = run_c(exe, *args, timeout=timeout)
    print(out)
    return out


RAYS_SOURCE = CDIR / "tracer_rays.c"
ROWS_SOURCE = CDIR / "tracer_render_rows.c"

# What some cases print, checked here too: the figures behind their verdicts.
RAYS_FIGURES = {
    "sphere_random_rays_against_the_closest_root": r"sphere: 20000 random rays, hit/miss disagreements 0",
    "transformed_torus_against_the_inverse_transformed_ray": (
        r"transformed torus: 20000 rays \(\d+ hits\), hit/miss disagreements 0"
    ),
    "plane_path_against_long_double_and_the_general_solve": r"plane path: \d+ hits within 0\.\d+ of the tolerance",
}


@pytest.fixture(scope="module")
def rays_driver(tmp_path_factory: pytest.TempPathFactory) -> CDriver:
    shapes = [GENERATED / f"{n}.c" for n in ("sphere", "torus_z", "piriform")]
    sources = [RAYS_SOURCE, CDIR / "tracer_rays_optics.c", *runtime_c_sources(), *shapes]
    return CDriver.build(tmp_path_factory.mktemp("rays") / "rays", sources)


@pytest.mark.parametrize("case", case_names(RAYS_SOURCE))
def test_ray_level_analytic(rays_driver: CDriver, case: str) -> None:
    """tracer_rays.c's named cases (with tracer_rays_optics.c's): each ray-level answer against its analytic
    value, and the figures some cases print."""
    detail = rays_driver.check(case)
    print(detail)
    if case in RAYS_FIGURES:
        assert re.search(RAYS_FIGURES[case], detail), detail


def test_every_figure_belongs_to_a_case() -> None:
    assert set(RAYS_FIGURES) <= set(case_names(RAYS_SOURCE))


@pytest.fixture(scope="module")
def rows_driver(tmp_path_factory: pytest.TempPathFactory) -> CDriver:
    shapes = [GENERATED / f"{n}.c" for n in ("sphere", "torus_z")]
    return CDriver.build(tmp_path_factory.mktemp("rows") / "rows", [ROWS_SOURCE, *runtime_c_sources(), *shapes])


@pytest.mark.parametrize("case", case_names(ROWS_SOURCE))
def test_a_band_of_rows_is_exactly_those_rows_of_the_image(rows_driver: CDriver, case: str) -> None:
    detail = rows_driver.check(case)
    if case == "each_band_is_those_rows_of_the_whole_image":
        assert "render rows: 6 bands" in detail


def shape_table(path: Path, names: list[str]) -> Path:
    """A glue file listing the example shapes with their default params (from the specs)."""
    from implgen.spec.entry import load_spec

    lines = ['#include "shape.h"']
    lines += [f'#include "{n}.h"' for n in names]
    lines.append("const ig_shape *const rt_test_shapes[] = {" + ", ".join(f"&{n}_shape" for n in names) + "};")
    rows = []
    for n in names:
        spec = load_spec(ROOT / "examples" / "shapes" / f"{n}.yaml")
        vals = [repr(float(v)) for v in spec.params.values()] or ["0.0"]
        rows.append("{" + ", ".join(vals) + "}")
    lines.append("const double rt_test_params[][8] = {" + ", ".join(rows) + "};")
    lines.append(f"const int rt_test_nshapes = {len(names)};")
    path.write_text("\n".join(lines) + "\n")
    return path


def parse_offsets(out: str) -> dict[str, dict[str, float]]:
    rows = {}
    pat = re.compile(
        r"^(\S+)\s+hits\s+(\d+) rays\s+(\d+) match\s+(\d+) self-hits (\d+) misses (\d+) other (\d+) "
        r"ambiguous (\d+) lost (\d+)",
        re.M,
    )
    for m in pat.finditer(out):
        keys = ("hits", "rays", "match", "self", "miss", "other", "ambiguous", "lost")
        rows[m.group(1)] = dict(zip(keys, map(int, m.groups()[1:])))
        tail = re.search(r"any-opaque (\d+) differ (\d+)", out[m.end() : out.find("\n", m.end())])
        rows[m.group(1)].update(any_checked=int(tail.group(1)), any_differ=int(tail.group(2)))
    return rows


@pytest.fixture(scope="module")
def offsets_exes(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, list[str]]:
    names = example_shapes()
    if not names:
        pytest.skip("no generated example shapes")
    tmp = tmp_path_factory.mktemp("offsets")
    table = shape_table(tmp / "table.c", names)
    srcs = [CDIR / "tracer_offsets.c", table, *runtime_c_sources(), *(GENERATED / f"{n}.c" for n in names)]
    san = compile_c(tmp / "offsets_san", srcs)
    fast = compile_c(tmp / "offsets_fast", srcs, sanitize=False)
    return san, fast, names


def offsets_rows(exe: Path, names: list[str], *args: str, timeout: float = 300) -> dict[str, dict[str, float]]:
    """One run of tracer_offsets: a row of counts per shape, every shape's."""
    rows = parse_offsets(run(exe, *args, timeout=timeout))
    assert set(rows) == set(names)
    return rows


@pytest.fixture(scope="module")
def sanitized_offsets(offsets_exes) -> dict[str, dict[str, float]]:
    san, _, names = offsets_exes
    return offsets_rows(san, names, "2000", "7")


@pytest.fixture(scope="module")
def full_offsets(offsets_exes) -> dict[str, dict[str, float]]:
    _, fast, names = offsets_exes
    return offsets_rows(fast, names, "100000", "12345", timeout=600)


# tracer_offsets.c measures (its arguments: hits per shape, seed) and prints a row per shape, judged here shape
# by shape: one run each way, each shape reported by name
@pytest.mark.parametrize("name", example_shapes())
def test_secondary_rays_sanitized(sanitized_offsets, name) -> None:
    """Fewer points, but under ASan/UBSan: the same code paths must be memory- and UB-clean."""
    r = sanitized_offsets[name]
    assert r["self"] == 0 and r["miss"] == 0 and r["any_differ"] == 0, (name, r)


@pytest.mark.parametrize("name", example_shapes())
def test_secondary_rays_1e5_per_shape(full_offsets, name) -> None:
    """1e5 hit points per example shape over scales 1e-3 .. 1e3, two secondary rays leave each."""
    r = full_offsets[name]
    assert r["hits"] >= 99_000, (name, r)
    assert r["self"] == 0, (name, r)
    assert r["miss"] == 0, (name, r)
    # shadow rays' yes/no query (unrefined roots) agrees with the closest-hit query
    assert r["any_differ"] == 0 and r["any_checked"] >= 50_000, (name, r)
    # what cannot be judged (grazing second hits inside the offset band, reference losing the root) must stay rare
    assert r["ambiguous"] + r["lost"] + r["other"] <= 1e-3 * r["rays"], (name, r)
