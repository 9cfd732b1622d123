"""An equation as the user wrote it: the parsed tree (Python's `ast` of the text, after the grammar's whitelist
accepted every node) printed back in the equation grammar, in the user's order and grouping.

SymPy keeps the polynomial but not the writing: it orders terms its own way and distributes constants, so
`k*(x + y + z - 1)` comes back as `-k*(-x - y + z - 1)` or worse. This printer walks the user's own tree: names as
they are (identifiers the grammar checked), each number printed from its exact value (never the text typed),
`+ - * / ^` with the parentheses the grouping needs (the user's redundant ones are dropped). What it prints parses
back to the same polynomial (tests/test_fuzz_inputs.py checks it). Generated code still shows the canonical
form (spec/grammar.py's format_expression); this is what the user reads: the viewer, Save YAML, share pages.
"""

from __future__ import annotations

import ast
import decimal
from collections.abc import Callable
from fractions import Fraction

SUM, PRODUCT, UNARY, POWER, ATOM = 10, 20, 30, 40, 100  # how tightly each kind of node binds
_OPS = {ast.Add: " + ", ast.Sub: " - ", ast.Mult: "*", ast.Div: "/"}


def number_text(value: Fraction) -> str:
    """An exact number as the grammar reads it back to the same value: an integer, or the decimal fraction a
    literal is (its denominator 2^a 5^b), in exponent notation when that is shorter."""
    if value.denominator == 1 and abs(value.numerator) < 10**30:
        return str(value.numerator)
    with decimal.localcontext() as ctx:
        ctx.prec = 400  # a literal has at most 80 digits: its decimal expansion is exact in this many
        d = (decimal.Decimal(value.numerator) / decimal.Decimal(value.denominator)).normalize()
    plain, short = f"{d:f}", f"{d:e}".replace("e+", "e")
    return plain if len(plain) <= len(short) else short


def written(tree: ast.AST, number: Callable[[ast.Constant], Fraction]) -> str:
    """The text of a tree the grammar accepted; `number` gives a literal's exact value."""
    return _text(tree.body if isinstance(tree, ast.Expression) else tree, number)[0]


def _wrapped(part: tuple[str, int], tighter_than: int) -> str:
    text, binds = part
    return f"({text})" if binds < tighter_than else text


def _text(node: ast.AST, number: Callable[[ast.Constant], Fraction]) -> tuple[str, int]:
    """(text, how tightly it binds)."""
    if isinstance(node, ast.Constant):
        return number_text(number(node)), ATOM
    if isinstance(node, ast.Name):
        return node.id, ATOM
    if isinstance(node, ast.UnaryOp):
        sign = "-" if isinstance(node.op, ast.USub) else "+"
        return sign + _wrapped(_text(node.operand, number), POWER), UNARY
    if isinstance(node.op, ast.Pow):
        base = _wrapped(_text(node.left, number), ATOM)
        return f"{base}^{_wrapped(_text(node.right, number), ATOM)}", POWER
    return _chain(node, number)


def _chain(node: ast.BinOp, number: Callable[[ast.Constant], Fraction]) -> tuple[str, int]:
    """`a + b - c ...` or `a*b/c ...`, walked as the flat list it is (no recursion along it)."""
    binds = SUM if isinstance(node.op, (ast.Add, ast.Sub)) else PRODUCT
    kinds = (ast.Add, ast.Sub) if binds == SUM else (ast.Mult, ast.Div)
    steps = []
    while isinstance(node, ast.BinOp) and isinstance(node.op, kinds):
        steps.append((node.op, node.right))
        node = node.left
    parts = [_wrapped(_text(node, number), binds)]
    for op, right in reversed(steps):
        text, tight = _text(right, number)
        # the right operand of the same kind, or a signed one, keeps its parentheses: a - (b + c), a*(-b)
        parts.append(_OPS[type(op)] + (f"({text})" if tight <= binds or tight == UNARY else text))
    return "".join(parts), binds
