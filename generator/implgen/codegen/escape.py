"""Text that reaches a generated file, escaped for the exact place it lands in.

Generated files never contain raw user text: the equation is re-printed from its parsed tree
(`spec.canonical_equation`) and names are validated identifiers. Whatever else reaches a generated file (a
file name, a description) goes through one of these functions, each safe for ANY input string:

  c_comment   inside /* ... */ : no `*/` or `/*`, no `?` (C99 trigraphs: `??/` is a backslash, and a
              backslash before a newline splices lines), no newline, only printable ASCII.
  c_string    inside "..."     : backslash, quote and `?` escaped; anything not printable ASCII as a
              three-digit octal escape (hex escapes in C swallow every hex digit that follows).
  py_docstring inside \"\"\"...\"\"\" : backslash and every quote escaped (so no quote run can end it),
              anything not printable ASCII as \\xNN / \\uNNNN / \\UNNNNNNNN.
  py_string   a complete Python string literal (quotes included), printable ASCII only.
  glsl_comment after // : letters, digits, space and `_ . , : ; + - * / ^ ( ) =` only (GLSL ES 3.00 refuses
              many characters even in comments, and a backslash at the end would continue the comment onto
              the next line of code); anything else as U+XXXX.
"""

from __future__ import annotations

_PRINTABLE = frozenset(chr(c) for c in range(0x20, 0x7F))
_GLSL_COMMENT = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789 _.,:;+-*/^()=")


def _py_escape(ch: str) -> str:
    code = ord(ch)
    if code < 0x100:
        return f"\\x{code:02x}"
    return f"\\u{code:04x}" if code < 0x10000 else f"\\U{code:08x}"


def c_comment(text: str) -> str:
    """`text` made safe inside a C block comment, whatever stands around it: one line of printable ASCII
    with no `*/`, `/*` or `?`, and no `*` or `/` at either end (it could pair with the comment's own)."""
    out: list[str] = []
    text = str(text)
    for i, ch in enumerate(text):
        edge = i == 0 or i == len(text) - 1
        if ch not in _PRINTABLE or ch in "\\?":
            out.append(_py_escape(ch))
        elif ch in "*/" and (edge or (out and out[-1][-1:] in "*/" and out[-1][-1:] != ch)):
            out.append(_py_escape(ch))  # `*/` would close the comment, `/*` open a nested one
        else:
            out.append(ch)
    return "".join(out)


def c_string(text: str) -> str:
    """The body of a C string literal (without the quotes) that reads back as `text`'s UTF-8 bytes."""
    out = []
    for byte in str(text).encode("utf-8"):
        ch = chr(byte)
        if ch in '\\"?':
            out.append("\\" + ch)
        elif ch in _PRINTABLE:
            out.append(ch)
        else:
            out.append(f"\\{byte:03o}")
    return "".join(out)


def py_docstring(text: str) -> str:
    """`text` made safe inside a triple-quoted, non-raw Python string; it reads back as `text`."""
    out = []
    for ch in str(text):
        if ch in "\\\"'":
            out.append("\\" + ch)
        elif ch in _PRINTABLE:
            out.append(ch)
        else:
            out.append(_py_escape(ch))
    return "".join(out)


def py_string(text: str) -> str:
    """A double-quoted Python string literal that evaluates to `text` (printable ASCII only)."""
    return f'"{py_docstring(text)}"'


def glsl_comment(text: str) -> str:
    """`text` made safe after `//` in GLSL: one line of a small alphabet, anything else written U+XXXX."""
    return "".join(ch if ch in _GLSL_COMMENT else f"U+{ord(ch):04X}" for ch in str(text))
