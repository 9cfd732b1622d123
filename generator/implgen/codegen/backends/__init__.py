"""One folder per target language (c/, python/, glsl/), each a `Backend` (contract.py) in its `backend.py`:
name, template folder, files, printer. `backend(lang)` imports only the one asked for; the folders' own modules
(the GLSL program assembly, say) import without any printer. README.md: how to add a language."""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # contract.py imports SymPy: LANGS alone stays cheap (the CLI's usage line reads it)
    from implgen.codegen.backends.contract import Backend

LANGS = ("c", "python", "glsl")  # every backend, in the order `--lang all` writes them


def backend(lang: str) -> Backend:
    """The backend of `lang` (one of LANGS)."""
    if lang not in LANGS:
        raise ValueError(f"unknown language {lang!r}; backends: {', '.join(LANGS)}")
    return importlib.import_module(f"implgen.codegen.backends.{lang}.backend").BACKEND
