"""bench/tracer_speed.py: a base runtime that lacks a source this checkout lists gets a stand-in, and the report's
form (no timing is checked)."""

from __future__ import annotations

import shutil
from pathlib import Path

import tracer_speed

from implgen.resources import TRACER_SOURCES

ROOT = Path(__file__).resolve().parent.parent


def test_a_base_without_a_listed_source_gets_a_stand_in(tmp_path: Path) -> None:
    base = tmp_path / "old"
    shutil.copytree(ROOT / "runtime_c", base)
    (base / "tracer_floor.c").unlink()
    folder = tracer_speed.base_copy(base, tmp_path / "copy")
    assert all((folder / name).is_file() for name in TRACER_SOURCES)
    assert "stand-in" in (folder / "tracer_floor.c").read_text()
    assert (folder / "tracer_hit.c").read_bytes() == (ROOT / "runtime_c" / "tracer_hit.c").read_bytes()
    assert not (base / "tracer_floor.c").exists()  # the base folder itself is left alone


def test_the_report_has_a_row_per_scene_and_the_target(tmp_path: Path) -> None:
    out = tmp_path / "speed.md"
    scene = ROOT / "bench" / "scenes" / "torus.yaml"
    args = ["--base", str(ROOT / "runtime_c"), "--runs", "1", "--width", "24", "--height", "18", "-o", str(out)]
    tracer_speed.main([str(scene), *args])
    text = out.read_text()
    assert text.startswith("# The render loop against main's\n\nWritten by `bench/tracer_speed.py --base ")
    rows = [line.split("|")[1].strip() for line in text.splitlines() if line.startswith("| ")]
    assert rows == ["scene", "torus"]
    assert "Target: this at least 2× faster than the base (CPU medians) on every scene:" in text
