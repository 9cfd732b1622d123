"""Build a scene's tracer: which shapes a scene needs compiled (one per distinct spec, or per distinct spec and
param values when folding), and the library holding them (compile/library.py: generated, compiled, cached).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from implgen.compile.library import ShapeEntry, build_library, runtime_progress
from implgen.scene.model import Leaf, Scene


def plan_shapes(scene: Scene, fold: bool) -> tuple[list[ShapeEntry], dict[int, int]]:
    """The shapes to compile and, for each leaf (by id), its index in that list.

    Without folding each distinct spec is compiled once and leaves pass their params at run time. With
    folding each distinct (spec, param values) pair becomes its own shape with the values as constants.
    Names are made unique (two inline shapes may both be called `inline1` in different scenes' terms)."""
    entries: list[ShapeEntry] = []
    index: dict[tuple, int] = {}
    leaf_index: dict[int, int] = {}
    used: set[str] = set()
    for leaf in scene.leaves():
        spec = leaf.spec
        key: tuple = (id(spec),) + ((tuple(leaf.params.values()),) if fold and spec.params else ())
        if key not in index:
            base = spec.name
            name, k = base, 1
            while name.lower() in used:  # without case: Torus.h and torus.h are one file on some systems
                k += 1
                name = f"{base}_{k}"
            used.add(name.lower())
            if fold and spec.params:
                s2 = spec.specialise(leaf.params, name=name)
            elif name != spec.name:
                s2 = spec.specialise({}, name=name)
            else:
                s2 = spec
            index[key] = len(entries)
            entries.append(ShapeEntry(spec=s2, c_name=name, folded=bool(fold and spec.params)))
        leaf_index[id(leaf)] = index[key]
    return entries, leaf_index


def leaf_params(entry: ShapeEntry, leaf: Leaf) -> list[float]:
    return [] if entry.folded else [float(v) for v in leaf.params.values()]


@dataclass
class BuildResult:
    library: Path
    entries: list[ShapeEntry]
    leaf_index: dict[int, int]
    generated: int  # shapes generated on this call (0 when all came from the cache)

    def for_scene(self, scene: Scene, fold: bool) -> BuildResult:
        """This library for another scene made of the same shapes (another frame of an animation, another view
        of the viewer's document): the leaves are mapped anew, nothing is built."""
        entries, leaf_index = plan_shapes(scene, fold)
        if [e.c_name for e in entries] != [e.c_name for e in self.entries]:
            raise AssertionError("a scene uses other shapes than the library was built for")
        return BuildResult(library=self.library, entries=entries, leaf_index=leaf_index, generated=0)


def build_scene(scene: Scene, fold: bool = False, extra_flags: tuple[str, ...] = ()) -> BuildResult:
    """The scene's library; extra_flags: more compiler flags (bench/floor.py's instrumented build)."""
    entries, leaf_index = plan_shapes(scene, fold)
    library, generated = build_library(entries, extra_flags)
    return BuildResult(library=library, entries=entries, leaf_index=leaf_index, generated=generated)


def runtime_ready() -> tuple[int, int]:
    """(the tracer runtime's objects already compiled in the build cache, its sources): a first build compiles
    the rest (compile/library.runtime_progress)."""
    return runtime_progress()
