"""Spec -> the expressions the generated code evaluates.

Coefficients of f(o + t d) = c_0 + c_1 t + ... + c_n t^n are computed in Taylor form: every node of the
equation's expression tree (as the user wrote it) becomes its truncated power series in t, so
c_k = (d . grad)^k f(o) / k! comes out by exact series arithmetic (sums add, products convolve, powers
square and multiply), truncated at the exact degree n of f. This never expands f in x, y, z: at degree 20
the expanded form of f(o + t d) has tens of thousands of terms, while the series form stays O(nodes * n^2)
operations, and it keeps the user's (usually better conditioned) grouping. `bench gen` measures both.

The gradient is differentiated on the same tree. One `cse` runs over all outputs of a shape (coefficients,
value, gradient, bounds); each generated function then takes the shared temporaries it needs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import sympy
from sympy.polys.domains import QQ
from sympy.polys.rings import ring

from implgen.errors import UserError
from implgen.spec.grammar import MAX_TREE_DEPTH
from implgen.spec.parse import AXES, Spec, X, Y, Z

# Names used inside generated code. User params are always prefixed `k_` (see spec.param_symbol), and cse
# temporaries are `w0, w1, ...`, so none of these can collide with a user's name.
OX, OY, OZ = sympy.symbols("ox oy oz", real=True)
DX, DY, DZ = sympy.symbols("dx dy dz", real=True)
PX, PY, PZ = sympy.symbols("px py pz", real=True)
ORIGIN = (OX, OY, OZ)
DIRECTION = (DX, DY, DZ)
POINT = (PX, PY, PZ)

Series = list  # list[sympy.Expr]: coefficients lowest power first, truncated


def _add(a: Series, b: Series, sign: int = 1) -> Series:
    out = [sympy.Integer(0)] * max(len(a), len(b))
    for i, v in enumerate(a):
        out[i] = out[i] + v
    for i, v in enumerate(b):
        out[i] = out[i] + sign * v
    return out


def _mul(a: Series, b: Series, n: int) -> Series:
    size = min(len(a) + len(b) - 1, n + 1)
    out = []
    for k in range(size):
        terms = [a[i] * b[k - i] for i in range(max(0, k - len(b) + 1), min(k, len(a) - 1) + 1)]
        out.append(sympy.Add(*terms))
    return out


def _pow(a: Series, k: int, n: int) -> Series:
    result: Series = [sympy.Integer(1)]
    base = a
    while k:
        if k & 1:
            result = _mul(result, base, n)
        k >>= 1
        if k:
            base = _mul(base, base, n)
    return result


def ray_series(f: sympy.Expr, n: int) -> Series:
    """Coefficients c_0..c_n of f(o + t d) by truncated series arithmetic over f's own tree."""
    leaves = {X: [OX, DX], Y: [OY, DY], Z: [OZ, DZ]}
    memo: dict[sympy.Expr, Series] = {}

    def series(e: sympy.Expr) -> Series:
        if e in memo:
            return memo[e]
        if e in leaves:
            out = leaves[e]
        elif not e.free_symbols & {X, Y, Z}:
            out = [e]
        elif e.is_Add:
            out = [sympy.Integer(0)]
            for arg in e.args:
                out = _add(out, series(arg))
        elif e.is_Mul:
            out = [sympy.Integer(1)]
            for arg in e.args:
                out = _mul(out, series(arg), n)
        elif e.is_Pow and e.exp.is_Integer and e.exp >= 0:
            out = _pow(series(e.base), int(e.exp), n)
        else:  # the parser only builds sums, products and integer powers
            raise ValueError(f"not a polynomial node: {e}")
        memo[e] = out
        return out

    coeffs = series(f)[: n + 1]
    return coeffs + [sympy.Integer(0)] * (n + 1 - len(coeffs))


def exact_ray_coefficients(spec: Spec) -> list:
    """Reference: c_0..c_n by composition in the polynomial ring QQ[o, d, params][t] (exact, expanded)."""
    t = sympy.Symbol("t")
    gens = [X, Y, Z, t, *ORIGIN, *DIRECTION, *spec.param_symbols]
    R, x, y, z, tt, ox, oy, oz, dx, dy, dz, *_ = ring(gens, QQ)
    fp = R.from_expr(spec.f)
    composed = fp.compose([(x, ox + tt * dx), (y, oy + tt * dy), (z, oz + tt * dz)])
    by_power: dict[int, object] = {}
    t_index = 3
    for monom, coeff in composed.terms():
        k = monom[t_index]
        term = R({tuple(0 if i == t_index else e for i, e in enumerate(monom)): coeff})
        by_power[k] = by_power.get(k, R.zero) + term
    return [by_power.get(k, R.zero) for k in range(spec.degree + 1)]


@dataclass(frozen=True)
class Block:
    """Straight-line code for one generated function: temporaries, then outputs."""

    temps: list[tuple[sympy.Symbol, sympy.Expr]]
    outputs: list[sympy.Expr]
    inputs: list[sympy.Symbol]  # the ray/point/param symbols the block reads


@dataclass(frozen=True)
class Derivation:
    spec: Spec
    coeffs: Block
    value: Block
    gradient: Block
    bounds: Block | None


def _split(
    temps: Sequence[tuple[sympy.Symbol, sympy.Expr]], outputs: list[sympy.Expr], inputs: set[sympy.Symbol]
) -> Block:
    """The temporaries (in order) that `outputs` need, directly or through other temporaries."""
    needed: set[sympy.Symbol] = set()
    for e in outputs:
        needed |= e.free_symbols
    kept = []
    for sym, expr in reversed(temps):
        if sym in needed:
            kept.append((sym, expr))
            needed |= expr.free_symbols
    kept.reverse()
    reads = sorted(needed & inputs, key=lambda s: s.name)
    return Block(kept, outputs, reads)


def _chain_powers(temps: list[tuple[sympy.Symbol, sympy.Expr]], outputs: list[sympy.Expr]):
    """Rewrite b**k as products of shared squares b2 = b*b, b4 = b2*b2, ... wherever b**4 or higher occurs.

    SymPy folds repeated products into powers (the series of x^20 has ox**20), and printing those as
    k - 1 multiplications wastes work; square-and-multiply over shared temporaries needs about log2(k).
    """
    exprs = [e for _, e in temps] + outputs
    need: dict[sympy.Expr, int] = {}
    for e in exprs:
        for p in e.atoms(sympy.Pow):
            if p.exp.is_Integer and p.exp >= 2:
                need[p.base] = max(need.get(p.base, 0), int(p.exp))
    need = {b: k for b, k in need.items() if k >= 4}  # squares and cubes alone print fine as b*b, b*b*b
    if not need:
        return temps, outputs
    need = {b: need[b] for b in sorted(need, key=sympy.default_sort_key)}  # stable across hash seeds
    names = sympy.numbered_symbols("q", real=True)
    squares: dict[sympy.Expr, list[sympy.Expr]] = {}
    new_defs: dict[sympy.Expr, list[tuple[sympy.Symbol, sympy.Expr]]] = {}
    for base, top in need.items():
        chain, defs, current = [base], [], base
        while 2 ** len(chain) <= top:
            sym = next(names)
            defs.append((sym, current * current))
            chain.append(sym)
            current = sym
        squares[base], new_defs[base] = chain, defs

    def product(base: sympy.Expr, k: int) -> sympy.Expr:
        factors = [squares[base][i] for i in range(k.bit_length()) if k >> i & 1]
        return sympy.Mul(*factors, evaluate=False) if len(factors) > 1 else factors[0]

    def rewrite(e: sympy.Expr) -> sympy.Expr:
        return e.replace(
            lambda a: a.is_Pow and a.base in squares and a.exp.is_Integer and a.exp >= 2,
            lambda a: product(a.base, int(a.exp)),
        )

    defined: set[sympy.Expr] = set()
    out: list[tuple[sympy.Symbol, sympy.Expr]] = []

    def emit_ready() -> None:
        for base, defs in new_defs.items():
            if base not in defined and base.free_symbols <= ready:
                out.extend(defs)
                defined.add(base)

    ready = {s for e in exprs for s in e.free_symbols} - {s for s, _ in temps}
    emit_ready()
    for sym, expr in temps:
        out.append((sym, rewrite(expr)))
        ready.add(sym)
        emit_ready()
    return out, [rewrite(e) for e in outputs]


def derive(spec: Spec) -> Derivation:
    """The coefficients, value, gradient and bounds of `spec` as straight-line blocks. SymPy differentiates and
    eliminates common subexpressions recursively; the parser keeps every equation within MAX_TREE_DEPTH levels,
    which leaves room under Python's default recursion limit. Should the stack still run out (a caller already
    deep in its own stack), the spec is refused in one line instead of a traceback of thousands."""
    try:
        return _derive(spec)
    except RecursionError:
        raise UserError(
            spec.source,
            f"equation: too deeply nested to derive here (Python's recursion limit was reached; an equation "
            f"nests at most {MAX_TREE_DEPTH} levels)",
        ) from None


def _derive(spec: Spec) -> Derivation:
    n = spec.degree
    coeffs = ray_series(spec.f, n)
    at_point = {X: PX, Y: PY, Z: PZ}
    value = spec.f.xreplace(at_point)
    gradient = [sympy.diff(spec.f, v).xreplace(at_point) for v in (X, Y, Z)]
    box: list[sympy.Expr] = []
    if spec.bounds is not None:
        inf = sympy.oo
        box = [spec.bounds[a][0] if a in spec.bounds else -inf for a in AXES]
        box += [spec.bounds[a][1] if a in spec.bounds else inf for a in AXES]
    outputs = [*coeffs, value, *gradient, *box]
    temps, reduced = sympy.cse(outputs, symbols=sympy.numbered_symbols("w", real=True), order="none")
    temps, reduced = _chain_powers(temps, reduced)
    inputs = {*ORIGIN, *DIRECTION, *POINT, *spec.param_symbols}
    k = n + 1
    return Derivation(
        spec=spec,
        coeffs=_split(temps, reduced[:k], inputs),
        value=_split(temps, reduced[k : k + 1], inputs),
        gradient=_split(temps, reduced[k + 1 : k + 4], inputs),
        bounds=_split(temps, reduced[k + 4 :], inputs) if box else None,
    )
