"""Numbers and vectors from user files, checked once, the same way everywhere.

Every check raises a one-line UserError naming the file and the key. Integers are compared exactly before
any conversion, so a width written with 400 digits is "outside [1, 16384]", never an OverflowError, and a
value that passes is a finite double inside its documented range: no inf or NaN reaches the C side.
"""

from __future__ import annotations

import math
from typing import Any

from implgen.errors import UserError

# The documented range of any length or coordinate in a spec or scene (positions, translations, params,
# bounds): past it, squares and products of the ray's polynomials leave double range at high degree.
MAX_COORDINATE = 1e9


def describe(value: Any) -> str:
    """A short, safe rendering of a bad value for a message."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int) and value.bit_length() > 64:
        return f"a {'negative ' if value < 0 else ''}number of about 1e{int(value.bit_length() * 0.30103)}"
    if isinstance(value, (int, float)):
        return f"{value:g}"
    if isinstance(value, str):
        return repr(value[:40])
    return f"a {type(value).__name__}"


def key_name(k: Any) -> str:
    """A mapping key as it appears in a message: the key itself when it is a plain name, else described."""
    return k if isinstance(k, str) and k.isidentifier() else describe(k)


def mapping(
    source: str, key: str, value: Any, allowed: tuple[str, ...], required: tuple[str, ...] = (), what: str = ""
) -> dict:
    """`value` is a mapping with only `allowed` keys and every `required` one; `what` says what it should
    hold, for the message when it is not a mapping at all."""
    if not isinstance(value, dict):
        raise _fail(source, key, f"expected a mapping{' with ' + what if what else ''}")
    for k in value:
        if k not in allowed:
            name = key_name(k)
            raise _fail(source, f"{key}.{name}" if key else name, f"unknown key (allowed: {', '.join(allowed)})")
    for k in required:
        if k not in value:
            raise _fail(source, key, f"missing key {k!r}")
    return value


def _fail(source: str, key: str, message: str) -> UserError:
    return UserError(source, f"{key}: {message}" if key else message)


def _range_text(lo: float, hi: float, lo_open: bool) -> str:
    return f"{'(' if lo_open else '['}{lo:g}, {hi:g}]"


def number(
    source: str,
    key: str,
    value: Any,
    lo: float = -MAX_COORDINATE,
    hi: float = MAX_COORDINATE,
    *,
    lo_open: bool = False,
    text_ok: bool = False,
) -> float:
    """A finite number in [lo, hi] (or (lo, hi] with lo_open). `text_ok` also takes "1.5" written as text
    (YAML reads `1e3`, without a dot, as text)."""
    if text_ok and isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise _fail(source, key, f"expected a finite number, not {describe(value)}") from None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(source, key, f"expected a finite number, not {describe(value)}")
    if isinstance(value, float) and not math.isfinite(value):
        raise _fail(source, key, f"expected a finite number, not {value}")
    if value < lo or value > hi or (lo_open and value == lo):  # exact for ints of any size
        raise _fail(source, key, f"{describe(value)} is outside {_range_text(lo, hi, lo_open)}")
    return float(value)


def whole(source: str, key: str, value: Any, lo: int, hi: int) -> int:
    """A whole number in [lo, hi]."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise _fail(source, key, f"expected a whole number, not {describe(value)}")
    if not lo <= value <= hi:
        raise _fail(source, key, f"{describe(value)} is outside [{lo}, {hi}]")
    return value


def vector(
    source: str,
    key: str,
    value: Any,
    lo: float = -MAX_COORDINATE,
    hi: float = MAX_COORDINATE,
) -> tuple[float, float, float]:
    """Three finite numbers, each in [lo, hi]."""
    if not isinstance(value, (list, tuple)) or len(value) != 3:
        raise _fail(source, key, "expected a list of three numbers")
    x, y, z = (number(source, f"{key}[{i}]", v, lo, hi) for i, v in enumerate(value))
    return (x, y, z)
