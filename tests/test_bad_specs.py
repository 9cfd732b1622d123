"""Bad specs and `implgen SPEC...` options, run as the user runs them (tests/bad_input_harness.py): each exits
with status 2 and one line naming the file or option, writes nothing, runs no code, within 5 s and 300 MB.

Classes: code injection in equations, comments, control and non-ASCII characters, Python syntax beyond the
grammar, reserved and bad names, numbers past every range (huge integers, NaN, inf, 1e400, long digit runs),
degree and nesting bombs, structure (keys, types), YAML tricks (tags, aliases, merge keys, documents), files
that are not specs, and output paths.
"""

from __future__ import annotations

import pytest

from bad_input_harness import FIFO, FOLDER, SPHERE, Case, Link, check, run_batch
from test_generator_bad_input import CASES as IN_PROCESS_CASES

PWN = "__import__('os').system('touch PWNED')"
GOOD = "name: s\nequation: x^2 + y^2 + z^2 - 1\n"


def spec(case_id: str, text: str | bytes, fragment: str) -> Case:
    return Case(case_id, ["s.yaml", "-o", "out", "-q"], fragment, {"s.yaml": text})


def equation(case_id: str, eq: str, fragment: str, extra: str = "") -> Case:
    """A spec whose equation is `eq`, written as a YAML double-quoted string (escapes reach the parser)."""
    quoted = eq.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n").replace("\x00", "\\0")
    quoted = "".join(ch if ch.isprintable() or ch == " " else f"\\U{ord(ch):08x}" for ch in quoted)
    return spec(case_id, f'name: s\nequation: "{quoted}"\n{extra}', fragment)


NOT_ALLOWED = "is not allowed (an equation uses"
CASES: list[Case] = [spec(f"basic-{cid}", text, frag) for cid, text, frag in IN_PROCESS_CASES]

# ------------------------------------------------------------------------- code injection in equations
CASES += [
    equation("inject-c-comment", "x^2 + y^2 + z^2 - 1 # */ int pwned = 1; /*", "character '#' at position 21"),
    equation("inject-py-docstring", 'x^2 - 1 # """; import os; os.system("touch PWNED"); """', "character '#'"),
    equation("inject-bare-close-comment", "x^2 + y */ 2", "syntax error"),
    equation("inject-triple-quote", 'x + """', "character '\"'"),
    equation("inject-import", PWN, 'character "\'"'),
    equation("inject-import-no-quotes", "__import__(os).system(x)", "function calls are not allowed"),
    equation("inject-exec", "exec(x)", "function calls are not allowed"),
    equation("inject-eval", "eval(x) + y", "function calls are not allowed"),
    equation("inject-getattr", "x.__class__.__base__", "attribute access is not allowed"),
    equation("inject-dunder-name", "__builtins__ + x", "unknown symbol '__builtins__'"),
    equation("inject-lambda", "(lambda: x)()", "character ':'"),
    equation("inject-walrus", "(q := x) + y", "character ':'"),
    equation("inject-subscript", "x[0] + y", "character '['"),
    equation("inject-fstring", "f'{x}'", 'character "\'"'),
    equation("inject-semicolon", "x; y", "character ';'"),
    equation("inject-newline-statement", "x\nimport os", "syntax error"),
    equation("inject-backslash-continuation", "x + \\\ny", "character '\\\\'"),
    equation("inject-conditional", "x if y else z", "not a polynomial expression"),
    equation("inject-boolean-and", "1and y", "syntax error"),
    equation("inject-boolean-or", "x or y", "not a polynomial expression"),
    equation("inject-comparison", "x < y", "character '<'"),
    equation("inject-matmul", "x @ y", "character '@'"),
    equation("inject-bitwise", "x | y", "character '|'"),
    equation("inject-generator", "sum(x for x in y)", "function calls are not allowed"),
    equation("inject-keyword-await", "await x", "not a polynomial expression"),
    equation("inject-yield", "(yield x)", "not a polynomial expression"),
    equation("inject-modulo", "x % 2", "character '%'"),
    equation("inject-floor-division", "x // 2 + y", "only + - * / and ^ (or **) are allowed"),
    equation("inject-ellipsis", "x + ...", "not a number"),
    equation("inject-complex", "x + 1j", "not a number"),
]

# ------------------------------------------------------------------ control characters and non-ASCII
CASES += [
    equation("char-nul", "x\x00 + y", "character U+0000 at position 2"),
    equation("char-escape", "x + \x1b[31my", "character U+001B"),
    equation("char-carriage-return", "x\r + y", "character U+000D"),
    equation("char-form-feed", "x \x0c+ y", "character U+000C"),
    equation("char-unicode-minus", "x\u2212y", "character U+2212"),
    equation("char-superscript", "x\u00b2 + y", "character U+00B2"),
    equation("char-zero-width", "x\u200b + y", "character U+200B"),
    equation("char-bom", "\ufeffx + y", "character U+FEFF"),
    equation("char-fullwidth-digit", "x + \uff11", "character U+FF11"),
    equation("char-cyrillic-x", "\u0445 + y", "character U+0445"),
    equation("char-emoji", "x + \U0001f600", "character U+1F600"),
    equation("char-right-to-left", "x + \u202ey", "character U+202E"),
    spec("file-nul-byte", b"name: s\nequation: x\x00\n", "is not a text file"),
    spec("file-latin1", b"name: s\nequation: x\ndescription: caf\xe9\n", "is not a text file"),
    spec("file-control-char", "name: s\nequation: x\x07\n", "invalid YAML"),
]

# ------------------------------------------------------------------------------------------- names
CASES += [
    spec("name-rt-scene", "name: rt_scene\nequation: x\n", "reserved by implgen"),
    spec("name-ig", "name: ig\nequation: x\n", "reserved by implgen"),
    spec("name-ig-shape", "name: ig_shape\nequation: x\n", "reserved by implgen"),
    spec("name-upper-rt", "name: RT_X\nequation: x\n", "reserved by implgen"),
    spec("name-implgen", "name: implgen_shape\nequation: x\n", "reserved by implgen"),
    spec("name-header-math", "name: math\nequation: x\n", "is reserved"),
    spec("name-header-stdio", "name: Stdio\nequation: x\n", "C header"),
    spec("name-header-runtime", "name: tracer\nequation: x\n", "C header"),
    spec("name-module-numpy", "name: numpy\nequation: x\n", "reserved by implgen"),
    spec("name-module-inspect", "name: inspect\nequation: x\n", "'inspect' is the name of a Python module"),
    spec("name-module-json", "name: json\nequation: x\n", "is the name of a Python module"),
    spec("name-module-ctypes", "name: CTypes\nequation: x\n", "is the name of a Python module"),
    spec("name-module-sympy", "name: sympy\nequation: x\n", "is the name of a Python module"),
    spec("name-c-keyword", "name: struct\nequation: x\n", "reserved word"),
    spec("name-py-keyword", "name: lambda\nequation: x\n", "reserved word"),
    spec("name-underscore", "name: _hidden\nequation: x\n", "not an identifier"),
    spec("name-too-long", f"name: {'a' * 65}\nequation: x\n", "not an identifier"),
    spec("name-empty", "name: ''\nequation: x\n", "not an identifier"),
    spec("name-number", "name: 12\nequation: x\n", "12 is not an identifier"),
    spec("name-null", "name:\nequation: x\n", "not an identifier"),
    spec("name-dash", "name: my-shape\nequation: x\n", "not an identifier"),
    spec("name-nul", 'name: "s\\0"\nequation: x\n', "not an identifier"),
    spec("name-non-ascii", "name: \u00e9t\u00e9\nequation: x\n", "not an identifier"),
    spec("name-list", "name: [a]\nequation: x\n", "a list is not an identifier"),
    spec("param-keyword", "name: s\nequation: x - a\nparams: {for: 1}\n", "reserved word"),
    spec("param-underscore", "name: s\nequation: x\nparams: {_a: 1}\n", "not an identifier"),
    spec("param-number-name", "name: s\nequation: x\nparams: {1: 1}\n", "not an identifier"),
]

# ------------------------------------------------------------------------------------------ numbers
BIG = "9" * 400
CASES += [
    spec("param-huge-int", f"name: s\nequation: x - a\nparams: {{a: {BIG}}}\n", "a number of about 1e400 is outside"),
    spec("param-huge-negative", f"name: s\nequation: x - a\nparams: {{a: -{BIG}}}\n", "is outside"),
    spec(
        "param-over-4300-digits", "name: s\nequation: x - a\nparams: {a: " + "9" * 5000 + "}\n", "more than 4300 digits"
    ),
    spec("param-1e400", "name: s\nequation: x - a\nparams: {a: 1e400}\n", "finite number, not inf"),
    spec("param-text-1e400", "name: s\nequation: x - a\nparams: {a: '1e400'}\n", "finite number, not inf"),
    spec("param-text-nan", "name: s\nequation: x - a\nparams: {a: 'nan'}\n", "finite number, not nan"),
    spec("param-yaml-NaN", "name: s\nequation: x - a\nparams: {a: .NaN}\n", "finite number, not nan"),
    spec("param-minus-inf", "name: s\nequation: x - a\nparams: {a: -.inf}\n", "finite number, not -inf"),
    spec("param-above-range", "name: s\nequation: x - a\nparams: {a: 1.5e9}\n", "outside [-1e+09, 1e+09]"),
    spec("param-list", "name: s\nequation: x - a\nparams: {a: [1, 2]}\n", "finite number, not a list"),
    spec("params-not-mapping", "name: s\nequation: x\nparams: [a, b]\n", "params: must be a mapping"),
    spec(
        "params-too-many",
        "name: s\nequation: x\nparams: {" + ", ".join(f"p{i}: 1" for i in range(65)) + "}\n",
        "more than 64",
    ),
    equation("const-81-digits", "x + " + "1" * 81, "more than 80 digits"),
    equation("const-1e400", "x * 1e400", "number is not finite"),
    equation("const-1e-400", "x * 1e-400 + y", "constant too large"),
    equation("const-exponent-underflow", "x * 1e-99999999 + y", "has an exponent beyond ±400"),
    equation("const-zero-exponent-underflow", "x + 0e-9999999999", "has an exponent beyond ±400"),
    equation("const-exponent-overflow", "x * 1e99999999 + y", "number is not finite"),
    equation("const-power-tower", "x + 10^10^10", "constant power too large"),
    equation("const-product-overflow", "x + 10^70 * 10^70 * 10^70 * 10^70", "constant too large"),
    equation("const-division-tiny", "x / 10^70 / 10^70 / 10^70 / 10^70", "beyond 2^900"),
    equation("coefficient-beyond-double", "(2^200*x)^5 + y", "beyond 2^900"),
    equation("coefficient-tiny", "(x/2^200)^5 + y", "beyond 2^900"),
    equation("coefficient-param-product", "(2^120*x*a)^8 + y", "beyond 2^900", "params: {a: 1}\n"),
    equation("degree-25", "x^25 + y", "degree would exceed 24"),
    equation("degree-bomb-sum", "(x+y+z)^10000", "degree would exceed 24"),
    equation("degree-bomb-nested", "((((x^2)^2)^2)^2)^2", "degree would exceed 24"),
    equation("degree-bomb-tower", "x^(2^64)", "degree would exceed 24"),
    equation("degree-bomb-power-of-product", "(2*x)^99999999999", "degree would exceed 24"),
    equation("degree-bomb-param-product", "x + (3*a)^(10^12)", "parameters raised", "params: {a: 1}\n"),
    equation(
        "expansion-bomb-params",
        "x + (a+b+c+d+e+f+g+h)^20",
        "would expand to up to 888,031 terms (at most 20,000)",
        "params: {a: 1, b: 1, c: 1, d: 1, e: 1, f: 1, g: 1, h: 1}\n",
    ),
    equation(
        "expansion-bomb-product",
        "x + (a+b+c+d)^30 * (e+f+g+h)^30",
        "would expand to up to",
        "params: {a: 1, b: 1, c: 1, d: 1, e: 1, f: 1, g: 1, h: 1}\n",
    ),
    equation("degree-bomb-huge-exponent", "(x+1)^99999999999999999999", "degree would exceed 24"),
    equation("degree-product-chain", "*".join(["(x+y+1)"] * 30), "degree would exceed 24"),
    equation(
        "expanded-degree-24-too-large",
        " + ".join(
            f"{i % 7 + 1}*x^{a}*y^{b}*z^{24 - a - b}"
            for i, (a, b) in enumerate((a, b) for a in range(25) for b in range(25 - a))
            if i < 200
        ),
        "too large to generate in bounded time",
    ),
    equation("degree-mult-chain", "*".join(["x"] * 3000), "nested"),
    equation(
        "param-power-overflow",
        "x^2 + y^2 + z^2 - a^40",
        "params: with these params a coefficient",
        "params: {a: 1e9}\n",
    ),
    equation("param-power-overflow-product", "x*a^20*b^20 + y", "reaches 2^", "params: {a: 1e9, b: 1e9}\n"),
    equation("param-degree-bomb", "x + a^100", "parameters raised to a degree above 64", "params: {a: 1}\n"),
    equation("exponent-float", "x^2.5 + y", "non-negative integer"),
    equation("exponent-param", "x^a", "exponent must be a constant", "params: {a: 2}\n"),
    equation("deep-unary", "-" * 5000 + "x", "nested"),
    equation("deep-parentheses-110", "(" * 110 + "x" + ")" * 110, "parentheses nested deeper than 100"),
    equation(
        "deep-tree-55-levels",
        "x^2 + z^2 + " + "b + a*(" * 55 + "y" + ")" * 55,
        "nested 110 levels deep inside one another (at most 64)",
        "params: {a: 0.5, b: 0.1}\n",
    ),
    equation("equation-too-long", "x" + " + x" * 6000, "longer than 20000 characters"),
    equation("long-underscore-number", "x + " + "1_" * 50 + "1", "more than 80 digits"),
    equation("hex-exponent-bomb", "x^0xffffffffff", "degree would exceed 24"),
    spec("bounds-huge", f"name: s\nequation: x\nbounds: {{x: [-1, {BIG}]}}\n", "bounds.x"),
    spec("bounds-nan", "name: s\nequation: x\nbounds: {x: [.nan, 1]}\n", "must be finite"),
    spec("bounds-expression-huge", "name: s\nequation: x - a\nparams: {a: 1e9}\nbounds: {x: [0, a^3]}\n", "outside"),
    spec("bounds-injection", "name: s\nequation: x\nbounds: {x: ['0 # */', 1]}\n", "character '#'"),
    spec("bounds-variable", GOOD + "bounds: {x: [-1, z]}\n", "unknown symbol 'z'"),
    spec("bounds-equal", GOOD + "bounds: {x: [1, 1]}\n", "low must be below high"),
]

# ---------------------------------------------------------------------------------------- structure
CASES += [
    spec("equation-list", "name: s\nequation: [x, y]\n", "equation: must be text"),
    spec("equation-mapping", "name: s\nequation: {x: 1}\n", "equation: must be text"),
    spec("equation-null", "name: s\nequation:\n", "equation: must be text"),
    spec("equation-bool", "name: s\nequation: yes\n", "equation: must be text"),
    spec("equation-empty", "name: s\nequation: ''\n", "expression is empty"),
    spec("equation-three-sides", "name: s\nequation: x = y = z\n", "single '='"),
    spec("equation-empty-side", "name: s\nequation: 'x ='\n", "single '='"),
    spec("description-list", GOOD + "description: [a]\n", "description: must be text"),
    spec("description-too-long", GOOD + f"description: {'a' * 2001}\n", "longer than 2000"),
    spec("title-number", GOOD + "title: 3\n", "title: must be text"),
    spec("title-too-long", GOOD + f"title: {'t' * 81}\n", "title: longer than 80"),
    spec("reference-mapping", GOOD + "reference: {a: 1}\n", "reference: must be text"),
    spec("title-escape", GOOD + 'title: "\\e[31mred\\e[0m"\n', "title: control character U+001B at position 1"),
    spec("description-nul", GOOD + 'description: "a\\0b"\n', "description: control character U+0000 at position 2"),
    spec("reference-del", GOOD + 'reference: "x\\x7f"\n', "reference: control character U+007F"),
    spec("title-c1", GOOD + 'title: "a\\x9bb"\n', "title: control character U+009B"),
    spec("title-bidi", GOOD + 'title: "abc\\u202edcba"\n', "title: control character U+202E at position 4"),
    spec("ranges-list", GOOD + "ranges: [1, 2]\n", "ranges: must be a mapping"),
    spec("ranges-undeclared", GOOD + "ranges: {a: [0, 1]}\n", "ranges: 'a' is not a declared param"),
    spec("ranges-reversed", "name: s\nequation: x - a\nparams: {a: 1}\nranges: {a: [2, 0]}\n", "low must be below"),
    spec("ranges-default-out", "name: s\nequation: x - a\nparams: {a: 1}\nranges: {a: [2, 3]}\n", "default 1"),
    spec("ranges-nan", "name: s\nequation: x - a\nparams: {a: 1}\nranges: {a: [.nan, 3]}\n", "ranges.a"),
    spec("ranges-overflow", "name: s\nequation: x - a^9\nparams: {a: 1}\nranges: {a: [0, 1e300]}\n", "ranges.a"),
    spec("key-case", "Name: s\nequation: x\n", "unknown key 'Name'"),
    spec("key-number", GOOD + "1: x\n", "unknown key 1"),
    spec("scalar-document", "just text\n", "not a shape spec"),
    spec("number-document", "12\n", "not a shape spec"),
    spec("comment-only", "# nothing here\n", "not a shape spec"),
    spec("two-documents", GOOD + "---\n" + GOOD, "invalid YAML"),
    spec("python-tag-name", "name: !!python/name:os.system\nequation: x\n", "invalid YAML"),
    spec("python-module-tag", "name: s\nequation: !!python/module:os\n", "invalid YAML"),
    spec("binary-tag", "name: !!binary aGVsbG8=\nequation: x\n", "not an identifier"),
    spec("set-tag", "name: s\nequation: !!set {x}\n", "equation: must be text"),
    spec("unknown-tag", "name: !pwn s\nequation: x\n", "invalid YAML"),
    spec(
        "alias-bomb",
        "a: &a [1, 1, 1, 1, 1, 1, 1, 1, 1, 1]\n"
        + "".join(
            f"{c}: &{c} [*{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}, *{p}]\n"
            for p, c in zip("abcdefgh", "bcdefghi")
        )
        + GOOD,
        "more than 100000 values",
    ),
    spec("alias-cycle", "name: s\nequation: x\nparams: &p {a: *p}\n", "cycle"),
    spec("alias-undefined", "name: *nope\nequation: x\n", "invalid YAML"),
    spec(
        "merge-key-bomb",
        "b: &b {x: 1}\n"
        + "".join(
            f"m{i}: &m{i} {{<<: [*{'b' if i == 0 else f'm{i - 1}'}], k{i}: [*{'b' if i == 0 else f'm{i - 1}'}, "
            f"*{'b' if i == 0 else f'm{i - 1}'}]}}\n"
            for i in range(25)
        )
        + GOOD,
        "more than 100000 values",
    ),
    spec("merge-key-unknown", "base: &b {name: s, equation: x}\n<<: *b\n", "unknown key 'base'"),
    spec("merge-key-not-mapping", "<<: [1, 2]\nname: s\nequation: x\n", "invalid YAML"),
    spec("duplicate-key-in-params", "name: s\nequation: x - a\nparams: {a: 1, a: 2}\n", "duplicate key 'a'"),
    spec("huge-file", GOOD + "description: " + "a" * (1 << 20) + "\n", "larger than 1048576 bytes"),
    spec("tab-indent", "name: s\n\tequation: x\n", "invalid YAML"),
    spec("deep-flow-list", "name: s\nequation: x\nparams: " + "[" * 3000 + "]" * 3000 + "\n", "invalid YAML"),
    spec(
        "deep-block-mapping",
        GOOD + "params:\n" + "".join(" " * (2 * i + 2) + f"k{i}:\n" for i in range(600)),
        "nested too deeply",
    ),
]

# ------------------------------------------------------------------------------ files that are not specs
CASES += [
    Case("file-missing", ["nope.yaml", "-o", "out"], "not found (expected a shape spec file)"),
    Case("file-folder", ["dir.yaml", "-o", "out"], "is a folder, not a shape spec file", {"dir.yaml": FOLDER}),
    Case("file-fifo", ["p.yaml", "-o", "out"], "is a fifo, not a shape spec file", {"p.yaml": FIFO}),
    Case("file-dev-null", ["/dev/null", "-o", "out"], "is a device, not a shape spec file"),
    Case("file-dev-zero", ["/dev/zero", "-o", "out"], "is a device"),
    Case("file-etc-passwd", ["/etc/passwd", "-o", "out"], "not a shape spec"),
    Case("file-proc-status", ["/proc/self/status", "-o", "out"], "not a shape spec"),
    Case("file-png", ["pic.png", "-o", "out"], "is not a text file", {"pic.png": b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR"}),
    Case("file-a-scene", ["scene.yaml", "-o", "out"], "not a shape spec", {"scene.yaml": "objects: [{equation: y}]\n"}),
    Case("file-link-loop", ["loop.yaml", "-o", "out"], "cannot read", {"loop.yaml": Link("loop.yaml")}),
    Case("file-dangling-link", ["gone.yaml", "-o", "out"], "not found", {"gone.yaml": Link("nowhere.yaml")}),
    Case("file-name-too-long", ["a" * 300 + ".yaml", "-o", "out"], "cannot read"),
]

# ------------------------------------------------------------------------------------ output and options
CASES += [
    Case("out-is-a-file", [SPHERE, "-o", "out"], "exists and is not a folder", {"out": "precious\n"}, names="-o out"),
    Case("out-under-a-file", [SPHERE, "-o", "f/out"], "is not a folder", {"f": "x\n"}, names="-o f/out"),
    Case("out-in-proc", [SPHERE, "-o", "/proc/implgen-out"], "cannot write in /proc", names="-o /proc/implgen-out"),
    Case("out-in-sys", [SPHERE, "-o", "/sys/implgen/out"], "cannot write in /sys", names="-o /sys/implgen/out"),
    Case("out-name-too-long", [SPHERE, "-o", "o" * 300], "long", names="-o ooo"),
    Case("out-path-too-long", [SPHERE, "-o", "/".join(["d" * 200] * 25)], "long", names="-o ddd"),
    Case("out-link-loop", [SPHERE, "-o", "loop/out"], "is a link to nothing", {"loop": Link("loop")}, names="-o loop"),
    Case("out-fifo", [SPHERE, "-o", "p"], "exists and is not a folder", {"p": FIFO}, names="-o p"),
    Case("option-lang", [SPHERE, "--lang", "fortran", "-o", "out"], "invalid choice: 'fortran'", names="--lang"),
    Case("option-unknown", [SPHERE, "--colour", "red"], "unrecognized arguments: --colour", names="--colour"),
    Case("option-no-spec", ["-o", "out"], "the following arguments are required: SPEC.yaml", names="command line"),
    Case("option-o-without-value", [SPHERE, "-o"], "expected one argument", names="-o"),
    Case("bench-unknown", ["bench", "nothing"], "choose one of", names="bench"),
    Case("bench-gen-option", ["bench", "gen", "--nope"], "unrecognized arguments: --nope", names="implgen bench gen"),
    Case("bench-solvers-option", ["bench", "solvers", "--timed", "x"], "argument --timed", names="bench solvers"),
    Case("bench-render-option", ["bench", "render", "--width", "x"], "argument --width", names="bench render"),
    Case("demo-option", ["demo", "--x"], "unrecognized arguments: --x", names="implgen demo"),
    Case(
        "two-specs-same-name",
        ["a.yaml", "b.yaml", "-o", "out"],
        "writes s.c, which another spec given also writes",
        {"a.yaml": GOOD, "b.yaml": GOOD.replace("- 1", "- 2")},
        names="b.yaml",
    ),
    Case(
        "good-then-bad",
        ["a.yaml", "b.yaml", "-o", "out"],
        "function calls are not allowed",
        {"a.yaml": GOOD, "b.yaml": "name: t\nequation: sin(x)\n"},
        names="b.yaml",
    ),
]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    return run_batch(CASES, tmp_path_factory.mktemp("bad-specs"))


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_spec(case, results):
    check(case, results[0][case.id])


def test_bad_specs_fit_in_300_mb(results):
    assert results[1] < 300 << 20
