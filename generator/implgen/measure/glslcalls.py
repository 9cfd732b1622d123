"""How many times a GLSL program holds a function once every call is inlined, as GPU compilers do (GLSL has no
recursion): the copies of `target` in `main` are its calls in main, plus, for every function main calls, that
function's copies times the calls. Read from the program's text: its top-level function definitions, their
bodies found by matching braces, a call being the function's name followed by `(`; `#define NAME VALUE` lines
of one identifier (the IG_SHAPE_* names of a page's main) are followed to the name they stand for.
tests/test_glsl_page_program.py and bench/glsl_page_cost.py count the shape's tree in the page's program with it.
"""

from __future__ import annotations

import re
from functools import cache

_DEFINITION = re.compile(r"^[A-Za-z_]\w*\s+([A-Za-z_]\w*)\s*\(([^;{}()]*)\)\s*\{", re.MULTILINE)
_ALIAS = re.compile(r"^#define\s+([A-Za-z_]\w*)\s+([A-Za-z_]\w*)\s*$", re.MULTILINE)
_CALL = re.compile(r"\b([A-Za-z_]\w*)\s*\(")


def _bodies(text: str) -> dict[str, str]:
    out = {}
    for m in _DEFINITION.finditer(text):
        depth, i = 1, m.end()
        while depth and i < len(text):
            depth += {"{": 1, "}": -1}.get(text[i], 0)
            i += 1
        out[m.group(1)] = text[m.end() : i - 1]
    return out


def inlined_copies(program: str, target: str, root: str = "main") -> int:
    """How many copies of function `target` the program's `root` holds with every call inlined."""
    alias = dict(_ALIAS.findall(program))
    bodies = _bodies(program)
    calls = {name: [alias.get(c, c) for c in _CALL.findall(body)] for name, body in bodies.items()}

    @cache
    def copies(name: str) -> int:
        return sum(1 if c == target else copies(c) for c in calls.get(name, ()) if c == target or c in bodies)

    return copies(root)
