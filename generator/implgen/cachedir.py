"""Where implgen keeps what it builds and parses (the build cache): `$IMPLGEN_CACHE`, else
`$XDG_CACHE_HOME/implgen`, else `~/.cache/implgen`.

On the ground floor because two rooms keep entries there: the spec cache (codegen/speccache.py: parsed specs)
and the compile room (compile/: generated C, objects, libraries)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_dir() -> Path:
    """The build cache folder (created on demand)."""
    env = os.environ.get("IMPLGEN_CACHE")
    if env:
        root = Path(env)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        root = (Path(xdg) if xdg else Path.home() / ".cache") / "implgen"
    root.mkdir(parents=True, exist_ok=True)
    return root
