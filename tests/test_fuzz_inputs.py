"""Fuzzing the readers of user text with Hypothesis: the equation parser, the spec loader and the scene loader.

Inputs are built valid from strategies and then broken in exactly one place (tests/fuzz_strategies.py), or are
the example files with bytes flipped, snippets inserted, slices deleted or repeated. The property is the
bad-input contract: every input ends in success or a UserError whose message is one line naming the file,
never another exception, never a file written on failure, never a hang (each example runs under an alarm).
Where a spec loads, it is also generated (C and Python) and the output holds the re-printed equation, never
the raw text. Parsed equations print back to text that parses to the same polynomial.

The default profile (tests/conftest.py) is small and derandomized, so `make test` is quick and reproducible;
`HYPOTHESIS_PROFILE=long` runs many more random examples (docs/testing.md#fuzzing). Every failure found so
far is replayed as an explicit case from tests/fuzz_corpus/.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import signal
import sys
from pathlib import Path

import pytest
import yaml
from hypothesis import event, given
from hypothesis import strategies as st

from conftest import fuzz_settings
from fuzz_strategies import (
    SCENES,
    SHAPES,
    bad_equations,
    broken,
    deep_scenes,
    example_files,
    expressions,
    mutated,
    poisoned,
    scenes,
    specs,
)
from implgen.animation.frames import load_frames
from implgen.cli import main
from implgen.errors import UserError
from implgen.spec.entry import load_spec
from implgen.spec.grammar import ParseError, format_expression, parse_expression, split_equation
from implgen.spec.parse import VARIABLES, exact_polynomial, param_symbol

ROOT = Path(__file__).resolve().parent.parent
CORPUS = Path(__file__).resolve().parent / "fuzz_corpus"
TIME_LIMIT = 30  # seconds per example: a hang, not a slow machine


class Hang(BaseException):
    """Raised by the alarm; a BaseException so no `except Exception` in the code under test swallows it."""


@contextlib.contextmanager
def time_limit(seconds: float = TIME_LIMIT):
    def ring(signum, frame):
        raise Hang(f"no answer within {seconds} s")

    old = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def _stack_depth() -> int:
    frame, n = sys._getframe(1), 0
    while frame is not None:
        frame, n = frame.f_back, n + 1
    return n


@contextlib.contextmanager
def command_line_stack(frames_above_main: int = 10):
    """Python's recursion limit as the code under test has it under `implgen` from a shell: the default
    limit, less the few frames from the interpreter to cli.main. Hypothesis raises the limit by up to 2,000
    frames while a test runs, which would hide a walk that overflows on the command line (docs:
    200 levels of CSG); this puts it back for the duration of the call."""
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(_stack_depth() + 1000 - frames_above_main)
    try:
        yield
    finally:
        sys.setrecursionlimit(limit)


def outcome(load, *args):
    """(value, None) on success, (None, message) for a UserError; anything else propagates and fails. The load
    runs with the recursion room it has on the command line (command_line_stack)."""
    with time_limit(), command_line_stack():
        try:
            value = load(*args)
            event("accepted")
            return value, None
        except UserError as err:
            message = str(err)
    assert message and "\n" not in message and message.isprintable(), repr(message)
    event(f"refused: {message.split(': ', 2)[-1][:40]}")
    return None, message


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    """A scratch tree: shapes/ (a link to the example shapes, so scenes' `../shapes/x.yaml` resolve),
    scenes/ for scene files under test, specs/ for spec files under test."""
    root = tmp_path_factory.mktemp("fuzz")
    (root / "shapes").symlink_to(SHAPES)
    (root / "scenes").mkdir()
    (root / "specs").mkdir()
    return root


def dump(doc, flow: bool | None = None) -> str:
    """YAML text of a document. PyYAML's writer recurses a few frames per level, so documents nested hundreds
    of levels deep (fuzz_strategies.DEEP_LEVELS) are written with room to recurse; the code under test runs
    with the usual limit."""
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 20_000))
    try:
        return yaml.safe_dump(doc, allow_unicode=True, sort_keys=False, width=10_000, default_flow_style=flow)
    finally:
        sys.setrecursionlimit(limit)


def run_cli(argv: list[str]) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err), time_limit():
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


def assert_refused_cleanly(code: int, err: str, names: str, outputs: list[Path]) -> None:
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("implgen: error: ") and names in err, err
    assert "Traceback" not in err
    for path in outputs:
        assert not path.exists(), f"{path} written on failure"


# --------------------------------------------------------------------------------------- equations

PARAMS = ["a", "r"]
SYMBOLS = {p: param_symbol(p) for p in PARAMS}


@fuzz_settings(200)
@given(expressions(PARAMS))
def test_parsed_equations_print_back_to_the_same_polynomial(text):
    with time_limit():
        try:
            parsed = parse_expression(text, VARIABLES, SYMBOLS, 24)
        except ParseError as err:  # degree past 24, division by a zero constant, ...
            assert "\n" not in str(err)
            return
        shown = format_expression(parsed.expr, {s: p for p, s in SYMBOLS.items()})
        again = parse_expression(shown, VARIABLES, SYMBOLS, 24)
        as_written = parse_expression(parsed.text, VARIABLES, SYMBOLS, 24)  # the user's tree printed back
    assert exact_polynomial(again.expr - parsed.expr, list(SYMBOLS.values())) == 0
    assert exact_polynomial(as_written.expr - parsed.expr, list(SYMBOLS.values())) == 0
    assert as_written.text == parsed.text  # printed back, it prints the same again
    poly = exact_polynomial(parsed.expr, list(SYMBOLS.values()))
    degree = max((sum(m[:3]) for m in poly.monoms()), default=0) if poly != 0 else 0
    assert degree <= parsed.degree_bound
    assert len(poly.terms()) <= parsed.terms  # the bound that refuses expansion bombs is a bound


@fuzz_settings(300)
@given(bad_equations(PARAMS) | st.text(max_size=60))
def test_equation_parser_refuses_with_one_line(text):
    with time_limit():
        try:
            lhs, rhs = split_equation(text)
            parse_expression(lhs, VARIABLES, SYMBOLS, 24)
            parse_expression(rhs, VARIABLES, SYMBOLS, 24)
        except ParseError as err:
            assert str(err) and "\n" not in str(err)
            assert err.position is None or 0 <= err.position <= len(err.text)  # the caret's place is in the text


# -------------------------------------------------------------------------------------------- specs


@fuzz_settings(250)
@given(broken(specs()))
def test_spec_loader_broken_specs(work, case):
    how, doc = case
    path = work / "specs" / "spec.yaml"
    path.write_text(dump(doc), encoding="utf-8")
    spec, message = outcome(load_spec, path)
    assert spec is not None or message.startswith(f"{path}: "), message


@fuzz_settings(150)
@given(poisoned(specs()))
def test_spec_with_a_value_no_key_accepts_is_refused(work, case):
    """A huge integer, NaN, inf, a deep list or a stray mapping anywhere in a spec: refused, never read as
    something else (left out, a default, text)."""
    where, doc = case
    path = work / "specs" / "poisoned.yaml"
    path.write_text(dump(doc), encoding="utf-8")
    spec, message = outcome(load_spec, path)
    assert spec is None, f"accepted with {where} poisoned"
    assert message.startswith(f"{path}: "), message


@fuzz_settings(40)
@given(st.one_of(specs().map(lambda d: ("valid", d)), broken(specs())))
def test_spec_generation_writes_only_the_parsed_text(work, case):
    """Through the command line: a refusal writes nothing; generated files show the re-printed equation,
    never the raw text or the description."""
    how, doc = case
    if isinstance(doc, dict) and isinstance(doc.get("description"), str):
        doc["description"] = "Zq9 " + doc["description"]  # a marker no generated file has reason to hold
    path = work / "specs" / "gen.yaml"
    path.write_text(dump(doc), encoding="utf-8")
    out = work / "gen-out"
    shutil.rmtree(out, ignore_errors=True)
    code, _, err = run_cli([str(path), "--lang", "all", "-o", str(out), "-q"])
    if code != 0:
        assert_refused_cleanly(code, err, str(path), [out])
        return
    assert err == ""
    spec = load_spec(path)
    texts = [p.read_text() for p in out.iterdir()]
    assert len(texts) == 4  # .h, .c, .py, .glsl
    raw = doc["equation"].strip() if isinstance(doc.get("equation"), str) else ""
    for text in texts:
        assert spec.equation in text and "Zq9" not in text
        if len(raw) > 12 and raw not in spec.equation:
            assert raw not in text


# ------------------------------------------------------------------------------------------- scenes


def _refusal_through_cli(work: Path, path: Path) -> None:
    folder = work / "render-out"
    folder.mkdir(exist_ok=True)
    code, _, err = run_cli(["render", str(path), "-o", str(folder / "out.png"), "-q"])
    assert_refused_cleanly(code, err, str(path), [])
    assert list(folder.iterdir()) == []  # neither the image nor a temporary file


def _scene_loads_or_is_refused_cleanly(work: Path, path: Path) -> None:
    """The scene file loads, or is refused in one line naming it, by the loader and by `implgen render` alike
    (nothing written)."""
    scene, message = outcome(load_frames, path)
    if scene is None:
        assert message.startswith(f"{path}: "), message
        _refusal_through_cli(work, path)


@fuzz_settings(250)
@given(broken(scenes()))
def test_scene_loader_broken_scenes(work, case):
    how, doc = case
    path = work / "scenes" / "scene.yaml"
    path.write_text(dump(doc), encoding="utf-8")
    _scene_loads_or_is_refused_cleanly(work, path)


@fuzz_settings(60)
@given(deep_scenes(), st.booleans())
def test_scene_loader_deep_scenes(work, case, flow):
    """Objects nested deep (valid up to the CSG limit, then hundreds of levels of CSG, lists or mappings), in
    block or flow style: loaded, or refused in one line naming the file; never a RecursionError."""
    path = work / "scenes" / "deep.yaml"
    path.write_text(dump(case, flow=flow or None), encoding="utf-8")
    _scene_loads_or_is_refused_cleanly(work, path)


@fuzz_settings(150)
@given(poisoned(scenes()))
def test_scene_with_a_value_no_key_accepts_is_refused(work, case):
    where, doc = case
    path = work / "scenes" / "poisoned.yaml"
    path.write_text(dump(doc), encoding="utf-8")
    scene, message = outcome(load_frames, path)
    assert scene is None, f"accepted with {where} poisoned"
    assert message.startswith(f"{path}: "), message


# ---------------------------------------------------------------------------------- raw text mutation

SPEC_FILES = example_files(SHAPES)
SCENE_FILES = example_files(SCENES)


@fuzz_settings(300)
@given(st.sampled_from(SPEC_FILES).flatmap(lambda f: st.tuples(st.just(f[0]), mutated(f[1]))))
def test_mutated_example_specs(work, case):
    name, data = case
    path = work / "specs" / name
    path.write_bytes(data)
    try:
        spec, message = outcome(load_spec, path)
    finally:
        path.unlink()
    assert spec is not None or message.startswith(f"{path}: "), message


@fuzz_settings(200)
@given(st.sampled_from(SCENE_FILES).flatmap(lambda f: st.tuples(st.just(f[0]), mutated(f[1]))))
def test_mutated_example_scenes(work, case):
    name, data = case
    path = work / "scenes" / name
    path.write_bytes(data)
    try:
        _scene_loads_or_is_refused_cleanly(work, path)
    finally:
        path.unlink()


# ------------------------------------------------------------------------------------------ the corpus

CORPUS_FILES = sorted(CORPUS.glob("*.yaml")) if CORPUS.exists() else []


@pytest.mark.parametrize("path", CORPUS_FILES, ids=[p.stem for p in CORPUS_FILES])
def test_fuzz_corpus(path, tmp_path):
    """Inputs the fuzzer once broke the contract with. The first comment line says what kind of file it is
    (`# spec` or `# scene`) and the second what the run must print (`# ok`, or `# error: <fragment>`)."""
    kind, expect = (line.removeprefix("# ").strip() for line in path.read_text(encoding="utf-8").splitlines()[:2])
    target = tmp_path / ("scenes" if kind == "scene" else "specs") / path.name
    target.parent.mkdir()
    os.symlink(SHAPES, tmp_path / "shapes")
    target.write_bytes(path.read_bytes())
    out = tmp_path / ("out.png" if kind == "scene" else "out")
    argv = ["render", str(target), "-o", str(out), "-q", "--width", "4", "--height", "3"] if kind == "scene" else []
    argv = argv or [str(target), "--lang", "all", "-o", str(out), "-q"]
    code, _, err = run_cli(argv)
    if expect == "ok":
        assert code == 0 and err == "" and out.exists(), err
    else:
        fragment = expect.removeprefix("error: ")
        assert_refused_cleanly(code, err, str(target), [out])
        assert fragment in err, err
