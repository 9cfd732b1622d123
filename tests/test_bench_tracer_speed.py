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
    assert "Target: this at least 2× faster than the base (paired CPU medians) on every scene:" in text


def test_each_round_runs_base_this_and_a_control_of_the_base(tmp_path: Path, monkeypatch) -> None:
    """A round runs all three sides, in an order that turns through all six; the control is the base runtime built
    again, and the report gives base/control beside base/this, so that the noise is measured with the change."""
    seen: list[tuple[str, int]] = []

    def fake_built(scene: Path, runtime: Path):
        class Side:
            def close(self) -> None:
                pass

        side = Side()
        side.runtime = runtime
        return side, None

    def fake_measure(cs, sc, size, threads):
        seen.append((str(cs.runtime), id(cs)))
        return 1.0, {"base": 2.0, "this": 1.0}[Path(cs.runtime).name], {}

    monkeypatch.setattr(tracer_speed, "built", fake_built)
    monkeypatch.setattr(tracer_speed, "_measure", fake_measure)
    size = type("S", (), {"width": 8, "height": 6, "spp": 1})()
    got = tracer_speed.time_scene(tmp_path / "x.yaml", [tmp_path / "base", tmp_path / "this"], size, 6)
    assert got["cpu0"] == [2.0] * 6 and got["cpu1"] == [1.0] * 6 and got["cpu2"] == [2.0] * 6
    rounds = [seen[3 + 3 * r : 6 + 3 * r] for r in range(6)]  # after the 3 warm-up runs
    sides = {ident: k for k, (_, ident) in enumerate(seen[:3])}
    assert sorted(tuple(sides[ident] for _, ident in rnd) for rnd in rounds) == sorted(tracer_speed.ORDERS)
    line, ratio = tracer_speed.row("x", got)
    assert ratio == 2.0 and "| 2.00× (2.00–2.00) | 1.00× (1.00–1.00) |" in line


def test_a_run_leaves_the_process_compiling_with_the_installed_runtime(tmp_path: Path) -> None:
    """The comparison points the compiles at a copy of the base runtime in a temporary folder; after the run the
    process builds with the installed runtime again (a later test's scene build once read the deleted copy)."""
    import implgen.compile.library as library
    import implgen.resources as resources

    before = (resources.runtime_dir(), library.runtime_dir())
    args = ["--base", str(ROOT / "runtime_c"), "--runs", "1", "--width", "8", "--height", "6"]
    tracer_speed.main([*args, "-o", str(tmp_path / "speed.md"), str(ROOT / "bench" / "scenes" / "torus.yaml")])
    assert (resources.runtime_dir(), library.runtime_dir()) == before
    assert (resources.runtime_dir() / "roots.c").is_file()
