"""The gallery: famous algebraic surfaces, each a shape spec with a title, a line on what it is and the work it
comes from (docs/surfaces.md).

A spec in the gallery's folder (resources.gallery_dir(): examples/shapes/ in the source tree, `implgen.gallery`
once installed) is in the gallery when it names its `reference`. Listing reads the YAML only -- no equation is
parsed here, so no SymPy is imported; `entry.load()` gives the checked `Spec`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from implgen.errors import UserError
from implgen.resources import gallery_dir
from implgen.spec.entry import parse_spec
from implgen.spec.model import Spec
from implgen.yamlfile import read_yaml

FRAME_RADIUS = 2.0  # an open axis of a gallery spec, in a picture: [-2, 2]


@dataclass(frozen=True)
class Entry:
    name: str  # the spec's name (an identifier: its files and functions are called so)
    title: str  # e.g. "Kummer quartic"
    description: str  # one line: what it is
    reference: str  # the work it comes from
    path: Path = field(repr=False)
    data: dict = field(repr=False)  # the mapping read from the YAML, as parse_spec takes it

    @property
    def source(self) -> str:
        return str(self.path)

    @property
    def text(self) -> str:
        """The spec file as written (for the viewer's 'show the YAML', a download)."""
        return self.path.read_text(encoding="utf-8")

    def as_dict(self) -> dict[str, str]:
        """The entry as plain text for a page's picker (JSON): name, title, description, reference. Text, to be
        shown as text (never as markup)."""
        return {"name": self.name, "title": self.title, "description": self.description, "reference": self.reference}

    def load(self) -> Spec:
        """The checked `Spec`, through the spec cache (spec/cache.py: a second load needs no SymPy)."""
        return parse_spec(self.data, self.source, cache=True)

    def load_framed(self, radius: float = FRAME_RADIUS) -> Spec:
        """The `Spec` with a whole box: an axis the spec leaves open (Barth's sextic runs off to infinity) is
        bounded to [-radius, radius], as a picture of it must be."""
        bounds = self.data.get("bounds") or {}
        if isinstance(bounds, dict) and all(a in bounds for a in "xyz"):
            return self.load()
        framed = {a: bounds.get(a, [-radius, radius]) for a in "xyz"} if isinstance(bounds, dict) else bounds
        return parse_spec({**self.data, "bounds": framed}, self.source, cache=True)


def _text(data: dict, key: str) -> str:
    value = data.get(key, "")
    return " ".join(value.split()) if isinstance(value, str) else ""


def entries(folder: str | Path | None = None) -> list[Entry]:
    """Every gallery spec, by title. A YAML file that is not a mapping naming a `reference` is not in the gallery;
    an unreadable file, or a gallery spec without a name, is a UserError (one line naming the file). The
    equations are checked by load()."""
    base = Path(folder) if folder is not None else gallery_dir()
    out = []
    for path in sorted(base.glob("*.yaml")):
        data = read_yaml(path)
        if not isinstance(data, dict) or not data.get("reference"):
            continue
        name = data.get("name")
        if not isinstance(name, str) or not name:
            raise UserError(path, "a gallery spec needs a name")
        title = _text(data, "title") or name
        out.append(Entry(name, title, _text(data, "description"), _text(data, "reference"), path, data))
    return sorted(out, key=lambda e: e.title.casefold())


def entry(name: str, folder: str | Path | None = None) -> Entry:
    """The gallery entry called `name` (KeyError when there is none)."""
    for e in entries(folder):
        if e.name == name:
            return e
    raise KeyError(name)
