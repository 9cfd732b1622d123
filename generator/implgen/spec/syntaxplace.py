"""Refused equations and where they go wrong: `ParseError` (the message, and the index of the character at fault
for the viewer's caret), the grammar's alphabet checked character by character, and the place of a syntax error
with the likely fix. That place is read only once Python's parser has refused the text (spec/grammar.py): the text
is read again as tokens (linear time) to find the first place the grammar cannot go on -- an unclosed or unopened
parenthesis, two operands side by side (`2x`: write 2*x), an operator with nothing on one side -- else Python's
parser's own place is mapped back onto the text as typed. Nothing here decides what is accepted; the messages
quote at most 20 characters of a token.
"""

from __future__ import annotations

import re
import string
from dataclasses import dataclass

ALPHABET = frozenset(string.ascii_letters + string.digits + " \t\n._+-*/^()=")


class ParseError(ValueError):
    """The text is not an acceptable polynomial expression; the message says why, and where when it is known:
    `position` is the index in `text` of the character at fault (a caret goes under it), and the message says its
    column (and line, in a text of several lines) between `head` and `tail`."""

    def __init__(self, head: str, position: int | None = None, text: str = "", tail: str = "") -> None:
        self.head, self.position, self.text, self.tail = head, position, text, tail
        self.placed = position is not None  # the message says where
        place = "" if position is None else f" at {place_in(text, position)}"
        super().__init__(f"{head}{place}{tail}")

    def within(self, text: str, offset: int) -> ParseError:
        """The same error in a longer text, where the parsed one starts at `offset` (the right side of lhs = rhs)."""
        if self.position is None:
            return self
        if self.placed:
            return ParseError(self.head, self.position + offset, text, self.tail)
        moved = ParseError(self.head)
        moved.position, moved.text = self.position + offset, text
        return moved


def place_in(text: str, position: int) -> str:
    """`column C` (1-based), or `line L, column C` in a text of several lines."""
    start = text.rfind("\n", 0, position) + 1
    column = f"column {position - start + 1}"
    return column if "\n" not in text else f"line {text.count(chr(10), 0, position) + 1}, {column}"


def _show(ch: str) -> str:
    return repr(ch) if " " < ch < "\x7f" else f"U+{ord(ch):04X}"


def check_alphabet(text: str) -> None:
    """Refuse the first character outside the grammar's alphabet (comments, quotes, escapes, non-ASCII)."""
    for i, ch in enumerate(text):
        if ch not in ALPHABET:
            what = f"character {_show(ch)} at position {i + 1} is not allowed (an equation uses "
            error = ParseError(what + "letters, digits, spaces, . _ + - * / ^ ( ) and one =)")
            error.position, error.text = i, text  # the caret's place; the message says it already
            raise error


_TOKEN = re.compile(
    r"\s*(?:(?P<number>(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9][0-9_]*)(?:[eE][-+]?[0-9][0-9_]*)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<op>\*\*|[-+*/^])|(?P<open>\()|(?P<close>\))|(?P<other>\S))"
)
_ENDS = ("number", "name", "close")  # a token that can end an operand
_STARTS = ("number", "name", "open")  # and one that can start one


@dataclass(frozen=True)
class _Token:
    kind: str
    text: str
    start: int
    spaced: bool  # white space before it


def _tokens(text: str) -> list[_Token]:
    out, at = [], 0
    while (m := _TOKEN.match(text, at)) is not None:  # None: nothing but white space is left
        kind = m.lastgroup or "other"
        out.append(_Token(kind, m.group(kind)[:20], m.start(kind), m.start(kind) > at))
        at = m.end()
    return out


def _pair_problem(prev: _Token | None, tok: _Token) -> tuple[int, str] | None:
    """What is wrong with `tok` after `prev` (None: at the start), as (index, what), or None."""
    if prev is not None and prev.kind in _ENDS and tok.kind in _STARTS:
        a, b = prev.text, tok.text
        if prev.kind == "number" and tok.kind == "number" and not tok.spaced:
            return prev.start, f"{a + b!r} is not a number"
        if prev.kind == "number" and tok.kind == "name" and not tok.spaced:
            return tok.start, f"write {a}*{b} for {a}{b}: a number and a name side by side are not multiplied"
        return tok.start, f"an operator is missing between {a!r} and {b!r} (a product is written {a}*{b})"
    if tok.kind == "op" and tok.text not in "+-" and (prev is None or prev.kind in ("op", "open")):
        return tok.start, f"{tok.text!r} has nothing before it"
    if tok.kind == "close" and prev is not None and prev.kind == "op":
        return prev.start, f"{prev.text!r} has nothing after it"
    if tok.kind == "close" and prev is not None and prev.kind == "open":
        return prev.start, "'()' holds nothing"
    if tok.kind == "other":
        return tok.start, f"{tok.text!r} is not allowed here"
    return None


def _syntax_problem(text: str) -> tuple[int, str] | None:
    """Where the text goes wrong and what would fix it, as (index, what), or None when the tokens say nothing."""
    tokens = _tokens(text)
    opened: list[int] = []
    for tok in tokens:
        if tok.kind == "open":
            opened.append(tok.start)
        elif tok.kind == "close" and not opened:
            return tok.start, "')' closes nothing: no '(' is open before it"
        elif tok.kind == "close":
            opened.pop()
    if opened:
        return opened[-1], "'(' is never closed: add the ')' that ends it"
    prev = None
    for tok in tokens:
        problem = _pair_problem(prev, tok)
        if problem is not None:
            return problem
        prev = tok
    if prev is not None and prev.kind == "op":
        return prev.start, f"{prev.text!r} has nothing after it"
    return None


def original_index(text: str, index: int) -> int:
    """The index in `text` of the character at `index` of the text Python parsed (`text` stripped, `^` as `**`)."""
    at, done = len(text) - len(text.lstrip()), 0
    while at < len(text) and done < index:
        done += 2 if text[at] == "^" else 1
        at += 1
    return at


def place(text: str, source: str, err: Exception) -> tuple[int | None, str]:
    """(the index in `text` of the character at fault, what is wrong there or "") for a text that Python's parser
    refused as `source` (`text` stripped, `^` written `**`) with `err`; (None, "") when nothing says where."""
    problem = _syntax_problem(text)
    if problem is not None:
        return problem
    line, offset = getattr(err, "lineno", None), getattr(err, "offset", None)
    if not isinstance(line, int) or not isinstance(offset, int) or line < 1 or offset < 1:
        return None, ""
    starts = [0] + [i + 1 for i, ch in enumerate(source) if ch == "\n"]
    index = starts[min(line, len(starts)) - 1] + offset - 1
    return min(original_index(text, index), len(text)), ""


def syntax_error(text: str, source: str, err: Exception) -> ParseError:
    """The ParseError for a text Python's parser refused: where, and the likely fix when the tokens show it
    ; else where Python's parser stopped."""
    index, what = place(text, source, err)
    return ParseError("syntax error", index, text, f": {what}" if what else "")
