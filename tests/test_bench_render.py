"""`implgen bench render`: the report's form (no timing is checked), and its options refused in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from implgen.cli import main as cli_main

ROOT = Path(__file__).resolve().parent.parent


def test_the_report_has_one_row_per_scene_and_the_fold_table(tmp_path: Path, capsys) -> None:
    out = tmp_path / "render.md"
    scenes = [str(ROOT / "bench" / "scenes" / "torus.yaml"), str(ROOT / "examples" / "scenes" / "csg_trio.yaml")]
    args = ["bench", "render", *scenes, "--runs", "2", "--width", "24", "--height", "18", "--fold-compare"]
    assert cli_main([*args, "-o", str(out)]) == 0
    text = out.read_text()
    assert text.startswith("# Render speed and thread scaling\n\nWritten by `implgen bench render --threads 1,2")
    rows = [line.split("|")[1].strip() for line in text.splitlines() if line.startswith("| ")]
    assert rows == ["scene", "torus", "csg_trio", "scene", "torus", "csg_trio"]  # scaling table, fold table
    header = next(line for line in text.splitlines() if line.startswith("| scene | 1 thr."))
    assert "speed-up 1→2" in header and "work" in header and "busy" in header
    assert "Load average after" in text and f"wrote {out}" in capsys.readouterr().out


@pytest.mark.parametrize(
    "bad, option",
    [(["--threads", "1,x"], "--threads"), (["--threads", "0,2"], "--threads"), (["-o", "{tmp}/r.txt"], "-o")],
)
def test_bad_options_are_one_line(tmp_path: Path, capsys, bad: list[str], option: str) -> None:
    scene = str(ROOT / "bench" / "scenes" / "torus.yaml")
    args = ["bench", "render", scene, "--runs", "1", "-o", str(tmp_path / "r.md")]
    assert cli_main(args + [b.format(tmp=tmp_path) for b in bad]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"implgen: error: {option}")
    assert list(tmp_path.iterdir()) == []  # refused before any work


def test_a_missing_scene_is_one_line_before_the_report_starts(tmp_path: Path, capsys) -> None:
    """The report prints its lines as they come: a scene that does not load is refused before the first, not
    after the header."""
    good = str(ROOT / "bench" / "scenes" / "torus.yaml")
    assert cli_main(["bench", "render", good, str(tmp_path / "missing.yaml"), "-o", str(tmp_path / "r.md")]) == 2
    said = capsys.readouterr()
    assert said.out == ""
    assert said.err == f"implgen: error: {tmp_path / 'missing.yaml'}: not found (expected a scene file)\n"
    assert list(tmp_path.iterdir()) == []
