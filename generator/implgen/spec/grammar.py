"""Equation text -> SymPy expression, without eval.

The text is read by Python's own parser (`ast.parse`, which only builds a syntax tree and runs nothing);
we then walk that tree and accept a small whitelist: numbers, declared symbols, `+ - * /`, `^`/`**` with a
constant non-negative integer exponent, and parentheses. Division is by non-zero constants only. Anything
else (calls, attribute access, lambdas, comprehensions, names we do not know) is refused with a message.

Before any of that, every character is checked against the grammar's own alphabet (ASCII letters, digits,
spaces, `. _ + - * / ^ ( )` and one `=`): the grammar has no comments, strings or escapes, so `#`, quotes,
backslashes, control characters and non-ASCII text are refused with the position of the first one.

While walking we track an upper bound of the degree, so `x^100000` or `(x+1)^(10^10)` is refused before any
algebra is attempted. Constants are exact rationals whose numerator and denominator must stay below
2^MAX_CONST_BITS, so every number the generated code prints is a finite double.

`format_expression` prints a parsed expression back in this same grammar: what generated files show.
"""

from __future__ import annotations

import ast
import math
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, replace
from fractions import Fraction

import sympy
from sympy.printing.str import StrPrinter

from implgen.spec import syntaxplace, written
from implgen.spec.syntaxplace import ALPHABET, ParseError, check_alphabet, place_in  # noqa: F401 -- its names

MAX_TEXT_LENGTH = 20_000
MAX_NESTING = 100  # parentheses / operator nesting a user could mean
MAX_TREE_DEPTH = 64  # levels of the parsed expression tree (expression_depth); docs/limitations.md
MAX_CONST_BITS = 256  # numerators and denominators of constants stay below 2^256 (about 1e77)
MAX_DIGITS = 80  # digits in one number as written
_LONG_NUMBER = re.compile(rf"[0-9_]{{{MAX_DIGITS + 1},}}")
MAX_TERMS = 20_000  # terms of the expanded polynomial: (x+y+z+1)^24 has 2925; (a+b+...+h)^20 would have 888,030
_TERMS_CAP = 10**9
MAX_EXPONENT = 400  # |e| in 1.5e-7 as written; every constant stays within 2^±256 anyway
_EXPONENT = re.compile(r"[eE]([-+]?[0-9_]+)$")


@dataclass(frozen=True)
class Parsed:
    expr: sympy.Expr
    degree_bound: int  # upper bound of the total degree in the "variables"
    param_degree_bound: int
    terms: int = 1  # upper bound of the number of terms once expanded (capped at _TERMS_CAP)
    names: frozenset[str] = frozenset()  # the variables and params it uses
    text: str = ""  # the user's own tree printed back (spec/written.py), set once the whole text has parsed


def _joined(a: Parsed, b: Parsed) -> frozenset[str]:
    return a.names | b.names


def _paren_depth(text: str) -> int:
    depth = deepest = 0
    for ch in text:
        if ch == "(":
            depth += 1
            deepest = max(deepest, depth)
        elif ch == ")":
            depth -= 1
    return deepest


class _Builder:
    def __init__(
        self,
        text: str,
        variables: Mapping[str, sympy.Symbol],
        params: Mapping[str, sympy.Symbol],
        max_degree: int,
        max_param_degree: int,
        original: str = "",
    ) -> None:
        self.text = text
        self.original = original  # the text as given (`^`, leading space): where errors point
        self.variables = variables
        self.params = params
        self.max_degree = max_degree
        self.max_param_degree = max_param_degree
        self._line_starts: list[int] | None = None

    def _segment(self, node: ast.AST) -> str | None:
        """The text of `node`. ast.get_source_segment splits the whole text into lines on every call: once per
        number, that made a long equation take quadratic time. The text is ASCII, so offsets are characters."""
        if self._line_starts is None:
            self._line_starts = [0] + [i + 1 for i, ch in enumerate(self.text) if ch == "\n"]
        try:
            start = self._line_starts[node.lineno - 1] + node.col_offset
            end = self._line_starts[node.end_lineno - 1] + node.end_col_offset
        except (AttributeError, TypeError, IndexError):
            return None
        return self.text[start:end]

    def build(self, node: ast.AST, depth: int = 0) -> Parsed:
        if depth > 4 * MAX_NESTING:
            raise ParseError("expression is nested too deeply")
        if isinstance(node, ast.Expression):
            return self.build(node.body, depth + 1)
        if isinstance(node, ast.Constant):
            return Parsed(self._number(node), 0, 0)
        if isinstance(node, ast.Name):
            return self._name(node)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
            inner = self.build(node.operand, depth + 1)
            expr = -inner.expr if isinstance(node.op, ast.USub) else inner.expr
            return Parsed(expr, inner.degree_bound, inner.param_degree_bound, inner.terms, inner.names)
        if isinstance(node, ast.BinOp):
            return self._binop(node, depth)
        raise self._refused(node)

    def _refused(self, node: ast.AST) -> ParseError:
        """The refusal of `node`, the caret's place at its start (the message quotes it)."""
        error = ParseError(self._refusal(node))
        error.position, error.text = self._where(node), self.original
        return error

    def _refusal(self, node: ast.AST) -> str:
        segment = self._segment(node) or type(node).__name__
        if isinstance(node, ast.Call):
            what = "function calls are not allowed (a product is written with *: a*(b + c))"
        elif isinstance(node, ast.Attribute):
            what = "attribute access is not allowed"
        elif isinstance(node, (ast.Lambda, ast.ListComp, ast.SetComp, ast.DictComp, ast.GeneratorExp)):
            what = "lambdas and comprehensions are not allowed"
        elif isinstance(node, ast.BinOp):
            what = "only + - * / and ^ (or **) are allowed"
        else:
            what = "not a polynomial expression"
        return f"{what}: {segment[:60]!r}"

    def _number(self, node: ast.Constant) -> sympy.Rational:
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParseError(f"not a number: {value!r}"[:80])
        if isinstance(value, float):
            if value != value or value in (float("inf"), float("-inf")):
                raise ParseError("number is not finite")
            # The literal as written ("0.1") is exact as a decimal fraction: keep it exact.
            segment = self._segment(node) or repr(value)
            exponent = _EXPONENT.search(segment)
            if exponent and abs(int(exponent.group(1).replace("_", ""))) > MAX_EXPONENT:
                # 1e-99999999 underflows to a finite 0.0, but its exact value needs 10^99999999
                raise ParseError(f"number {segment[:30]!r} has an exponent beyond ±{MAX_EXPONENT}")
            try:
                frac = Fraction(segment.replace("_", ""))
            except ValueError:
                frac = Fraction(value)
            return _bounded(sympy.Rational(frac.numerator, frac.denominator))
        return _bounded(sympy.Integer(value))

    def _name(self, node: ast.Name) -> Parsed:
        name = node.id
        if name in self.variables:
            return Parsed(self.variables[name], 1, 0, 1, frozenset([name]))
        if name in self.params:
            return Parsed(self.params[name], 0, 1, 1, frozenset([name]))
        known = ", ".join([*self.variables, *self.params]) or "none"
        where = self._where(node)
        raise ParseError(f"unknown symbol {name!r}", where, self.original, f" (known: {known})")

    def _where(self, node: ast.AST) -> int | None:
        """The index in the original text of `node`'s first character."""
        if not self.original or self._segment(node) is None:
            return None
        return syntaxplace.original_index(self.original, self._line_starts[node.lineno - 1] + node.col_offset)

    def _binop(self, node: ast.BinOp, depth: int) -> Parsed:
        op = node.op
        if isinstance(op, ast.Pow):
            return self._power(node, depth)
        if not isinstance(op, (ast.Add, ast.Sub, ast.Mult, ast.Div)):
            raise self._refused(node)
        if isinstance(op, (ast.Add, ast.Sub, ast.Mult)):
            return self._chain(node, depth)
        left = self.build(node.left, depth + 1)
        right = self.build(node.right, depth + 1)
        # Division: by a non-zero constant only.
        if right.degree_bound or right.param_degree_bound or not right.expr.is_Rational:
            segment = self._segment(node.right) or "?"
            raise ParseError(f"division by a non-constant ({segment[:40]}) is not polynomial")
        if right.expr == 0:
            raise ParseError("division by zero")
        return self._constant_checked(
            Parsed(left.expr / right.expr, left.degree_bound, left.param_degree_bound, left.terms, left.names)
        )

    def _chain(self, node: ast.BinOp, depth: int) -> Parsed:
        """`a + b - c + ...` or `a * b * c ...`: Python's parser makes a left-leaning tree as deep as the list
        is long; walk it as the flat list it is, so a sum of 500 terms is not "nested too deeply"."""
        adding = isinstance(node.op, (ast.Add, ast.Sub))
        kinds = (ast.Add, ast.Sub) if adding else (ast.Mult,)
        steps = []
        while isinstance(node, ast.BinOp) and isinstance(node.op, kinds):
            steps.append((node.op, node.right))
            node = node.left
        result = self.build(node, depth + 1)
        terms = [result.expr]
        for op, right in reversed(steps):
            item = self.build(right, depth + 1)
            if adding:
                terms.append(-item.expr if isinstance(op, ast.Sub) else item.expr)
                result = self._counted(
                    result.expr,
                    max(result.degree_bound, item.degree_bound),
                    max(result.param_degree_bound, item.param_degree_bound),
                    result.terms + item.terms,
                    _joined(result, item),
                )
            else:
                result = self._checked(
                    result.expr * item.expr,
                    result.degree_bound + item.degree_bound,
                    result.param_degree_bound + item.param_degree_bound,
                    result.terms * item.terms,
                    _joined(result, item),
                )
        if adding:
            result = Parsed(
                sympy.Add(*terms), result.degree_bound, result.param_degree_bound, result.terms, result.names
            )
        return self._constant_checked(result)

    def _power(self, node: ast.BinOp, depth: int) -> Parsed:
        base = self.build(node.left, depth + 1)
        exponent = self.build(node.right, depth + 1)
        if exponent.degree_bound or exponent.param_degree_bound or not exponent.expr.is_Rational:
            segment = (self._segment(node.right) or "?")[:40]
            raise ParseError(f"exponent must be a constant non-negative integer, not {segment!r}")
        if not exponent.expr.is_integer or exponent.expr < 0:
            raise ParseError(f"exponent must be a non-negative integer, not {exponent.expr}")
        k = int(exponent.expr)
        if base.degree_bound == 0 and base.param_degree_bound == 0:
            bits = max(abs(base.expr.p).bit_length(), abs(base.expr.q).bit_length(), 1)
            if k > 1 and bits * k > 2 * MAX_CONST_BITS:
                raise ParseError(f"constant power too large: exponent {k}")
            return Parsed(_bounded(base.expr**k), 0, 0)
        degree, param_degree = base.degree_bound * k, base.param_degree_bound * k
        self._check_degrees(degree, param_degree)  # before the power: SymPy computes 2^k of (2*x)^k at once
        terms = math.comb(base.terms + k - 1, k) if base.terms < _TERMS_CAP else _TERMS_CAP  # multinomial count
        return self._checked(base.expr**k, degree, param_degree, terms, base.names)

    def _check_degrees(self, degree: int, param_degree: int) -> None:
        if degree > self.max_degree:
            raise ParseError(f"degree would exceed {self.max_degree} (the highest supported)")
        if param_degree > self.max_param_degree:
            raise ParseError(f"parameters raised to a degree above {self.max_param_degree}")

    def _checked(self, expr: sympy.Expr, degree: int, param_degree: int, terms: int, names: frozenset[str]) -> Parsed:
        self._check_degrees(degree, param_degree)
        return self._constant_checked(self._counted(expr, degree, param_degree, terms, names))

    def _counted(self, expr: sympy.Expr, degree: int, param_degree: int, terms: int, names: frozenset[str]) -> Parsed:
        """The term bound is also at most the number of monomials of that degree in the names used (which
        keeps (x+y+z+1)^12 * (x-y+z-1)^12 at 2925, not 455^2)."""
        nv = sum(1 for n in names if n in self.variables)
        monomials = math.comb(degree + nv, nv) * math.comb(param_degree + len(names) - nv, len(names) - nv)
        return Parsed(expr, degree, param_degree, min(terms, monomials, _TERMS_CAP), names)

    @staticmethod
    def _constant_checked(parsed: Parsed) -> Parsed:
        """A node that evaluated to a number (`10^70 * 10^70`) obeys the same bound as a literal."""
        if parsed.expr.is_Rational:
            _bounded(parsed.expr)
        return parsed


def _bounded(value: sympy.Rational) -> sympy.Rational:
    if max(abs(value.p).bit_length(), abs(value.q).bit_length()) > MAX_CONST_BITS:
        raise ParseError(
            f"constant too large or too small: numerator and denominator must stay below 2^{MAX_CONST_BITS} "
            "(about 1e77)"
        )
    return value


def parse_expression(
    text: str,
    variables: Mapping[str, sympy.Symbol],
    params: Mapping[str, sympy.Symbol],
    max_degree: int,
    max_param_degree: int = 64,
) -> Parsed:
    """Parse one side of an equation. `variables` count towards the degree; `params` do not."""
    _check_text(text, "expression")
    if not text.strip():
        raise ParseError("expression is empty")
    if _LONG_NUMBER.search(text):
        raise ParseError(f"a number is written with more than {MAX_DIGITS} digits")
    if _paren_depth(text) > MAX_NESTING:
        raise ParseError(f"parentheses nested deeper than {MAX_NESTING}")
    source = text.replace("^", "**").strip()
    try:
        with warnings.catch_warnings():
            # `1and y`, `1if x else y`: the parser's SyntaxWarning becomes the syntax error it is, not a
            # second line on stderr.
            warnings.simplefilter("error")
            tree = ast.parse(source, mode="eval")
    except (SyntaxError, SyntaxWarning, ValueError) as err:
        raise syntaxplace.syntax_error(text, source, err) from None
    except (RecursionError, MemoryError) as err:
        raise ParseError("expression is nested too deeply") from err
    builder = _Builder(source, variables, params, max_degree, max_param_degree, text)
    try:
        parsed = builder.build(tree)
    except RecursionError as err:
        raise ParseError("expression is nested too deeply") from err
    check_depth(parsed.expr)
    check_terms(parsed.terms)
    as_written = written.written(tree, lambda node: Fraction(int((r := builder._number(node)).p), int(r.q)))
    return replace(parsed, text=as_written)


def expression_depth(expr: sympy.Basic) -> int:
    """The depth of `expr`'s tree as SymPy holds it: a number or a symbol is 0, a sum, product or power one more
    than its deepest operand (SymPy flattens a sum in a sum, a product in a product, and writes -a as -1*a and
    x - y^2 as x + (-1)*y^2). Walked without recursion, each shared subtree once, so in time linear in the
    tree's size whatever its depth."""
    depth: dict[int, tuple[sympy.Basic, int]] = {}  # id -> (node, depth); the node kept so no id is reused
    stack: list[tuple[sympy.Basic, bool]] = [(expr, False)]
    while stack:
        node, ready = stack.pop()
        if id(node) in depth:
            continue
        if ready or not node.args:
            depth[id(node)] = (node, 1 + max((depth[id(a)][1] for a in node.args), default=-1))
            continue
        stack.append((node, True))
        stack.extend((a, False) for a in node.args if id(a) not in depth)
    return depth[id(expr)][1]


def check_depth(expr: sympy.Basic) -> None:
    """Refuse a tree deeper than MAX_TREE_DEPTH, before anything walks it recursively: SymPy's diff, cse and
    printers recurse several Python frames a level, and a tree over 100 levels deep overflowed Python's
    default recursion limit in a fresh process (docs/limitations.md)."""
    depth = expression_depth(expr)
    if depth > MAX_TREE_DEPTH:
        raise ParseError(
            f"sums, products and powers nested {depth} levels deep inside one another (at most {MAX_TREE_DEPTH})"
        )


def _check_text(text: object, what: str) -> None:
    """Text, at most MAX_TEXT_LENGTH characters, of the allowed alphabet; `what` names it in the error."""
    if not isinstance(text, str):
        raise ParseError(f"{what} must be text")
    if len(text) > MAX_TEXT_LENGTH:
        raise ParseError(f"{what} longer than {MAX_TEXT_LENGTH} characters")
    check_alphabet(text)


def check_terms(terms: int) -> None:
    """Refuse what would expand to more than MAX_TERMS terms, before anything expands it."""
    if terms > MAX_TERMS:
        shown = f"{terms:,}" if terms < _TERMS_CAP else f"more than {_TERMS_CAP:,}"
        raise ParseError(f"would expand to up to {shown} terms (at most {MAX_TERMS:,})")


def split_equation(text: str) -> tuple[str, str]:
    """`lhs = rhs` -> (lhs, rhs); a bare `expr` means `expr = 0`."""
    _check_text(text, "equation")
    parts = text.split("=")
    if len(parts) == 1:
        return parts[0], "0"
    if len(parts) == 2 and parts[0].strip() and parts[1].strip():
        return parts[0], parts[1]
    raise ParseError("equation must be 'expr' or 'lhs = rhs' with a single '='")


class _GrammarPrinter(StrPrinter):
    """SymPy's str printer, with powers written `^` and internal symbols under the user's names."""

    def __init__(self, names: Mapping[sympy.Symbol, str]) -> None:
        super().__init__({"order": "lex"})
        self._names = names

    def _print_Symbol(self, expr: sympy.Symbol) -> str:  # noqa: N802 -- SymPy's naming
        return self._names.get(expr, expr.name)

    def _print_Pow(self, expr: sympy.Pow, rational: bool = False) -> str:  # noqa: N802
        return super()._print_Pow(expr, rational).replace("**", "^")


def format_expression(expr: sympy.Expr, names: Mapping[sympy.Symbol, str]) -> str:
    """`expr` printed in the equation grammar (it parses back to the same polynomial), symbols renamed by
    `names`. Its text comes from the expression tree, never from what a user typed."""
    text = _GrammarPrinter(names).doprint(expr)
    check_alphabet(text)  # identifiers, digits, operators: nothing else can come out
    return text
