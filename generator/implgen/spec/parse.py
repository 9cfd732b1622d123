"""Shape spec files: YAML (safe_load) -> validated `Spec`.

    name: piriform                      # identifier; names the generated files and functions
    equation: x^4 - x^3 + y^2 + z^2     # `expr` (meaning expr = 0) or `lhs = rhs`
    params: {a: 1.0}                    # optional ordered mapping name -> default number
    bounds: {x: [0, 1], y: [-0.5, 0.5]} # optional object-space box; numbers or expressions in params;
                                        # an axis left out is unbounded
    description: a peg top              # optional; title, reference (a citation) too: text, never in generated code
    ranges: {a: [0.5, 2]}               # optional: a slider's range per param (the viewer, the gallery)

Inside is f < 0 with f = lhs - rhs; the outward normal is grad f / |grad f|.
"""

from __future__ import annotations

import math
import unicodedata
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import sympy
from sympy.polys.domains import QQ
from sympy.polys.rings import ring

from implgen import abi, validate
from implgen.errors import UserError
from implgen.spec import paramvalues
from implgen.spec.fingerprint import code_key
from implgen.spec.grammar import (
    ParseError,
    check_depth,
    check_terms,
    format_expression,
    parse_expression,
    split_equation,
)
from implgen.spec.model import Spec
from implgen.spec.names import check_identifier, check_shape_name

MAX_DEGREE = abi.value("IG_MAX_DEGREE")  # the solvers' limit, read from runtime_c/roots.h
MAX_PARAMS = 64
MAX_DESCRIPTION = 2_000
MAX_TEXT = {"title": 80, "reference": 500, "description": MAX_DESCRIPTION}  # the spec's texts, in characters
MAX_COEFF_BITS = paramvalues.MAX_COEFF_BITS  # |numerator|, |denominator| of every expanded coefficient
# (2^900 ~ 8e270: room for the multinomial factors the ray coefficients multiply them by)
# Generation time grows with the size of f as written times its degree (Taylor coefficients, then one cse):
# about 1 s per 700 on the 2-core test machine, and faster than linear past that (an expanded degree-24
# polynomial of 1150 terms, size 169,000, took 8.5 minutes). The example shapes are below 400.
MAX_SIZE_DEGREE = 10_000
AXES = paramvalues.AXES
KEYS = ("name", "title", "description", "reference", "equation", "params", "ranges", "bounds")
X, Y, Z = sympy.symbols("x y z", real=True)
VARIABLES = {"x": X, "y": Y, "z": Z}


def param_symbol(name: str) -> sympy.Symbol:
    """Internal symbol for a user param: prefixed, so a param called `c`, `d`, `o` or `t` cannot collide
    with the names the generated code uses itself."""
    return sympy.Symbol(f"k_{name}", real=True)


@dataclass(frozen=True)
class SymbolicForm:
    """The SymPy side of a `Spec` (spec/model.py): the expression and the symbolic bounds."""

    f: sympy.Expr  # lhs - rhs, structure as written; x, y, z and k_* symbols
    bounds: dict[str, tuple[sympy.Expr, sympy.Expr]] | None  # axis -> (lo, hi) in k_* symbols
    param_symbols: list[sympy.Symbol]

    def specialise(self, spec: Spec, values: Mapping[str, float], name: str | None = None) -> Spec:
        """The same shape with the given params folded into the equation as constants."""
        unknown = set(values) - set(spec.params)
        if unknown:
            raise UserError(spec.source, f"unknown params {sorted(unknown)} for shape {spec.name!r}")
        new_name = name or spec.name
        check_shape_name(spec.source, "name", new_name)
        subs = {
            param_symbol(k): sympy.nsimplify(validate.number(spec.source, f"params.{k}", v), rational=True)
            for k, v in values.items()
        }
        bounds = None
        if self.bounds is not None:
            bounds = {a: (lo.subs(subs), hi.subs(subs)) for a, (lo, hi) in self.bounds.items()}
        rest = {k: v for k, v in spec.params.items() if k not in values}
        folded = {**spec.folded, **{k: float(v) for k, v in values.items()}}
        texts = {"title": spec.title, "reference": spec.reference}
        ranges = {k: r for k, r in spec.ranges.items() if k in rest}
        return make_spec(
            new_name, self.f.subs(subs), rest, spec.degree, bounds, spec.description, spec.source, folded, texts, ranges
        )


def make_spec(
    name: str,
    f: sympy.Expr,
    params: dict[str, float],
    degree: int,
    bounds: dict[str, tuple[sympy.Expr, sympy.Expr]] | None,
    description: str,
    source: str,
    folded: dict[str, float] | None = None,
    texts: Mapping[str, str] | None = None,
    ranges: Mapping[str, tuple[float, float]] | None = None,
    written: str = "",
) -> Spec:
    """A `Spec` with its symbolic part at hand, and the plain data a scene reads computed from it."""
    symbols = [param_symbol(p) for p in params]
    names = {param_symbol(p): p for p in params}
    trees = None
    if bounds is not None:
        trees = {a: (paramvalues.tree_of(lo, names), paramvalues.tree_of(hi, names)) for a, (lo, hi) in bounds.items()}
        if any(t is None for pair in trees.values() for t in pair):
            raise ValueError(f"bounds of {name!r} are not polynomials in the params")  # the parser ensures it
    poly = exact_polynomial(f, symbols)
    terms = [(math.log2(abs(c.numerator)) - math.log2(c.denominator), monom[3:]) for monom, c in poly.terms() if c != 0]
    folded = folded or {}
    bounds_text = None if bounds is None else {a: (str(lo), str(hi)) for a, (lo, hi) in bounds.items()}
    spec = Spec(
        name=name,
        equation=canonical_equation(f, params),
        params=params,
        degree=degree,
        param_terms=terms,
        bounds_trees=trees,
        spec_key=code_key(name, str(f), params, bounds_text, folded),
        symbolic_part=Spec.parsed(SymbolicForm(f=f, bounds=bounds, param_symbols=symbols)),
        description=description,
        source=source,
        folded=folded,
        title=(texts or {}).get("title", ""),
        reference=(texts or {}).get("reference", ""),
        ranges=dict(ranges or {}),
        written=written,
    )
    return spec


def _parse_params(source: str, raw: Any) -> dict[str, float]:
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        raise UserError(source, "params: must be a mapping of name to default number")
    if len(raw) > MAX_PARAMS:
        raise UserError(source, f"params: more than {MAX_PARAMS}")
    params: dict[str, float] = {}
    for name, value in raw.items():
        check_identifier(source, "params", name)
        if name in AXES:
            raise UserError(source, f"params: {name!r} shadows the coordinate {name}")
        number = validate.number(source, f"params.{name}", value, text_ok=True)
        params[name] = int(value) if isinstance(value, int) else number
    return params


def canonical_equation(f: sympy.Expr, params: Mapping[str, float]) -> str:
    """f (meaning f = 0) as generated files show it: printed from the expression tree under the user's param
    names, so the text is the parsed equation, never what was typed."""
    return format_expression(f, {param_symbol(p): p for p in params})


def _parse_equation(source: str, text: Any, params: dict[str, float]) -> tuple[sympy.Expr, int, str]:
    """f = lhs - rhs, its degree, and the equation as written (the user's tree printed back: spec/written.py)."""
    if not isinstance(text, (str, int, float)) or isinstance(text, bool):
        raise UserError(source, "equation: must be text such as 'x^2 + y^2 + z^2 - 1'")
    symbols = {p: param_symbol(p) for p in params}
    text = str(text)
    try:
        lhs_text, rhs_text = split_equation(text)
        lhs = _side(text, lhs_text, 0, symbols)
        rhs = _side(text, rhs_text, len(lhs_text) + 1, symbols)  # a bare expr's right side is "0": no error
        check_terms(lhs.terms + rhs.terms)
        f = lhs.expr - rhs.expr
        check_depth(f)  # lhs - rhs: the right side negated can be a level deeper than either side
        as_written = f"{lhs.text} = {rhs.text}" if "=" in text else lhs.text
    except ParseError as err:
        raise UserError(source, f"equation: {err}", err.position) from None
    poly = exact_polynomial(f, list(symbols.values()))
    if poly == 0:
        raise UserError(source, "equation: is identically zero (every point would be on the surface)")
    degree = max(sum(m[:3]) for m in poly.monoms())
    if degree == 0:
        raise UserError(source, "equation: has no x, y or z (a constant, not a surface)")
    if degree > MAX_DEGREE:
        raise UserError(source, f"equation: degree {degree} is above the highest supported, {MAX_DEGREE}")
    ops = int(sympy.count_ops(f))
    if ops * degree > MAX_SIZE_DEGREE:
        raise UserError(
            source,
            f"equation: too large to generate in bounded time: {ops} operations at degree {degree} "
            f"(operations x degree at most {MAX_SIZE_DEGREE}; a factored form such as (x+y+z+1)^24 is small)",
        )
    for coeff in poly.coeffs():
        if max(abs(int(coeff.numerator)).bit_length(), int(coeff.denominator).bit_length()) > MAX_COEFF_BITS:
            raise UserError(
                source,
                f"equation: a coefficient of the expanded polynomial is beyond 2^{MAX_COEFF_BITS} "
                f"or below 2^-{MAX_COEFF_BITS} in size (not a normal double)",
            )
    return f, degree, as_written


def _side(text: str, part: str, offset: int, symbols: dict[str, sympy.Symbol]):
    """One side of the equation `text`, which starts at `offset` in it (an error points into `text`)."""
    try:
        return parse_expression(part, VARIABLES, symbols, MAX_DEGREE)
    except ParseError as err:
        raise err.within(text, offset) from None


def exact_polynomial(f: sympy.Expr, params: list[sympy.Symbol]):
    """f as an element of the polynomial ring QQ[x, y, z, params] (exact rational arithmetic)."""
    R, *_ = ring([X, Y, Z, *params], QQ)
    return R.from_expr(f) if f != 0 else R.zero


def _parse_bounds(source: str, raw: Any, params: dict[str, float]) -> dict[str, tuple[sympy.Expr, sympy.Expr]] | None:
    if raw is None:
        return None
    if not isinstance(raw, dict) or not raw:
        raise UserError(source, "bounds: must be a mapping such as {x: [-1, 1], y: [-1, 1], z: [-1, 1]}")
    symbols = {p: param_symbol(p) for p in params}
    defaults = {param_symbol(k): v for k, v in params.items()}
    bounds: dict[str, tuple[sympy.Expr, sympy.Expr]] = {}
    for axis, pair in raw.items():
        if axis not in AXES:
            raise UserError(source, f"bounds: unknown axis {str(axis)[:20]!r} (use x, y, z)")
        if not isinstance(pair, list) or len(pair) != 2:
            raise UserError(source, f"bounds.{axis}: must be a pair [low, high]")
        ends = []
        for item in pair:
            if isinstance(item, bool) or not isinstance(item, (int, float, str)):
                raise UserError(source, f"bounds.{axis}: {validate.describe(item)} is not a number or expression")
            if isinstance(item, float) and not math.isfinite(item):
                raise UserError(source, f"bounds.{axis}: must be finite (leave the axis out to leave it open)")
            try:
                end = parse_expression(str(item), {}, symbols, 0).expr
            except ParseError as err:
                raise UserError(source, f"bounds.{axis}: {err}") from None
            validate.number(source, f"bounds.{axis}", float(end.subs(defaults)))
            ends.append(end)
        lo, hi = ends
        if not float(lo.subs(defaults)) < float(hi.subs(defaults)):
            raise UserError(source, f"bounds.{axis}: low must be below high (with the default params)")
        bounds[axis] = (lo, hi)
    return bounds


def parse_full(data: Any, source: str = "<spec>") -> Spec:
    """Validate an already-loaded mapping (a spec file, or an inline shape in a scene), in full with SymPy. Callers
    come through spec/entry.py's parse_spec."""
    if not isinstance(data, dict) or not any(k in KEYS for k in data):
        # Possibly not meant as a spec at all (a scene's `shape:` naming some other file): say what was
        # expected, and echo nothing of the file.
        raise UserError(source, "not a shape spec (expected a YAML mapping with 'name' and 'equation')")
    unknown = [k for k in data if k not in KEYS]
    if unknown:
        raise UserError(source, f"unknown key {validate.describe(unknown[0])} (allowed: {', '.join(KEYS)})")
    for key in ("name", "equation"):
        if key not in data:
            raise UserError(source, f"missing key {key!r}")
    name = check_shape_name(source, "name", data["name"])
    params = _parse_params(source, data.get("params"))
    f, degree, as_written = _parse_equation(source, data["equation"], params)
    bounds = _parse_bounds(source, data.get("bounds"), params)
    texts = {key: _parse_text(source, key, data.get(key, "")) for key in MAX_TEXT}
    description = texts.pop("description")
    ranges = _parse_ranges(source, data.get("ranges"), params)
    spec = make_spec(name, f, params, degree, bounds, description, source, None, texts, ranges, as_written)
    spec.check_values({}, source, "params")  # the defaults
    for key, (lo, hi) in ranges.items():  # every coefficient stays a finite double at both ends of a range
        spec.check_values({key: lo}, source, f"ranges.{key}")
        spec.check_values({key: hi}, source, f"ranges.{key}")
    return spec


# Bidirectional-text controls reorder what is shown around them (a title that reads one way and is another).
_BIDI_CONTROLS = frozenset("\u061c\u200e\u200f\u202a\u202b\u202c\u202d\u202e\u2066\u2067\u2068\u2069")


def _parse_text(source: str, key: str, value: Any) -> str:
    """A title, description or reference: text of bounded length, its whitespace runs made single spaces, and no
    control characters (a terminal escape, NUL, DEL, a bidirectional override). It is shown (the viewer, the
    gallery's table, a terminal), never written into generated code."""
    if not isinstance(value, str):
        raise UserError(source, f"{key}: must be text")
    if len(value) > MAX_TEXT[key]:
        raise UserError(source, f"{key}: longer than {MAX_TEXT[key]} characters")
    for i, ch in enumerate(value):
        if not ch.isspace() and (unicodedata.category(ch) in ("Cc", "Cs") or ch in _BIDI_CONTROLS):
            raise UserError(source, f"{key}: control character U+{ord(ch):04X} at position {i + 1} is not allowed")
    return " ".join(value.split())


def _parse_ranges(source: str, raw: Any, params: dict[str, float]) -> dict[str, tuple[float, float]]:
    """`ranges: {param: [low, high]}`: the span a slider offers for a declared param, holding its default."""
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        raise UserError(source, "ranges: must be a mapping such as {a: [0.5, 2]}")
    ranges: dict[str, tuple[float, float]] = {}
    for key, pair in raw.items():
        if key not in params:
            raise UserError(source, f"ranges: {validate.describe(key)} is not a declared param")
        if not isinstance(pair, list) or len(pair) != 2:
            raise UserError(source, f"ranges.{key}: must be a pair [low, high]")
        lo, hi = (validate.number(source, f"ranges.{key}", v, text_ok=True) for v in pair)
        if not lo < hi:
            raise UserError(source, f"ranges.{key}: low must be below high")
        if not lo <= params[key] <= hi:
            raise UserError(source, f"ranges.{key}: does not hold the default {params[key]:g}")
        ranges[key] = (lo, hi)
    return ranges
