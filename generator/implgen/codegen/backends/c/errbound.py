"""The ray coefficients with a rigorous bound on their rounding: `<name>_coeffs_err` of the generated C.

The coefficient block (the same temporaries and outputs `<name>_coeffs` evaluates) is printed once more, one
floating-point operation per statement, each carrying a bound on its distance from the exact value: running
error analysis with the helpers of runtime_c/errarith.h. Inputs are balls (the ray's origin and direction with
their own error bounds), params are exact, integer constants are exact and a rational constant is rounded once.
Only + - * / and integer powers occur (the spec grammar allows nothing else); a power with another exponent
would make the function report "no bound" (return 0). docs/certify.md states what the bound promises.

Every name printed here is a SymPy symbol of the derivation (ox.., dx.., k_<validated param>, w<i>, q<i>) or a
numbered local of our own; numbers are printed from exact integers or correctly rounded doubles.
"""

from __future__ import annotations

from fractions import Fraction

import sympy

from implgen.codegen.backends.contract import EXACT_INT, finite_double
from implgen.codegen.derive import DIRECTION, ORIGIN


class _Emitter:
    """Statements of one function: each SSA value is a pair of locals (v<i>, e<i>): value and error bound."""

    def __init__(self, params: set[sympy.Symbol]):
        self.lines: list[str] = []
        self.names: dict[sympy.Symbol, tuple[str, str]] = {}
        self.params = params
        self.count = 0
        self.bounded = True
        for i, (o, d) in enumerate(zip(ORIGIN, DIRECTION)):
            self.names[o] = (f"o[{i}]", f"eo[{i}]")
            self.names[d] = (f"d[{i}]", f"ed[{i}]")

    def _new(self, value: str, error: str) -> tuple[str, str]:
        k = self.count
        self.count += 1
        self.lines.append(f"const double v{k} = {value};")
        self.lines.append(f"const double e{k} = {error};")
        return f"v{k}", f"e{k}"

    def const(self, q: Fraction) -> tuple[str, str]:
        if q.denominator == 1 and abs(q.numerator) < EXACT_INT:
            return f"{float(q.numerator)!r}", "0.0"
        v = finite_double(q.numerator, q.denominator)  # correctly rounded: one rounding
        return self._new(repr(v), f"ig_err_const({v!r})")

    def op(self, kind: str, a: tuple[str, str], b: tuple[str, str]) -> tuple[str, str]:
        sign = {"add": "+", "sub": "-", "mul": "*", "div": "/"}[kind]
        helper = {"add": "add", "sub": "add", "mul": "mul", "div": "div"}[kind]
        k = self.count
        self.count += 1
        self.lines.append(f"const double v{k} = {a[0]} {sign} {b[0]};")
        self.lines.append(f"const double e{k} = ig_err_{helper}({a[0]}, {a[1]}, {b[0]}, {b[1]}, v{k});")
        return f"v{k}", f"e{k}"

    def neg(self, a: tuple[str, str]) -> tuple[str, str]:
        return self._new(f"-{a[0]}", a[1])

    def expr(self, e: sympy.Expr) -> tuple[str, str]:
        if e.is_Symbol:
            if e in self.names:
                return self.names[e]
            if e in self.params:
                return str(e), "0.0"
            raise KeyError(str(e))
        if e.is_Rational:
            return self.const(Fraction(int(e.p), int(e.q)))
        if e.is_Add:
            return self._add(e.args)
        if e.is_Mul:
            return self._mul(e.args)
        if e.is_Pow and e.exp.is_Integer:
            return self._pow(self.expr(e.base), int(e.exp))
        self.bounded = False
        return "0.0", "INFINITY"

    def _add(self, terms) -> tuple[str, str]:
        acc = None
        for t in terms:
            negative = t.could_extract_minus_sign()
            x = self.expr(-t if negative else t)
            if acc is None:
                acc = self.neg(x) if negative else x
            else:
                acc = self.op("sub" if negative else "add", acc, x)
        return acc

    def _mul(self, factors) -> tuple[str, str]:
        coeff, rest = sympy.Mul(*factors).as_coeff_Mul()
        negative = coeff < 0
        coeff = abs(coeff)
        acc = None if coeff == 1 else self.expr(coeff)
        for f in sympy.Mul.make_args(rest):
            x = self.expr(f)
            acc = x if acc is None else self.op("mul", acc, x)
        acc = acc if acc is not None else ("1.0", "0.0")
        return self.neg(acc) if negative else acc

    def _pow(self, base: tuple[str, str], k: int) -> tuple[str, str]:
        if k == 0:
            return "1.0", "0.0"
        if k < 0:
            return self.op("div", ("1.0", "0.0"), self._pow(base, -k))
        result, square = None, base
        while True:
            if k & 1:
                result = square if result is None else self.op("mul", result, square)
            k >>= 1
            if not k:
                return result
            square = self.op("mul", square, square)


def coeffs_err_lines(block, params) -> dict:
    """The body of `<name>_coeffs_err` for the coefficient block: statements, one per line, and whether every
    operation has a bound (else the function returns 0)."""
    em = _Emitter(set(params))
    for sym, e in block.temps:
        v, err = em.expr(e)
        em.lines.append(f"const double {sym} = {v};")
        em.lines.append(f"const double {sym}_e = {err};")
        em.names[sym] = (str(sym), f"{sym}_e")
    for i, e in enumerate(block.outputs):
        v, err = em.expr(sympy.sympify(e))
        em.lines.append(f"c[{i}] = {v};")
        em.lines.append(f"e[{i}] = {err};")
    return {"lines": em.lines, "bounded": em.bounded}


def c_extra(derivation) -> dict:
    """The C templates' extra variables: the error-bounded coefficient function's body."""
    return {"coeffs_err": coeffs_err_lines(derivation.coeffs, derivation.spec.param_symbols)}
