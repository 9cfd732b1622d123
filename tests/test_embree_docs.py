"""docs/embree.md against what it describes, without Embree: step 2 names every runtime source a shape's
library needs (the lists in implgen.resources) and where the runtime folder is after a pip install, and every
function embree_shape.h declares is named in the page."""

from __future__ import annotations

import re
from pathlib import Path

from implgen import resources

ROOT = Path(__file__).resolve().parent.parent
DOC = (ROOT / "docs/embree.md").read_text()


def _step(n: int) -> str:
    """The text of the numbered step n of "Wiring a shape into your renderer" (up to the next step)."""
    part = DOC.split("## Wiring a shape into your renderer", 1)[1]
    m = re.search(rf"^{n}\. (.*?)(?=^{n + 1}\. |^## )", part, re.S | re.M)
    assert m, f"no step {n}"
    return m.group(1)


def test_step_two_lists_every_source_a_shape_needs():
    step = _step(2)
    named = set(re.findall(r"`([a-z_]+\.c)`", step))
    needed = {*resources.SOLVER_SOURCES, *resources.SHAPE_SOURCES, *resources.EMBREE_SOURCES}
    assert needed <= named, sorted(needed - named)


def test_step_two_says_where_the_runtime_folder_is_once_installed():
    step = _step(2)
    assert "implgen.resources.runtime_dir()" in step and "pip install" in step
    assert (resources.runtime_dir() / "embree_shape.h").is_file()


def test_every_declared_function_is_named():
    header = (ROOT / "runtime_c/embree_shape.h").read_text()
    declared = set(re.findall(r"^\w[\w\s\*]*?\b(ig_embree_\w+)\(", header, re.M))
    assert "ig_embree_context_init" in declared
    missing = sorted(f for f in declared if f not in DOC)
    assert not missing, missing
