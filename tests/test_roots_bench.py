"""`implgen bench solvers --quick` runs end to end and writes its table and plot."""

from __future__ import annotations

from pathlib import Path

from implgen.bench_solvers import main


def test_bench_solvers_quick(tmp_path: Path) -> None:
    assert main(["--quick", "-o", str(tmp_path)]) == 0
    md = (tmp_path / "solvers.md").read_text()
    assert "| torus rays | auto |" in md and "numpy.roots" in md and "Targets:" in md
    assert (tmp_path / "solvers.png").stat().st_size > 10_000
