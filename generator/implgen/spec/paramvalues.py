"""Param values checked against a shape, without SymPy.

A scene may override a shape's params. Two things must then still hold (Spec.check_values): every coefficient
of f in x, y, z stays within 2^MAX_COEFF_BITS (a param within range can still be raised to a power that
overflows: a^40 with a = 1e9), and the bounds stay an ordered box within the coordinate range. Both need only
plain data taken from the parsed spec once: the terms of f as (log2 |coefficient|, param exponents), and the
bounds as small expression trees in the params. Those are JSON-friendly, so the spec cache
(spec/cache.py) keeps them and a cached scene is checked exactly as a freshly parsed one, by this code.

A bounds tree is one of ["n", float], ["p", param name], ["+", tree, ...], ["*", tree, ...] or
["^", tree, whole exponent].
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from implgen import validate
from implgen.errors import UserError

AXES = ("x", "y", "z")
MAX_COEFF_BITS = 900  # |coefficient| of f in x, y, z (and of the ray polynomial's inputs) below 2^900
MAX_TREE_NODES = 10_000  # a bounds expression in the params: far more than any spec writes

Terms = list[tuple[float, tuple[int, ...]]]
Trees = dict[str, tuple[list, list]]


def tree_of(expr: Any, names: Mapping[Any, str]) -> list | None:
    """A SymPy expression in the param symbols (`names`: symbol -> param name) as a bounds tree; None when it
    holds anything a tree cannot say."""
    if expr.is_Symbol:
        return ["p", names[expr]] if expr in names else None
    if expr.is_Number:
        return ["n", float(expr)]
    if expr.is_Add or expr.is_Mul:
        args = [tree_of(a, names) for a in expr.args]
        return None if any(a is None for a in args) else ["+" if expr.is_Add else "*", *args]
    if expr.is_Pow and expr.exp.is_Integer:
        base = tree_of(expr.base, names)
        return None if base is None else ["^", base, int(expr.exp)]
    return None


def evaluate(tree: list, values: Mapping[str, float]) -> float:
    """A bounds tree as a double: sums with fsum, products in order; overflow gives an infinity, inf - inf a
    NaN."""
    try:
        op = tree[0]
        if op == "n":
            return tree[1]
        if op == "p":
            return float(values[tree[1]])
        if op == "+":
            return math.fsum(evaluate(a, values) for a in tree[1:])
        if op == "*":
            return math.prod(evaluate(a, values) for a in tree[1:])
        return evaluate(tree[1], values) ** tree[2]
    except OverflowError:
        return math.inf
    except ValueError:
        return math.nan


def tree_ok(tree: Any, params: Sequence[str], budget: list[int] | None = None) -> bool:
    """`tree` has the form above, names only `params` and has at most MAX_TREE_NODES nodes (for data read back
    from a cache, which must never be trusted blindly)."""
    budget = [MAX_TREE_NODES] if budget is None else budget
    budget[0] -= 1
    if budget[0] < 0 or not isinstance(tree, list) or not tree:
        return False
    op, args = tree[0], tree[1:]
    if op == "n":
        return len(args) == 1 and isinstance(args[0], float) and not math.isnan(args[0])
    if op == "p":
        return len(args) == 1 and args[0] in params
    if op in ("+", "*"):
        return len(args) >= 1 and all(tree_ok(a, params, budget) for a in args)
    if op == "^":
        exp = args[1] if len(args) == 2 else None
        return isinstance(exp, int) and not isinstance(exp, bool) and exp >= 0 and tree_ok(args[0], params, budget)
    return False


def box(params: Mapping[str, float], trees: Trees | None, values: Mapping[str, float] | None) -> list[float] | None:
    """The numeric box {xmin, ymin, zmin, xmax, ymax, zmax} for these param values (defaults for the rest);
    an end too large for a double is an infinity. None for a shape without bounds."""
    if trees is None:
        return None
    full = {**params, **(values or {})}
    lo = [evaluate(trees[a][0], full) if a in trees else -math.inf for a in AXES]
    hi = [evaluate(trees[a][1], full) if a in trees else math.inf for a in AXES]
    return lo + hi


def check(
    name: str,
    params: Mapping[str, float],
    terms: Terms,
    trees: Trees | None,
    values: Mapping[str, float],
    source: str,
    key: str,
) -> None:
    """With these param values (defaults for the rest) every coefficient of f stays within 2^MAX_COEFF_BITS,
    and the bounds stay an ordered box within the coordinate range; else one UserError naming `key`."""
    full = {**params, **values}
    logs = [math.log2(abs(full[p])) if full[p] else None for p in params]
    for log_c, exps in terms:
        if any(e and lg is None for e, lg in zip(exps, logs)):
            continue  # a zero param to a positive power: the term vanishes
        size = log_c + sum(e * lg for e, lg in zip(exps, logs) if e)
        if size > MAX_COEFF_BITS:
            raise UserError(
                source,
                f"{key}: with these params a coefficient of shape {name!r} reaches 2^{size:.0f} "
                f"(beyond 2^{MAX_COEFF_BITS}: not a finite double once the ray is put in)",
            )
    b = box(params, trees, values)
    if b is None:
        return
    for i, axis in enumerate(AXES):
        lo, hi = b[i], b[i + 3]
        if axis in trees and not (abs(lo) <= validate.MAX_COORDINATE and abs(hi) <= validate.MAX_COORDINATE):
            raise UserError(
                source,
                f"{key}: with these params the bounds of shape {name!r} leave "
                f"[-{validate.MAX_COORDINATE:g}, {validate.MAX_COORDINATE:g}] along {axis}",
            )
        if axis in trees and not lo < hi:
            raise UserError(
                source,
                f"{key}: with these params the bounds of shape {name!r} are empty along {axis} (from {lo:g} to {hi:g})",
            )


def named_items(option: str, items: Sequence[str], shape: str, params: Mapping[str, float]) -> dict[str, str]:
    """NAME=TEXT command-line items (`--param a=1`, `--range a=0:2`) naming params of the shape, each at most
    once: {name: text}. The text is not read here."""
    out: dict[str, str] = {}
    for item in items:
        name, eq, text = item.partition("=")
        label = f"{option} {item[:60] if item.isprintable() else validate.describe(item)}"  # one line, whatever came
        if not eq or not name:
            raise UserError(label, "expected NAME=VALUE" if option == "--param" else "expected NAME=LOW:HIGH")
        if name not in params:
            known = ", ".join(params) or "none"
            raise UserError(label, f"shape {shape!r} has no param {validate.describe(name)} (params: {known})")
        if name in out:
            raise UserError(label, f"{name} is given twice")
        out[name] = text
    return out
