"""The page's gallery picker: every gallery spec (implgen.spec.gallery) as the JSON the page reads from
/gallery.json -- title, the line on what it is, its source, and the spec's own equation, params, ranges and
bounds, which the page sends back as an ordinary `shape` message (parsed and checked like typed text).

Only plain values travel: a field of another type is left out (the entry too, without an equation). The page
shows every text with textContent, never as markup.
"""

from __future__ import annotations

import json
import logging
import math
from typing import Any

from implgen.errors import UserError
from implgen.spec import gallery

log = logging.getLogger("implgen.view")


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _numbers(raw: Any, size: int | None = None) -> dict[str, Any]:
    """name -> number (size None) or name -> [two numbers or expressions] (size 2), the rest left out."""
    if not isinstance(raw, dict):
        return {}
    if size is None:
        return {k: v for k, v in raw.items() if isinstance(k, str) and _number(v)}
    pairs = {k: v for k, v in raw.items() if isinstance(k, str) and isinstance(v, list) and len(v) == size}
    return {k: list(v) for k, v in pairs.items() if all(_number(x) or isinstance(x, str) for x in v)}


def entry_json(e: gallery.Entry) -> dict[str, Any] | None:
    equation = e.data.get("equation")
    if not isinstance(equation, str):
        return None
    out: dict[str, Any] = {**e.as_dict(), "equation": " ".join(equation.split())}
    out["params"] = _numbers(e.data.get("params"))
    out["ranges"] = {k: v for k, v in _numbers(e.data.get("ranges"), 2).items() if all(map(_number, v))}
    bounds = _numbers(e.data.get("bounds"), 2)
    if bounds:
        out["bounds"] = bounds
    return out


def gallery_json() -> bytes:
    """The JSON list, in the gallery's order (by title); an unreadable gallery is an empty list and a log line."""
    try:
        items = [j for j in map(entry_json, gallery.entries()) if j is not None]
    except UserError as err:
        log.warning("gallery not listed: %s", err)
        items = []
    return json.dumps(items, ensure_ascii=True).encode("ascii")
