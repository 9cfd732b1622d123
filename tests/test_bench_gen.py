"""`implgen bench gen` writes its table, with the machine, to the results file; a bad -o is refused first."""

from __future__ import annotations

from implgen.cli import main


def test_bench_gen_writes_its_table(tmp_path, capsys):
    out = tmp_path / "gen.md"
    assert main(["bench", "gen", "--degrees", "2", "4", "--repeats", "1", "--compare", "4", "-o", str(out)]) == 0
    text = out.read_text()
    assert "Written by `implgen bench gen` on " in text
    rows = [line for line in text.splitlines() if line.startswith("| 2 |") or line.startswith("| 4 |")]
    assert len(rows) == 2
    # operation counts do not depend on the machine: the sphere's coefficients and the expanded quartic's
    assert rows[0].split("|")[3].strip() == "20" and rows[1].split("|")[3].strip() == "46"
    assert rows[1].split("|")[7].strip() == "264"


def test_bench_gen_refuses_a_bad_output_before_any_work(tmp_path, capsys):
    assert main(["bench", "gen", "-o", str(tmp_path / "missing" / "gen.md")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "-o" in err[0]
