"""The GLSL backend's own pieces: a printer for float code, and f's reduced affine form, printed from f's tree.

GLSL runs in float (24 bits), so the shader never sees the ray polynomial's coefficients (at degree 12 and
above their cancellation leaves nothing). It evaluates f itself, in the form the user wrote it (the parsed
tree, never expanded), in reduced affine arithmetic over a segment of the ray: `NAME_raa(x, y, z)` takes the
three coordinates as affine forms vec3(centre, slope, radius) and returns f's form, every rounding counted
(runtime_glsl/raa.glsl; the method and its limits: docs/glsl.md).

Constants are exact rationals in the spec; in the affine code each becomes the nearest float and a bound on
the difference, rounded up, so the form still encloses the exact f. A constant beyond float range becomes
a product of in-range factors (powers of two are exact). Nothing here comes from user text: the code is
printed from the SymPy tree, and names are validated identifiers.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import sympy
from sympy.printing.c import C99CodePrinter
from sympy.printing.precedence import PRECEDENCE

from implgen.codegen.backends.glsl.chebform import ChebForm, OverBudget, better_form
from implgen.codegen.backends.glsl.program import SHAPE_FUNCTIONS
from implgen.codegen.derive import Derivation
from implgen.spec.parse import X, Y, Z, param_symbol

_F32_MAX = Fraction(float(np.finfo(np.float32).max))
_MIN_NORMAL = Fraction(2) ** -126  # GPUs may flush anything smaller to zero
_STEP = 100  # power-of-two factors of out-of-range constants: 2^±100, exact floats


def _f32(q: Fraction) -> float:
    """A float32 near q (in range), as a Python float holding it exactly."""
    return float(np.float32(float(q)))


def _f32_up(q: Fraction) -> float:
    """The smallest float32 >= q >= 0 that is a normal number (or zero)."""
    if q == 0:
        return 0.0
    v = np.float32(float(q))
    while Fraction(float(v)) < q:
        v = np.nextafter(v, np.float32(np.inf))
    return float(max(v, np.float32(2.0**-126)))


def _factors(q: Fraction) -> list[Fraction]:
    """q as a product of factors each within float range: [q] when it already is, else a mantissa and powers
    of two."""
    if q == 0 or (_MIN_NORMAL <= abs(q) <= _F32_MAX):
        return [q]
    k = abs(q).numerator.bit_length() - abs(q).denominator.bit_length()
    m = q / Fraction(2) ** k
    out = [m]
    step = _STEP if k > 0 else -_STEP
    while k:
        part = step if abs(k) > abs(step) else k
        out.append(Fraction(2) ** part)
        k -= part
    return out


def float_literal(value: float, exact: bool = False) -> str:
    """A GLSL float literal: the shortest text that reads back as the float32 (plain code), or 17 digits of
    its exact value (affine constants, whose error bound must refer to exactly that float)."""
    text = repr(value) if exact else str(np.float32(value))
    if not any(ch in text for ch in ".e"):
        text += ".0"
    return text


def constant_code(q: Fraction) -> str:
    """A rational as float code: one literal, or a product of in-range literals."""
    parts = [float_literal(_f32(f)) for f in _factors(q)]
    return parts[0] if len(parts) == 1 else "(" + " * ".join(parts) + ")"


# Identifiers. GLSL reserves every identifier that holds two consecutive underscores (GLSL ES 3.00 and 4.50,
# section 3.7; WebGL refuses them) and those that start gl_; WebGL those that start webgl_ or _webgl_. A spec's
# names are checked as C and Python identifiers (codegen/names.py) and may still make such identifiers here: a
# shape `ball_` would define `ball__hit`, a param `a__b` the local `k_a__b`. Rather than refuse a spec the
# other backends take, such names are written another way, one-to-one (docs/glsl.md, "Names"):
_GLSL_RESERVED_PREFIXES = ("gl_", "webgl_")
# the shape's own identifiers are <prefix>_<suffix> (templates/glsl/shape.glsl.j2)
SUFFIXES = (*SHAPE_FUNCTIONS, "params")
MANGLED_SHAPE = "ig_shape_"  # names.py refuses shape names that start ig_, so no kept name starts so
MANGLED_PARAM = "k0_"  # a kept param's local starts k_


def _spelled(name: str) -> str:
    """`name` with each _ written _u: no two underscores meet, nothing ends in _, and reading each _u back as _
    gives `name` again."""
    return "".join("_u" if ch == "_" else ch for ch in name)


def glsl_name(name: str) -> str:
    """The prefix of a shape's GLSL identifiers (`<prefix>_hit`, `<prefix>_params`, ...): the shape's name,
    unless the identifiers it makes are reserved in GLSL (the name holds __, ends in _ or starts gl_ or
    webgl_); then ig_shape_ and the name spelled with _u (`ball_` -> `ig_shape_ball_u`)."""
    if "__" in name or name.endswith("_") or name.lower().startswith(_GLSL_RESERVED_PREFIXES):
        return MANGLED_SHAPE + _spelled(name)
    return name


def param_local(name: str) -> str:
    """The local variable that holds a param in the shape's GLSL functions: k_<name>, unless that holds __ or
    ends like a shape's own identifier (`_value`, ..., `_params`: a param `params` of a shape `k` would hide
    the uniform `k_params`); then k0_, the name spelled with _u, and _u (`a__b` -> `k0_a_u_ub_u`), which ends
    in no suffix."""
    local = f"k_{name}"
    if "__" in name or local.endswith(tuple(f"_{s}" for s in SUFFIXES)):
        return MANGLED_PARAM + _spelled(name) + "_u"
    return local


class GLSLPrinter(C99CodePrinter):
    """Float code for GLSL ES 3.00 and 4.50: every number a float literal (GLSL has no implicit int to float),
    integer powers as products (GLSL's pow() is undefined for a negative base), open box sides as IG_OPEN."""

    def _print_Integer(self, expr: sympy.Integer) -> str:  # noqa: N802 -- SymPy's naming
        return constant_code(Fraction(int(expr)))

    def _print_Rational(self, expr: sympy.Rational) -> str:  # noqa: N802
        return constant_code(Fraction(int(expr.p), int(expr.q)))

    def _print_Infinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "IG_OPEN"

    def _print_Symbol(self, expr: sympy.Symbol) -> str:  # noqa: N802
        name = expr.name
        if name.startswith("k_") and expr == param_symbol(name[2:]):  # a param: its local (param_local)
            return param_local(name[2:])
        return super()._print_Symbol(expr)

    def _print_NegativeInfinity(self, expr: sympy.Expr) -> str:  # noqa: N802
        return "-IG_OPEN"

    def _print_Pow(self, expr: sympy.Pow) -> str:  # noqa: N802
        k = expr.exp
        if not (k.is_Integer and k >= 1):
            raise ValueError(f"GLSL code has only non-negative integer powers, not {expr}")
        base = self.parenthesize(expr.base, PRECEDENCE["Mul"] + 1)
        return "(" + "*".join([base] * int(k)) + ")"


class _AffineCode:
    """f's tree -> straight-line GLSL over affine forms (vec3), one statement per operation."""

    def __init__(self, params: dict[sympy.Symbol, str]) -> None:
        self.params = params
        self.lines: list[str] = []
        self.memo: dict[sympy.Expr, str] = {X: "x", Y: "y", Z: "z"}
        self.powers: dict[str, dict[int, str]] = {}

    def _new(self, code: str) -> str:
        name = f"a{len(self.lines)}"
        self.lines.append(f"vec3 {name} = {code};")
        return name

    def constant(self, q: Fraction) -> str:
        value = None
        for f in _factors(q):
            c = _f32(f)
            if abs(Fraction(c)) < _MIN_NORMAL:
                c = 0.0
            code = f"ig_raa_const({float_literal(c, exact=True)}, {float_literal(_f32_up(abs(f - Fraction(c))), True)})"
            value = code if value is None else self._new(f"ig_raa_mul({value}, {code})")
        return value if value is not None else "ig_raa_const(0.0, 0.0)"

    def node(self, e: sympy.Expr) -> str:
        if e in self.memo:
            return self.memo[e]
        if e.is_Rational:
            return self.constant(Fraction(int(e.p), int(e.q)))
        if e in self.params:
            out = self._new(f"ig_raa_param({self.params[e]})")
        elif e.is_Add:
            out = self._add(e)
        elif e.is_Mul:
            out = self._mul(e)
        elif e.is_Pow and e.exp.is_Integer and e.exp >= 1:
            out = self._power(self.node(e.base), int(e.exp))
        else:  # the parser builds only sums, products and integer powers of symbols and numbers
            raise ValueError(f"not a polynomial node: {e}")
        self.memo[e] = out
        return out

    def _add(self, e: sympy.Add) -> str:
        constant, terms = e.as_coeff_add()
        acc = None
        for term in terms:
            coeff, _ = term.as_coeff_mul()
            negative = coeff.is_negative
            v = self.node(-term if negative else term)
            if acc is None:
                acc = self._new(f"ig_raa_neg({v})") if negative else v
            else:
                acc = self._new(f"ig_raa_{'sub' if negative else 'add'}({acc}, {v})")
        if constant != 0:
            op = "sub" if constant < 0 else "add"
            acc = self._new(f"ig_raa_{op}({acc}, {self.constant(abs(Fraction(int(constant.p), int(constant.q))))})")
        assert acc is not None
        return acc

    def _mul(self, e: sympy.Mul) -> str:
        coeff, factors = e.as_coeff_mul()
        acc = None
        for factor in factors:
            v = self.node(factor)
            acc = v if acc is None else self._new(f"ig_raa_mul({acc}, {v})")
        assert acc is not None
        if coeff == -1:
            return self._new(f"ig_raa_neg({acc})")
        if coeff != 1:
            return self._new(f"ig_raa_mul({acc}, {self.constant(Fraction(int(coeff.p), int(coeff.q)))})")
        return acc

    def _power(self, base: str, k: int) -> str:
        known = self.powers.setdefault(base, {1: base})
        if k not in known:
            if k % 2 == 0:
                known[k] = self._new(f"ig_raa_sqr({self._power(base, k // 2)})")
            else:
                j = max((j for j in known if k - j in known), default=None)
                if j is None:
                    known[k] = self._new(f"ig_raa_mul({self._power(base, k - 1)}, {base})")
                else:
                    known[k] = self._new(f"ig_raa_mul({known[j]}, {known[k - j]})")
        return known[k]


def chebyshev_affine_code(form: ChebForm) -> tuple[list[str], str]:
    """(statements, result) computing f's affine form from x, y, z in the Chebyshev basis of its box
    (codegen/backends/glsl/chebform.py): u = (x - centre) / half-width, T_n(u) by doubling, then
    sum_i T_i(u) (sum_j T_j(v) (sum_k c_ijk T_k(w)))."""
    code = _AffineCode({})
    tables = []
    for axis, var in enumerate("xyz"):
        centre, half = form.centre[axis], form.half[axis]
        u = var if centre == 0 else code._new(f"ig_raa_sub({var}, {code.constant(centre)})")
        u = u if half == 1 else code._new(f"ig_raa_mul({u}, {code.constant(1 / half)})")
        table = {1: u}
        for n in range(2, max(m[axis] for m in form.coeffs) + 1):  # T_m and T_m+1 come before T_2m, T_2m+1
            m = n // 2
            if n % 2 == 0:
                double = code._new(f"ig_raa_mul({code._power(table[m], 2)}, {code.constant(Fraction(2))})")
                table[n] = code._new(f"ig_raa_sub({double}, {code.constant(Fraction(1))})")
            else:
                product = code._new(f"ig_raa_mul({table[m]}, {table[m + 1]})")
                double = code._new(f"ig_raa_mul({product}, {code.constant(Fraction(2))})")
                table[n] = code._new(f"ig_raa_sub({double}, {u})")
        tables.append(table)
    nested: dict[int, dict[int, dict[int, Fraction]]] = {}
    for (i, j, k), c in sorted(form.coeffs.items()):
        nested.setdefault(i, {}).setdefault(j, {})[k] = c

    def term(factor: int, axis: int, inner: str) -> str:
        return inner if factor == 0 else code._new(f"ig_raa_mul({tables[axis][factor]}, {inner})")

    def total(parts: list[str]) -> str:
        acc = parts[0]
        for part in parts[1:]:
            acc = code._new(f"ig_raa_add({acc}, {part})")
        return acc

    result = total(
        [
            term(
                i,
                0,
                total(
                    [term(j, 1, total([term(k, 2, code.constant(c)) for k, c in zs.items()])) for j, zs in ys.items()]
                ),
            )
            for i, ys in nested.items()
        ]
    )
    return code.lines, result


def affine_code(f: sympy.Expr, params: dict[sympy.Symbol, str]) -> tuple[list[str], str]:
    """(statements, result) computing f's affine form from x, y, z; `params` maps each param symbol to the
    GLSL float it is read from. Shared subtrees are computed once (one `cse`)."""
    temps, (reduced,) = sympy.cse([f], symbols=sympy.numbered_symbols("w", real=True), order="none")
    code = _AffineCode(params)
    for sym, expr in temps:
        code.memo[sym] = code.node(expr)
    return code.lines, code.node(reduced)


def glsl_extra(derivation: Derivation) -> dict:
    """What the GLSL templates need beyond the printed blocks: the affine code, the prefix of the shape's
    identifiers, the params' uniform and their local variables."""
    spec = derivation.spec
    prefix = glsl_name(spec.name)
    uniform = f"{prefix}_params"
    locals_ = {s.name: param_local(p) for p, s in zip(spec.params, spec.param_symbols)}
    params = {s: f"{uniform}[{i}]" for i, s in enumerate(spec.param_symbols)}
    form, cut = None, False
    if not params:
        try:
            form = better_form(spec.f, spec.bounds)
        except OverBudget:  # the viewer's GLSL budget ran out (chebform.budget): the tree, always at hand
            cut = True
    if form is None:
        lines, result = affine_code(spec.f, params)
        basis = "the tree as written (not expanded)"
        if cut:
            basis += ": the Chebyshev basis of the box was not tried to the end within the time budget"
    else:
        lines, result = chebyshev_affine_code(form)
        basis = "the Chebyshev basis of the box, which float evaluates far better than the tree as written"
    return {
        "prefix": prefix,
        "uniform": uniform,
        "param_locals": locals_,
        "raa": {"lines": lines, "result": result, "basis": basis},
    }
