"""A refused equation says where: the column (and line) of the character at fault, in the message and as a
position the viewer puts a caret under, and the likely fix where the tokens show it (`write 2*x for 2x`). The
place is found only once Python's parser has refused the text: nothing here changes what is accepted."""

from __future__ import annotations

import pytest

from implgen.errors import UserError
from implgen.spec.entry import parse_spec

CASES = [
    ("x^2 + y^2 + (z^2 - 1", 12, "syntax error at column 13: '(' is never closed: add the ')' that ends it"),
    ("2x^2 + y^2", 1, "syntax error at column 2: write 2*x for 2x"),
    ("x^2 + y^2 = (z", 12, "syntax error at column 13: '(' is never closed"),  # the right side: the whole text
    ("x^2 +", 4, "syntax error at column 5: '+' has nothing after it"),
    ("x^2 + y */ 2", 9, "syntax error at column 10: '/' has nothing before it"),
    ("x)", 1, "syntax error at column 2: ')' closes nothing"),
    ("x y", 2, "syntax error at column 3: an operator is missing between 'x' and 'y' (a product is written x*y)"),
    ("1.2.3 + x", 0, "syntax error at column 1: '1.2.3' is not a number"),
    ("x^2 +\n  2y", 9, "syntax error at line 2, column 4: write 2*y for 2y"),
    ("x^2 + q", 6, "unknown symbol 'q' at column 7 (known: x, y, z)"),
    ("x^2 + y^2 = 1 + q*z", 16, "unknown symbol 'q' at column 17"),
    ("x(y + 1)", 0, "function calls are not allowed (a product is written with *: a*(b + c))"),
    ("x^2 # c", 4, "character '#' at position 5 is not allowed"),
]


@pytest.mark.parametrize("equation, position, fragment", CASES, ids=[c[0] for c in CASES])
def test_a_refused_equation_says_where_and_the_likely_fix(equation: str, position: int, fragment: str) -> None:
    with pytest.raises(UserError) as caught:
        parse_spec({"name": "s", "equation": equation}, "s.yaml")
    err = caught.value
    assert fragment in err.message and str(err).startswith("s.yaml: equation: ") and "\n" not in str(err)
    assert err.position == position


@pytest.mark.parametrize("equation", ["2*x^2 + y^2 - 1", "2e3*x^2 + y^2 - 1", "2e-3*x + y^2 + z^2 - 1", "1_0*x - y"])
def test_numbers_in_exponent_notation_still_read(equation: str) -> None:
    """`2x` is refused rather than read as 2*x: `2e3` is a number, and with a param called `e` the digit after it
    would decide whether `2e` is a product; the message names the fix instead."""
    assert parse_spec({"name": "s", "equation": equation}, "s.yaml").degree >= 1
