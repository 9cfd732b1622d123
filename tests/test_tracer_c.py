"""The tracer's C tests: standalone drivers in tests/c/tracer_*.c, built with the sanitizers and run here.

tracer_rays.c + tracer_rays_optics.c (one driver) check ray-level answers against analytic values (sphere
distances, Snell, TIR, Fresnel, CSG event sequences, a transformed torus against the inverse-transformed ray,
the piriform in the paper's basis form). tracer_offsets.c measures secondary-ray robustness on every example
shape at scales 1e-3 .. 1e3. tracer_render_rows.c checks that a band of rows renders exactly those rows of the
whole image.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

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


def test_ray_level_analytic(tmp_path: Path) -> None:
    shapes = [GENERATED / f"{n}.c" for n in ("sphere", "torus_z", "piriform")]
    exe = compile_c(
        tmp_path / "rays", [CDIR / "tracer_rays.c", CDIR / "tracer_rays_optics.c", *runtime_c_sources(), *shapes]
    )
    out = run(exe)
    assert "0 failures" in out
    assert re.search(r"sphere: 20000 random rays, hit/miss disagreements 0", out)
    assert re.search(r"transformed torus: 20000 rays \(\d+ hits\), hit/miss disagreements 0", out)
    assert re.search(r"plane path: \d+ hits within 0\.\d+ of the tolerance", out)


def test_a_band_of_rows_is_exactly_those_rows_of_the_image(tmp_path: Path) -> None:
    shapes = [GENERATED / f"{n}.c" for n in ("sphere", "torus_z")]
    exe = compile_c(tmp_path / "rows", [CDIR / "tracer_render_rows.c", *runtime_c_sources(), *shapes])
    assert "render rows: 6 bands, 0 failures" in run(exe)


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


def test_secondary_rays_sanitized(offsets_exes) -> None:
    """Fewer points, but under ASan/UBSan: the same code paths must be memory- and UB-clean."""
    san, _, names = offsets_exes
    rows = parse_offsets(run(san, "2000", "7"))
    assert set(rows) == set(names)
    for name, r in rows.items():
        assert r["self"] == 0 and r["miss"] == 0 and r["any_differ"] == 0, (name, r)


def test_secondary_rays_1e5_per_shape(offsets_exes) -> None:
    """1e5 hit points per example shape over scales 1e-3 .. 1e3, two secondary rays leave each."""
    _, fast, names = offsets_exes
    out = run(fast, "100000", "12345", timeout=600)
    rows = parse_offsets(out)
    assert set(rows) == set(names)
    for name, r in rows.items():
        assert r["hits"] >= 99_000, (name, r)
        assert r["self"] == 0, (name, r)
        assert r["miss"] == 0, (name, r)
        # shadow rays' yes/no query (unrefined roots) agrees with the closest-hit query
        assert r["any_differ"] == 0 and r["any_checked"] >= 50_000, (name, r)
        # what cannot be judged (grazing second hits inside the offset band, reference losing the root)
        # must stay rare
        assert r["ambiguous"] + r["lost"] + r["other"] <= 1e-3 * r["rays"], (name, r)
