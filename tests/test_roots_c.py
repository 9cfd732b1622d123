"""Build and run the standalone C drivers of the root solvers and the shape intersection under
AddressSanitizer + UBSan (any report aborts: -fno-sanitize-recover=all)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from implgen import cbuild

ROOT = Path(__file__).resolve().parents[1]
RUNTIME = ROOT / "runtime_c"
CDIR = ROOT / "tests" / "c"
FLAGS = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O1", "-g",
         "-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]


def _build_and_run(tmp_path: Path, name: str, sources: list[Path]) -> subprocess.CompletedProcess:
    exe = tmp_path / name
    cmd = [cbuild.compiler(), *FLAGS, f"-I{RUNTIME}", f"-I{CDIR}", "-o", str(exe), *map(str, sources), "-lm"]
    build = subprocess.run(cmd, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    return subprocess.run([str(exe)], capture_output=True, text=True, timeout=120,
                          env={"ASAN_OPTIONS": "detect_leaks=1", "UBSAN_OPTIONS": "print_stacktrace=1"})


def test_roots_hard_cases_under_sanitizers(tmp_path: Path) -> None:
    run = _build_and_run(tmp_path, "test_roots", [CDIR / "test_roots.c", *sorted(RUNTIME.glob("roots*.c"))])
    assert run.returncode == 0, run.stdout + run.stderr
    assert "all cases passed" in run.stdout


def test_refinement_batched_equals_single_under_sanitizers(tmp_path: Path) -> None:
    run = _build_and_run(tmp_path, "test_refine", [CDIR / "test_refine.c", *sorted(RUNTIME.glob("roots*.c"))])
    assert run.returncode == 0, run.stdout + run.stderr
    assert "all refinement checks passed" in run.stdout


def test_far_torus_matches_near_torus_under_sanitizers(tmp_path: Path) -> None:
    run = _build_and_run(tmp_path, "test_shape_torus",
                         [CDIR / "test_shape_torus.c", CDIR / "shape_torus_fixture.c", RUNTIME / "shape.c",
                          *sorted(RUNTIME.glob("roots*.c"))])
    assert run.returncode == 0, run.stdout + run.stderr
    assert "all checks passed" in run.stdout


@pytest.mark.parametrize("src", sorted(RUNTIME.glob("roots*.c")) + [RUNTIME / "shape.c"], ids=lambda p: p.name)
def test_runtime_sources_compile_clean(tmp_path: Path, src: Path) -> None:
    cmd = [cbuild.compiler(), "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", f"-I{RUNTIME}",
           "-c", str(src), "-o", str(tmp_path / "x.o")]
    out = subprocess.run(cmd, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
