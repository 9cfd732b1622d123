"""The license: MIT, in LICENSE, pyproject.toml and the installed metadata; and every dependency's license, read
from the installed distributions' metadata, allows it (docs/dependencies.md#licenses)."""

from __future__ import annotations

import importlib.metadata
import re
import tomllib

from packaging.requirements import Requirement
from packaging.utils import canonicalize_name

from conftest import ROOT

# License families by how metadata spells them; permissive, or MPL-2.0 (it binds only the files of the package)
FAMILIES = {
    "MIT": r"\bMIT\b",
    "BSD": r"BSD",
    "Apache": r"Apache",
    "PSF": r"\bPSF\b|Python Software Foundation",
    "MPL": r"\bMPL\b|Mozilla Public",
    "HPND": r"HPND|MIT-CMU",
    "ISC": r"\bISC\b",
    "Zlib": r"\bZlib\b",
    "CC0": r"\bCC0\b",
    "Unlicense": r"Unlicense",
}
COPYLEFT = r"GPL|General Public License|\bEUPL\b|\bCDDL\b|\bSSPL\b"


def license_of(name: str) -> str:
    """A distribution's license as its metadata states it: the SPDX expression, else the license classifiers,
    else the first line of the License field."""
    meta = importlib.metadata.distribution(name).metadata
    if meta.get("License-Expression"):
        return meta["License-Expression"]
    classifiers = [c.split("::")[-1].strip() for c in meta.get_all("Classifier") or [] if c.startswith("License ::")]
    if classifiers:
        return " OR ".join(classifiers)
    return (meta.get("License") or "").strip().split("\n")[0]


def families(text: str) -> set[str]:
    return {family for family, pattern in FAMILIES.items() if re.search(pattern, text, re.IGNORECASE)}


def runtime_closure() -> set[str]:
    """implgen's installed runtime dependencies, and theirs, transitively (markers and extras evaluated)."""
    seen: set[tuple[str, tuple[str, ...]]] = set()
    todo = [(Requirement(r), "") for r in importlib.metadata.distribution("implgen").requires or []]
    while todo:
        req, extra = todo.pop()
        key = (canonicalize_name(req.name), tuple(sorted(req.extras)))
        if (req.marker is not None and not req.marker.evaluate({"extra": extra})) or key in seen:
            continue
        seen.add(key)
        for line in importlib.metadata.distribution(req.name).requires or []:
            todo += [(Requirement(line), e) for e in ("", *req.extras)]
    return {name for name, _ in seen}


def documented() -> dict[str, str]:
    """docs/dependencies.md's license table: canonical package name -> the license it states."""
    text = (ROOT / "docs" / "dependencies.md").read_text().split("## Licenses", 1)[1].split("\n## ", 1)[0]
    rows = re.findall(r"^\| ([^|]+) \| ([^|]+) \|$", text, re.MULTILINE)
    table = {}
    for packages, stated in rows[1:]:  # below the header row
        for name in re.sub(r"\(.*?\)", "", packages).split(","):
            table[canonicalize_name(name.strip())] = stated.strip()
    return table


def test_the_project_is_mit_everywhere():
    assert (ROOT / "LICENSE").read_text().startswith("MIT License\n\nCopyright (c)")
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert project["license"] == "MIT" and project["license-files"] == ["LICENSE"]
    meta = importlib.metadata.distribution("implgen").metadata
    assert meta["License-Expression"] == "MIT"
    assert meta["Summary"] and meta["Keywords"] and meta["Requires-Python"] == ">=3.11"
    assert "Programming Language :: Python :: 3.11" in meta.get_all("Classifier")


def test_every_runtime_dependency_allows_it():
    closure = runtime_closure()
    assert {"sympy", "numpy", "starlette", "distributed", "mpmath", "markupsafe"} <= closure  # transitive too
    for name in sorted(closure):
        stated = license_of(name)
        assert families(stated), (name, stated)
        assert not re.search(COPYLEFT, stated, re.IGNORECASE), (name, stated)


def test_the_docs_table_says_what_the_metadata_says():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    direct = [*project["dependencies"], *(r for extra in project["optional-dependencies"].values() for r in extra)]
    table = documented()
    for requirement in direct:
        name = canonicalize_name(Requirement(requirement).name)
        assert name in table, f"{name} has no row in docs/dependencies.md#licenses"
        stated = license_of(name)
        assert families(table[name]) == families(stated), (name, table[name], stated)
