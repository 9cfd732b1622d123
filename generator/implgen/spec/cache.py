"""Validated shape specs cached by content, so a scene whose shapes are unchanged loads without SymPy.

Parsing a spec (spec/parse.py) needs SymPy, whose import alone takes a few hundred milliseconds, yet the
render of a scene whose shapes were built before needs only what the build and the tracer read: the name,
the params and their defaults, the degree and the key of the generated code (`Spec.spec_key`). After a full
parse those are written to `spec/<key>.json` in the build cache (cache_dir(), beside `gen/`), keyed by
the spec's content -- the mapping read from the YAML, every value with its type -- and implgen's own
fingerprint (spec/fingerprint.py). The next load of the same content reads them back as a `Spec` whose
symbolic part is deferred.

Only a spec that parsed is ever written, so a cache keyed by content holds valid specs only: an invalid one
misses and is refused by the full parse with exactly its usual message. What is read back is checked (form,
types, ranges, and that it names the same shape and params as the mapping it was looked up for); anything
unreadable or out of shape is a miss, parsed in full and written again. What a cached spec does not hold
(the expression, symbolic bounds, `specialise`) is parsed from the same mapping on first use.

An entry is data, not code, but it decides which generated code a scene compiles, and it sits in the same
folder as the libraries: the folder's checks apply (cachedir.cache_dir: a folder that is not ours or that
others can write is refused with one line), an entry is read only when it is a regular file of ours that
nobody else can write, written atomically with mode 0600, and touched when used (the cache's size bound
evicts the least recently used entries).
"""

from __future__ import annotations

import hashlib
import json
import math
import re
from pathlib import Path
from typing import Any

from implgen import abi, cachedir
from implgen.errors import UserError
from implgen.spec import paramvalues
from implgen.spec.fingerprint import implgen_fingerprint
from implgen.spec.model import Spec, Symbolic
from implgen.spec.names import check_identifier, check_shape_name

FORMAT = 4
MAX_ENTRY_BYTES = 8 << 20  # an entry holds the printed equation of a spec file of at most 1 MiB
MAX_NESTING = 8  # a spec mapping is four levels deep (bounds -> axis -> pair -> end); deeper is never valid
_ENTRY_KEYS = {
    "format",
    "key",
    "name",
    "equation",
    "written",
    "params",
    "degree",
    "description",
    "title",
    "reference",
    "ranges",
    "box",
    "spec_key",
    "terms",
    "bounds",
}
_HEX24 = re.compile(r"[0-9a-f]{24}\Z")


class _Reparse:
    """The symbolic part of a cached spec: the full parse of the content the entry was found for (a class, not a
    closure, so a spec pickles with it to Dask workers)."""

    def __init__(self, content: str, source: str):
        self.content, self.source = content, source

    def __call__(self) -> Symbolic:
        return _parse(json.loads(self.content), self.source).symbolic


def _cached_spec(entry: dict, content: str, source: str) -> Spec:
    """A `Spec` from a cache entry: the plain data as stored, the symbolic part parsed from the same content
    when first asked for."""

    return Spec(
        name=entry["name"],
        equation=entry["equation"],
        written=entry["written"],
        params={k: v for k, v in entry["params"]},
        degree=entry["degree"],
        param_terms=[(c, tuple(e)) for c, e in entry["terms"]],
        bounds_trees=None if entry["bounds"] is None else {a: (lo, hi) for a, (lo, hi) in entry["bounds"].items()},
        spec_key=entry["spec_key"],
        symbolic_part=Spec.deferred(_Reparse(content, source)),
        description=entry["description"],
        source=source,
        default_box=entry["box"],
        title=entry["title"],
        reference=entry["reference"],
        ranges={k: (lo, hi) for k, lo, hi in entry["ranges"]},
    )


def parse_cached(data: Any, source: str = "<spec>") -> Spec:
    """spec/parse.py's parse_full through the cache: the same errors and the same values, the symbolic part
    deferred when this content parsed before. Callers come through spec/entry.py's parse_spec(cache=True)."""
    content = _canonical(data)
    if content is None:
        return _parse(data, source)
    key = hashlib.sha256(f"{FORMAT}\0{implgen_fingerprint()}\0{content}".encode()).hexdigest()
    path = _entry_path(key)
    entry = _read_entry(path, key, data)
    if entry is not None:
        return _cached_spec(entry, content, source)
    spec = _parse(data, source)  # raises exactly as without a cache
    _write_entry(path, key, spec)
    return spec


def _parse(data: Any, source: str) -> Spec:
    from implgen.spec.parse import parse_full

    return parse_full(data, source)


def _plain(value: Any, depth: int = 0) -> bool:
    """True when `value` is made only of what JSON keeps exactly (str-keyed mappings, lists, text, whole and
    float numbers, booleans, null), so its JSON text identifies it, types included."""
    if depth > MAX_NESTING:
        return False
    if isinstance(value, dict):
        return all(isinstance(k, str) and _plain(v, depth + 1) for k, v in value.items())
    if isinstance(value, list):
        return all(_plain(v, depth + 1) for v in value)
    return value is None or isinstance(value, (str, int, float))  # bool is an int


def _canonical(data: Any) -> str | None:
    """The content as JSON text (mapping order kept: params are ordered), or None when it cannot be keyed."""
    if not isinstance(data, dict) or not _plain(data):
        return None
    return json.dumps(data, ensure_ascii=True, allow_nan=True, separators=(",", ":"))


def _entry_path(key: str) -> Path:
    """Where the entry for `key` lives. The cache folder's checks apply (cachedir.cache_dir: ours, 0700, not a
    link): a folder someone else could write is refused with its one line here too, before anything is read."""
    return cachedir.cache_dir("spec") / f"{key[:40]}.json"


def _read_entry(path: Path, key: str, data: dict) -> dict | None:
    """The entry, if it is a regular file of ours nobody else can write (cachedir.read_file: not a link, a fifo
    does not block), at most MAX_ENTRY_BYTES, JSON, and in the form _write_entry gives it; a hit is touched
    (least-recently-used eviction)."""
    raw = cachedir.read_file(path, MAX_ENTRY_BYTES)
    if raw is None:  # missing, not ours, writable by others, not a regular file, too long
        return None
    try:
        entry = json.loads(raw.decode("utf-8"))
    except (ValueError, RecursionError):  # not UTF-8, not JSON
        return None
    if not _entry_ok(entry, key, data):
        return None
    cachedir.touch(path)
    return entry


def _named(check: Any, name: Any) -> bool:
    try:
        check("<cache>", "name", name)
    except UserError:
        return False
    return True


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _entry_ok(entry: Any, key: str, data: dict) -> bool:
    """The entry has the form _write_entry gives it and describes the shape `data` declares."""
    if not isinstance(entry, dict) or set(entry) != _ENTRY_KEYS:
        return False
    if entry["format"] != FORMAT or entry["key"] != key:
        return False
    name, params, degree, box = entry["name"], entry["params"], entry["degree"], entry["box"]
    if not isinstance(name, str) or name != data.get("name") or not _named(check_shape_name, name):
        return False
    if not isinstance(params, list) or not all(
        isinstance(p, list) and len(p) == 2 and _named(check_identifier, p[0]) and _number(p[1]) for p in params
    ):
        return False
    declared = data.get("params") or {}
    if not isinstance(declared, dict) or [p[0] for p in params] != list(declared):
        return False
    if not isinstance(degree, int) or isinstance(degree, bool) or not 1 <= degree <= abi.value("IG_MAX_DEGREE"):
        return False
    if not isinstance(entry["equation"], str) or not entry["equation"] or not isinstance(entry["written"], str):
        return False
    if not all(isinstance(entry[k], str) for k in ("description", "title", "reference")):
        return False
    if not _ranges_ok(entry["ranges"], [p[0] for p in params]):
        return False
    if not isinstance(entry["spec_key"], str) or not _HEX24.match(entry["spec_key"]):
        return False
    if not _terms_ok(entry["terms"], len(params)) or not _trees_ok(entry["bounds"], [p[0] for p in params]):
        return False
    if (box is None) != (entry["bounds"] is None):
        return False
    if box is None:
        return data.get("bounds") is None
    if not isinstance(box, list) or len(box) != 6 or data.get("bounds") is None:
        return False
    if not all(isinstance(v, float) and not math.isnan(v) for v in box):
        return False
    return all(box[i] < box[i + 3] for i in range(3))


def _ranges_ok(ranges: Any, params: list[str]) -> bool:
    return isinstance(ranges, list) and all(
        isinstance(r, list) and len(r) == 3 and r[0] in params and _number(r[1]) and _number(r[2]) and r[1] < r[2]
        for r in ranges
    )


def _terms_ok(terms: Any, nparams: int) -> bool:
    return isinstance(terms, list) and all(
        isinstance(t, list)
        and len(t) == 2
        and isinstance(t[0], float)
        and math.isfinite(t[0])
        and isinstance(t[1], list)
        and len(t[1]) == nparams
        and all(isinstance(e, int) and not isinstance(e, bool) and e >= 0 for e in t[1])
        for t in terms
    )


def _trees_ok(trees: Any, params: list[str]) -> bool:
    if trees is None:
        return True
    return (
        isinstance(trees, dict)
        and 1 <= len(trees) <= 3
        and all(
            axis in paramvalues.AXES
            and isinstance(pair, list)
            and len(pair) == 2
            and all(paramvalues.tree_ok(t, params) for t in pair)
            for axis, pair in trees.items()
        )
    )


def _write_entry(path: Path, key: str, spec: Spec) -> None:
    box = spec.box()
    entry = {
        "format": FORMAT,
        "key": key,
        "name": spec.name,
        "equation": spec.equation,
        "written": spec.written,
        "params": [[k, v] for k, v in spec.params.items()],
        "degree": spec.degree,
        "description": spec.description,
        "title": spec.title,
        "reference": spec.reference,
        "ranges": [[k, lo, hi] for k, (lo, hi) in spec.ranges.items()],
        "box": None if box is None else [float(v) for v in box],
        "spec_key": spec.spec_key,
        "terms": [[c, list(e)] for c, e in spec.param_terms],
        "bounds": None if spec.bounds_trees is None else {a: list(pair) for a, pair in spec.bounds_trees.items()},
    }
    data = json.dumps(entry, allow_nan=True).encode()
    try:
        cachedir.write_file(path, data)  # atomic, 0600
    except OSError:  # a read-only cache: the next load parses again
        pass
