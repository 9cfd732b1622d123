"""The Jinja2 environment every generated file comes from (shapes and the scene glue).

StrictUndefined, so a template naming a missing value fails instead of printing nothing; no autoescaping,
because the targets are C, Python and GLSL, not HTML: text that lands in a comment, docstring or string literal
goes through the filter for that place (codegen/escape.py). Cheap to import: no SymPy here.
"""

from __future__ import annotations

from functools import lru_cache

import jinja2

from implgen.codegen import escape
from implgen.resources import templates_dir


@lru_cache(maxsize=1)
def environment() -> jinja2.Environment:
    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(templates_dir())),
        undefined=jinja2.StrictUndefined,
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        autoescape=False,
    )
    env.filters.update(
        c_comment=escape.c_comment,
        c_string=escape.c_string,
        py_doc=escape.py_docstring,
        py_str=escape.py_string,
        glsl_comment=escape.glsl_comment,
    )
    return env
