"""What generated code depends on besides the spec: implgen's own generator sources and templates.

Both keys built from it live here, below the modules that use them: the key of a spec's generated code
(`code_key`, which spec/parse.py gives every parsed spec) and the spec cache's entry key
(spec/cache.py). Editing a spec or upgrading implgen changes them; nothing else does.
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Mapping
from functools import cache

from implgen.resources import templates_dir


@cache
def implgen_fingerprint() -> str:
    """Hash of the package's own Python sources and templates: generated code and parsed specs depend on them.
    Each file adds its folder's name, its own name and its bytes, in path order; every cached start computes
    it, so the tree is walked with os.walk rather than Path.rglob (the same files in the same order)."""
    h = hashlib.sha256()
    pkg = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))
    for top, suffix in ((pkg, ".py"), (str(templates_dir()), ".j2")):
        for _, folder, name in _files(top, suffix):
            with open(os.path.join(folder, name), "rb") as fh:
                h.update(f"{os.path.basename(folder)}/{name}".encode() + b"\0" + fh.read())
    return h.hexdigest()


def _files(top: str, suffix: str) -> list[tuple[tuple[str, ...], str, str]]:
    """(path parts below `top`, folder, name) of every file under `top` whose name ends in `suffix`, sorted by
    the parts as pathlib sorts paths; folders that are symbolic links are not entered (as Path.rglob)."""
    found = []
    for folder, _, names in os.walk(top):
        rel = os.path.relpath(folder, top)
        parts = () if rel == "." else tuple(rel.split(os.sep))
        found += [((*parts, n), folder, n) for n in names if n.endswith(suffix)]
    return sorted(found)


def code_key(
    name: str,
    f_text: str,
    params: Mapping[str, float],
    bounds_text: Mapping[str, tuple[str, str]] | None,
    folded: Mapping[str, float],
) -> str:
    """The key of one shape's generated code: its name, f and bounds as SymPy prints them, the params with
    their defaults, the folded values and implgen's fingerprint."""
    ident = {
        "name": name,
        "f": f_text,
        "params": list(params.items()),
        "bounds": None if bounds_text is None else {a: list(pair) for a, pair in bounds_text.items()},
        "folded": sorted(folded.items()),
        "implgen": implgen_fingerprint(),
    }
    return hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode()).hexdigest()[:24]
