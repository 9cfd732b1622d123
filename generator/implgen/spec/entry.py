"""The one way in to a shape spec: `load_spec(path)` or `parse_spec(data, source)`.

Without `cache`, the spec is parsed in full with SymPy (spec/parse.py). With `cache=True` it goes through the
parsed-spec cache (spec/cache.py): a spec whose content parsed before comes back without SymPy, its symbolic
part parsed from the same content on first use. Both ways give the same values and raise the same UserError
for the same bad spec; the cache is the caller's explicit choice (a scene's shapes, meshes), never implied.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from implgen.spec.model import Spec
from implgen.yamlfile import read_yaml


def parse_spec(data: Any, source: str = "<spec>", *, cache: bool = False) -> Spec:
    """A validated Spec from an already-loaded mapping (a spec file, or an inline shape in a scene)."""
    if cache:
        from implgen.spec.cache import parse_cached

        return parse_cached(data, source)
    from implgen.spec.parse import parse_full

    return parse_full(data, source)


def load_spec(path: str | Path, *, cache: bool = False) -> Spec:
    """A spec file, read safely (yamlfile.read_yaml) and validated as parse_spec does."""
    path = Path(path)
    return parse_spec(read_yaml(path), str(path), cache=cache)
