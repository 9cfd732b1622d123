"""What generated code depends on besides the spec: implgen's own generator sources and templates.

Both keys built from it live here, below the modules that use them: the key of a spec's generated code
(`code_key`, which spec/parse.py gives every parsed spec) and the spec cache's entry key
(spec/cache.py). Editing a spec or upgrading implgen changes them; nothing else does.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from functools import cache
from pathlib import Path

from implgen.resources import templates_dir


@cache
def implgen_fingerprint() -> str:
    """Hash of the package's own Python sources and templates: generated code and parsed specs depend on them."""
    h = hashlib.sha256()
    pkg = Path(__file__).resolve().parent.parent
    for p in sorted(pkg.rglob("*.py")) + sorted(templates_dir().rglob("*.j2")):
        h.update(str(p.relative_to(p.parents[1])).encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


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
