"""No user text becomes code: what reaches a generated file is re-printed or escaped for where it lands, and
no name a spec can choose collides with a symbol, macro or header of the runtime, the glue or the C library.

The escaping functions are checked on arbitrary text (Hypothesis) by the language itself: a C compiler sees
one comment and one string whose bytes are the input's, Python reads the literals back as the input.
"""

from __future__ import annotations

import ast
import ctypes
import importlib.metadata
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
import sympy
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import RUNTIME, SHAPE_FILES, compile_c, load_python_shape
from implgen.codegen import escape
from implgen.codegen.emit import generate
from implgen.compile.clib import WARNING_FLAGS, compiler
from implgen.errors import UserError
from implgen.outputs import write_text_files
from implgen.spec.entry import load_spec, parse_spec
from implgen.spec.grammar import format_expression, parse_expression
from implgen.spec.names import DEPENDENCY_MODULES, reserved_shape_name
from implgen.spec.parse import VARIABLES, exact_polynomial, param_symbol

ROOT = Path(__file__).resolve().parent.parent
NASTY = [
    "*/ int pwned = 1; /*",
    '"""\nimport os; os.system("touch PWNED")\n"""',
    "??/\n*/",
    "\\\n*/",
    "a\x00b\x1b[31m",
    "x² − ½ ​",
    "'''",
    "\r*/\r",
    "/*/",
    "*",
    "/",
    "\\",
    '"',
    "\U0001f600",
]
text = st.text(alphabet=st.characters(codec="utf-8"), max_size=40) | st.sampled_from(NASTY)


# ------------------------------------------------------------------------------------------ escaping


def _compile_c(tmp_path: Path, source: str, name: str) -> Path:
    c = tmp_path / f"{name}.c"
    c.write_text(source, encoding="utf-8")
    return compile_c(tmp_path / f"lib{name}.so", [c], sanitize=False, shared=True)


def test_c_comment_and_string_survive_a_compiler(tmp_path):
    """Every nasty text, in a comment between `*` and `/` characters and as a string: the library holds exactly
    the one string we put there, with the text's bytes, and no other symbol."""
    lines = []
    for i, t in enumerate(NASTY):
        lines.append(f"/*{escape.c_comment(t)}*/ /* *{escape.c_comment(t)}/ */")
        lines.append(f'const char s{i}[] = "{escape.c_string(t)}";')
    lib = ctypes.CDLL(str(_compile_c(tmp_path, "\n".join(lines) + "\n", "esc")))
    for i, t in enumerate(NASTY):
        got = ctypes.c_char_p(ctypes.addressof(ctypes.c_char.in_dll(lib, f"s{i}"))).value
        assert got == t.encode("utf-8").split(b"\0")[0]
    symbols = subprocess.run(
        ["nm", "-g", "--defined-only", str(tmp_path / "libesc.so")], capture_output=True, text=True
    ).stdout
    assert sorted(line.split()[-1] for line in symbols.splitlines()) == sorted(f"s{i}" for i in range(len(NASTY)))


@settings(max_examples=300, deadline=None, derandomize=True)
@given(text)
def test_c_comment_cannot_end_or_splice(t):
    out = escape.c_comment(t)
    assert all(" " <= ch < "\x7f" for ch in out)
    assert "*/" not in out and "/*" not in out and "?" not in out
    assert out[:1] not in ("*", "/") and out[-1:] not in ("*", "/")
    assert "\\\n" not in out


@settings(max_examples=300, deadline=None, derandomize=True)
@given(text)
def test_python_literals_read_back_exactly(t):
    assert ast.literal_eval('"""' + escape.py_docstring(t) + '"""') == t
    assert ast.literal_eval(escape.py_string(t)) == t
    assert all(" " <= ch < "\x7f" for ch in escape.py_string(t))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(text)
def test_c_string_is_printable_ascii_without_trigraphs(t):
    out = escape.c_string(t)
    assert all(" " <= ch < "\x7f" for ch in out) and "??" not in out
    # every quote and backslash in the output is escaped: the literal cannot end early
    assert re.fullmatch(r'(?:[^"\\]|\\.)*', out)


# ------------------------------------------------------------------------------ what generated files show


@pytest.mark.parametrize("path", SHAPE_FILES, ids=[p.stem for p in SHAPE_FILES])
def test_canonical_equation_parses_back_to_the_same_polynomial(path):
    spec = load_spec(path)
    symbols = {p: param_symbol(p) for p in spec.params}
    again = parse_expression(spec.equation.replace(" = 0", ""), VARIABLES, symbols, 24).expr
    assert exact_polynomial(again - spec.f, list(symbols.values())) == 0
    assert f"f(x, y, z) = {spec.equation}\n" in (ROOT / "generated" / f"{spec.name}.c").read_text()


def test_hostile_file_name_and_description_stay_text(tmp_path, monkeypatch):
    """A spec whose file name and description try to close the comment / docstring: the generated C compiles
    to exactly the shape's symbols, the module imports without running anything, and neither file holds
    the raw text."""
    monkeypatch.chdir(tmp_path)
    name = 'h"""x*\\y??\n z.yaml'
    payload = '*/ int pwned; /* """ ; import os; os.system("touch PWNED") ; """'
    path = tmp_path / name
    path.write_text(f"name: hostile\nequation: x^2 + y^2 + z^2 - a^2\nparams: {{a: 1}}\ndescription: '{payload}'\n")
    spec = load_spec(path)
    out = tmp_path / "out"
    files = generate(spec)
    for text_ in files.values():
        assert payload not in text_ and name not in text_ and "pwned" not in text_
    write_text_files(files, out)
    proc = subprocess.run(
        [
            compiler(),
            *WARNING_FLAGS,
            "-c",
            f"-I{RUNTIME}",
            f"-I{out}",
            "-o",
            str(tmp_path / "h.o"),
            str(out / "hostile.c"),
        ],
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr
    syms = subprocess.run(
        ["nm", "-g", "--defined-only", str(tmp_path / "h.o")], capture_output=True, text=True
    ).stdout.split()
    assert not [s for s in syms if "pwned" in s]
    module = load_python_shape("hostile", out)
    assert module.NAME == "hostile" and module.value([1.0, 0, 0], a=1.0) == 0.0
    assert not (tmp_path / "PWNED").exists()
    assert ast.literal_eval('"""' + escape.py_docstring(name) + '"""') == name  # the name shown is the name


def test_format_expression_uses_the_users_names():
    a = param_symbol("a")
    assert format_expression(sympy.Symbol("x") ** 2 - a**2, {a: "a"}) == "-a^2 + x^2"


# ------------------------------------------------------------------------------------------- names

GENERATED_SYMBOLS = (
    "{n}_coeffs",
    "{n}_value",
    "{n}_gradient",
    "{n}_bounds",
    "{n}_intersect",
    "{n}_first_hit",
    "{n}_normal",
    "{n}_shape",
    "{N}_DEGREE",
    "{N}_NPARAMS",
    "IMPLGEN_GENERATED_{N}_H",
)


def _names_that_make(symbol: str) -> set[str]:
    """Every shape name whose generated code would define `symbol`."""
    out = set()
    for pattern in GENERATED_SYMBOLS:
        regex = re.escape(pattern).replace(r"\{n\}", "(.+)").replace(r"\{N\}", "(.+)")
        m = re.fullmatch(regex, symbol)
        if m:
            stem = m.group(1)
            out |= {stem} if "{n}" in pattern else {stem, stem.lower()}
    return out


def _runtime_symbols(tmp_path: Path) -> set[str]:
    """Globals of a built scene library (runtime + glue; the test shape's own left out), every identifier in
    the templates and the runtime headers they include, directly or not (what shares a translation unit with
    generated code), the macros of the system headers, and libc/libm's exports."""
    from implgen.scene.build import build_scene
    from implgen.scene.load import parse_scene

    scene = parse_scene({"objects": [{"equation": "x^2 + y^2 + z^2 - 1", "name": "ball"}]}, "<t>")
    lib = build_scene(scene).library
    nm = subprocess.run(["nm", "-g", "--defined-only", str(lib)], capture_output=True, text=True).stdout
    symbols = {line.split()[-1] for line in nm.splitlines() if not line.split()[-1].startswith("ball_")}
    texts = [p.read_text() for p in (ROOT / "templates").rglob("*.j2")]
    pending, seen = [h for t in texts for h in re.findall(r'#include "(\w+\.h)"', t)], set()
    while pending:
        header = pending.pop()
        if header not in seen and (RUNTIME / header).exists():
            seen.add(header)
            texts.append((RUNTIME / header).read_text())
            pending += re.findall(r'#include "(\w+\.h)"', texts[-1])
    assert {"shape.h", "roots.h"} <= seen
    for t in texts:
        symbols |= set(re.findall(r"\b[A-Za-z_]\w*\b", t))
    includes = "".join(
        f"#include <{h}>\n"
        for h in ("math.h", "string.h", "stdlib.h", "stdio.h", "float.h", "limits.h", "stdint.h", "time.h", "pthread.h")
    )
    macros = subprocess.run(
        [compiler(), "-std=c99", "-dM", "-E", "-x", "c", "-"], input=includes, capture_output=True, text=True
    ).stdout
    symbols |= set(re.findall(r"^#define (\w+)", macros, re.M))
    for name in ("libc.so.6", "libm.so.6"):
        path = subprocess.run([compiler(), f"-print-file-name={name}"], capture_output=True, text=True).stdout.strip()
        if Path(path).exists():
            dyn = subprocess.run(
                ["nm", "-D", "--defined-only", str(Path(path).resolve())], capture_output=True, text=True
            ).stdout
            symbols |= {line.split()[-1].split("@")[0] for line in dyn.splitlines()}
    return symbols


def test_no_acceptable_shape_name_collides_with_a_runtime_symbol(tmp_path):
    symbols = _runtime_symbols(tmp_path)
    assert {"rt_scene_shape", "rt_scene_nshapes", "ig_real_roots", "IG_MAX_DEGREE", "ig_shape"} <= symbols
    clashes = []
    for symbol in symbols:
        for name in _names_that_make(symbol):
            if re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", name) and reserved_shape_name(name) is None:
                clashes.append((name, symbol))
    assert not clashes, clashes[:20]


def test_headers_the_generated_code_includes_are_not_shape_names():
    headers = set()
    for src in [*RUNTIME.glob("*.[ch]"), *(ROOT / "templates").rglob("*.j2")]:
        headers |= set(re.findall(r'#include\s*[<"](\w+)\.h[>"]', src.read_text()))
    assert {"math", "string", "shape", "roots", "tracer"} <= headers
    for h in headers:
        if re.fullmatch(r"[A-Za-z]\w*", h):
            assert reserved_shape_name(h) is not None, h
            assert reserved_shape_name(h.upper()) is not None, h


def test_python_modules_are_not_shape_names():
    """`inspect.py` in the output folder was imported by numpy in place of the standard library's:
    every module of the standard library, and every top-level package of implgen's dependencies, is refused."""
    modules = [m for m in sys.stdlib_module_names if re.fullmatch(r"[A-Za-z]\w*", m)]
    assert {"inspect", "json", "ctypes", "os", "types", "random"} <= set(modules)
    for name in modules:
        for spelling in (name, name.upper(), name.capitalize()):
            assert reserved_shape_name(spelling) is not None, spelling
    with pytest.raises(UserError, match=r"^s\.yaml: name: 'inspect' is the name of a Python module"):
        parse_spec({"name": "inspect", "equation": "x"}, "s.yaml")


def test_the_dependencies_top_level_packages_are_not_shape_names():
    """Read from pyproject.toml and the installed distributions, so a new dependency cannot be forgotten."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    wanted = {re.match(r"[A-Za-z0-9_.-]+", d).group(0).lower().replace("_", "-") for d in project["dependencies"]}
    tops: dict[str, set[str]] = {}
    for module, dists in importlib.metadata.packages_distributions().items():
        for dist in dists:
            tops.setdefault(dist.lower().replace("_", "-"), set()).add(module)
    assert wanted <= set(tops), wanted - set(tops)
    names = {m for d in wanted for m in tops[d] if re.fullmatch(r"[A-Za-z]\w*", m)}
    assert {"numpy", "sympy", "yaml", "PIL", "trimesh"} <= names
    assert names <= DEPENDENCY_MODULES, names - DEPENDENCY_MODULES
    assert all(reserved_shape_name(m) is not None for m in DEPENDENCY_MODULES)


@pytest.mark.parametrize(
    "name", ["rt_scene", "ig", "ig_shape", "RT_foo", "Ig_x", "rt", "math", "Stdio", "implgen_x", "pthread", "tracer"]
)
def test_reserved_names_are_refused_in_specs_and_scenes(name):
    with pytest.raises(UserError, match="reserved|header"):
        parse_spec({"name": name, "equation": "x"}, "<t>")


@settings(max_examples=200, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.from_regex(r"[A-Za-z][A-Za-z0-9_]{0,20}", fullmatch=True))
def test_accepted_names_make_only_their_own_symbols(name):
    """Whatever identifier is accepted, its generated symbols start with the name itself and none of them
    starts with a prefix the runtime owns."""
    if reserved_shape_name(name) is not None:
        return
    for pattern in GENERATED_SYMBOLS:
        symbol = pattern.format(n=name, N=name.upper())
        assert not symbol.lower().startswith(("ig_", "rt_")) or pattern.startswith("IMPLGEN")


# ------------------------------------------------------------------------------------------- constants


def test_coefficients_beyond_double_range_are_refused_at_validation():
    parse_spec({"name": "ok", "equation": "(2^150*x)^5 + y"}, "<t>")  # 2^750: fine
    with pytest.raises(UserError, match="coefficient of the expanded polynomial is beyond 2\\^900"):
        parse_spec({"name": "big", "equation": "(2^200*x)^5 + y"}, "<t>")  # 2^1000
    with pytest.raises(UserError, match="constant too large"):
        parse_spec({"name": "big", "equation": "x + 2^200 * 2^100"}, "<t>")


@pytest.mark.parametrize("printer", ["c", "python"])
def test_printers_refuse_a_constant_that_is_not_a_finite_double(printer):
    from implgen.codegen.backends import backend
    from implgen.codegen.backends.contract import ConstantRangeError

    doprint = backend(printer).printer().doprint
    assert "1.0/3.0" in doprint(sympy.Rational(1, 3)) or "1/3" in doprint(sympy.Rational(1, 3))
    for value in (sympy.Integer(2) ** 1100, sympy.Rational(1, 2**1100)):
        with pytest.raises(ConstantRangeError):
            doprint(value * sympy.Symbol("x"))
