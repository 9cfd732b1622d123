"""Bad specs: exit status 2, one line naming the file and the problem, no traceback, nothing written."""

from __future__ import annotations

import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from implgen.cli import main

GOOD = "name: s\nequation: x^2 + y^2 + z^2 - 1\n"

CASES = [
    # (id, file text, fragment expected in the message)
    ("malformed-yaml", "name: [unclosed\nequation: x\n", "invalid YAML"),
    ("empty-file", "", "not a shape spec"),
    ("not-a-mapping", "- x\n- y\n", "not a shape spec"),
    ("missing-equation", "name: s\n", "missing key 'equation'"),
    ("missing-name", "equation: x\n", "missing key 'name'"),
    ("unknown-key", GOOD + "colour: red\n", "unknown key 'colour'"),
    ("duplicate-key", GOOD + "name: t\n", "duplicate key"),
    ("unknown-symbol", "name: s\nequation: x + w\n", "unknown symbol 'w'"),
    ("sin", "name: s\nequation: sin(x) + y\n", "function calls are not allowed"),
    ("sqrt-power", "name: s\nequation: x^0.5 + y\n", "non-negative integer"),
    ("negative-power", "name: s\nequation: x^-1 + y\n", "non-negative integer"),
    ("divide-by-x", "name: s\nequation: 1/x + y\n", "division by a non-constant"),
    ("divide-by-param", "name: s\nequation: x/a\nparams: {a: 2}\n", "division by a non-constant"),
    ("divide-by-zero", "name: s\nequation: x/(1-1)\n", "division by zero"),
    ("symbolic-exponent", "name: s\nequation: x^y\n", "exponent must be a constant"),
    ("identically-zero", "name: s\nequation: (x+y)^2 - x^2 - 2*x*y - y^2\n", "identically zero"),
    ("constant", "name: s\nequation: a = 3\nparams: {a: 2}\n", "no x, y or z"),
    ("degree-above-max", "name: s\nequation: x^25 + y\n", "24"),
    ("huge-exponent", "name: s\nequation: x^100000\n", "exceed"),
    ("tower-exponent", "name: s\nequation: x^(10^10)\n", "exceed"),
    ("huge-constant-power", "name: s\nequation: x + 2^(10^10)\n", "constant power too large"),
    ("deep-parentheses", "name: s\nequation: " + "(" * 300 + "x" + ")" * 300 + "\n", "nested"),
    ("long-chain", "name: s\nequation: " + "+".join(["x"] * 6000) + "\n", "nested"),
    ("name-escapes-folder", "name: ../evil\nequation: x\n", "not an identifier"),
    ("name-with-slash", "name: a/b\nequation: x\n", "not an identifier"),
    ("name-keyword", "name: int\nequation: x\n", "reserved word"),
    ("param-nan", "name: s\nequation: x - a\nparams: {a: .nan}\n", "finite number"),
    ("param-inf", "name: s\nequation: x - a\nparams: {a: .inf}\n", "finite number"),
    ("param-text", "name: s\nequation: x - a\nparams: {a: abc}\n", "finite number"),
    ("param-bool", "name: s\nequation: x - a\nparams: {a: true}\n", "finite number"),
    ("param-shadows-x", "name: s\nequation: x - 1\nparams: {x: 1}\n", "shadows"),
    ("param-bad-name", "name: s\nequation: x - 1\nparams: {'a b': 1}\n", "not an identifier"),
    ("python-tag", "name: !!python/object/apply:os.system ['echo pwned']\nequation: x\n", "invalid YAML"),
    ("dunder-import", "name: s\nequation: __import__('os').system('echo pwned')\n", "not allowed"),
    ("attribute", "name: s\nequation: x.real + 1\n", "attribute access"),
    ("lambda", "name: s\nequation: (lambda q: q)(x)\n", "not allowed"),
    ("comprehension", "name: s\nequation: sum([x for x in y])\n", "not allowed"),
    ("list-comprehension", "name: s\nequation: '[x for x in y]'\n", "character '[' at position 1 is not allowed"),
    ("statement", "name: s\nequation: 'x; import os'\n", "character ';' at position 2 is not allowed"),
    ("double-equals", "name: s\nequation: x == 1\n", "single '='"),
    ("string-literal", "name: s\nequation: \"x + 'a'\"\n", 'character "\'" at position 5 is not allowed'),
    ("bounds-axis", GOOD + "bounds: {w: [0, 1]}\n", "unknown axis"),
    ("bounds-order", GOOD + "bounds: {x: [1, -1]}\n", "low must be below high"),
    ("bounds-symbol", GOOD + "bounds: {x: [-y, 1]}\n", "unknown symbol"),
    ("bounds-shape", GOOD + "bounds: {x: 1}\n", "pair"),
]


@pytest.fixture()
def out_dir(tmp_path: Path) -> Path:
    out = tmp_path / "out"
    out.mkdir()
    (out / "s.c").write_text("precious\n")
    return out


def _assert_untouched(out: Path) -> None:
    assert sorted(p.name for p in out.iterdir()) == ["s.c"]
    assert (out / "s.c").read_text() == "precious\n"


@pytest.mark.parametrize("text,fragment", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_spec_is_refused_cleanly(text, fragment, tmp_path, out_dir, capsys):
    spec = tmp_path / "bad.yaml"
    spec.write_text(text)
    start = time.perf_counter()
    code = main([str(spec), "--lang", "all", "-o", str(out_dir)])
    elapsed = time.perf_counter() - start
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.strip().splitlines()) == 1, err
    assert str(spec) in err and fragment in err, err
    assert "Traceback" not in err
    assert elapsed < 10.0
    _assert_untouched(out_dir)


def test_one_bad_spec_among_good_ones_writes_nothing(tmp_path, out_dir, capsys):
    good = tmp_path / "good.yaml"
    good.write_text("name: g\nequation: x^2 + y^2 - 1\n")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: b\nequation: sin(x)\n")
    assert main([str(good), str(bad), "-o", str(out_dir)]) == 2
    _assert_untouched(out_dir)


def test_missing_file_and_bad_options(tmp_path, out_dir, capsys):
    assert main([str(tmp_path / "nope.yaml"), "-o", str(out_dir)]) == 2
    assert "nope.yaml" in capsys.readouterr().err
    good = tmp_path / "good.yaml"
    good.write_text(GOOD)
    assert main([str(good), "--lang", "fortran", "-o", str(out_dir)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    _assert_untouched(out_dir)


def test_console_script_exit_status_and_output(tmp_path):
    """The installed `implgen` command, as a user runs it."""
    exe = shutil.which("implgen") or str(Path(sys.executable).parent / "implgen")
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: s\nequation: __import__('os')\n")
    proc = subprocess.run([exe, str(bad), "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "bad.yaml" in proc.stderr and "Traceback" not in proc.stderr
    assert not (tmp_path / "out").exists()
    good = tmp_path / "good.yaml"
    good.write_text(GOOD)
    proc = subprocess.run([exe, str(good), "--lang", "c", "-o", str(tmp_path / "out")], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["s.c", "s.h"]
