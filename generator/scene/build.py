"""Build a scene's tracer: generate C for exactly the shapes the scene uses, compile it with runtime_c.

Two caches, both under clib.cache_dir() (`$IMPLGEN_CACHE`, else `$XDG_CACHE_HOME/implgen`, else
`~/.cache/implgen`):
  gen/<key>/      generated .c/.h of one shape; the key hashes the spec's content (equation, params, bounds,
                  folded values, name) and implgen's own generator + template sources, so editing a spec or
                  upgrading implgen regenerates, and nothing else does;
  obj/<name>-<hash>.o  one object per C source (clib.compile_object hashes the source and the headers it
                  can see): the runtime's objects are compiled once and shared by every scene;
  scene-<hash>.so the linked library (clib.link_shared, keyed by its objects).
An unchanged scene therefore neither runs SymPy nor the C compiler the second time, and a new shape costs
one generation, one small compilation (its .c and the glue) and a link.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

from implgen import clib
from implgen.codegen.spec import Spec
from implgen.codegen.templating import environment
from implgen.outputs import atomic_write
from implgen.resources import SHAPE_SOURCES, SOLVER_SOURCES, TRACER_SOURCES, runtime_dir, runtime_sources, templates_dir
from implgen.scene.model import Leaf, Scene


@dataclass
class ShapeEntry:
    spec: Spec  # possibly renamed / with params folded
    c_name: str
    folded: bool


@lru_cache(maxsize=1)
def _implgen_fingerprint() -> str:
    """Hash of the generator's own sources and templates: generated code depends on them."""
    h = hashlib.sha256()
    pkg = Path(__file__).resolve().parent.parent
    for p in sorted(pkg.rglob("*.py")) + sorted(templates_dir().rglob("*.j2")):
        h.update(str(p.relative_to(p.parents[1])).encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def spec_key(spec: Spec) -> str:
    ident = {
        "name": spec.name,
        "f": str(spec.f),
        "params": list(spec.params.items()),
        "bounds": None if spec.bounds is None else {a: [str(lo), str(hi)] for a, (lo, hi) in spec.bounds.items()},
        "folded": sorted(spec.folded.items()),
        "implgen": _implgen_fingerprint(),
    }
    return hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode()).hexdigest()[:24]


def generated_dir(spec: Spec) -> tuple[Path, bool]:
    """Folder with <name>.c/.h for this spec, generated on a cache miss. Returns (folder, was_generated)."""
    from implgen.codegen.emit import generate

    target = clib.cache_dir() / "gen" / spec_key(spec)
    if (target / f"{spec.name}.c").exists() and (target / f"{spec.name}.h").exists():
        return target, False
    files = generate(spec, langs=("c",))
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".gen-", dir=target.parent))
    for fname, text in files.items():
        (tmp / fname).write_text(text, encoding="utf-8")
    try:
        os.replace(tmp, target)  # atomic: a parallel build sees all files or none
    except OSError:  # another process won the race; use its copy
        for p in tmp.iterdir():
            p.unlink()
        tmp.rmdir()
    return target, True


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


def _glue(entries: list[ShapeEntry]) -> str:
    """The C file that lists the scene's shapes for the tracer (templates/scene/glue.c.j2)."""
    return environment().get_template("scene/glue.c.j2").render(entries=entries)


@dataclass
class BuildResult:
    library: Path
    entries: list[ShapeEntry]
    leaf_index: dict[int, int]
    generated: int  # shapes generated on this call (0 when all came from the cache)


def build_scene(scene: Scene, fold: bool = False) -> BuildResult:
    entries, leaf_index = plan_shapes(scene, fold)
    dirs, generated = [], 0
    for e in entries:
        d, fresh = generated_dir(e.spec)
        dirs.append(d)
        generated += fresh
    glue_text = _glue(entries)
    glue_dir = clib.cache_dir() / "glue"
    glue_dir.mkdir(parents=True, exist_ok=True)
    glue = glue_dir / f"glue-{hashlib.sha256(glue_text.encode()).hexdigest()[:20]}.c"
    if not glue.exists():
        data = glue_text.encode()
        atomic_write(glue, lambda fh: fh.write(data))
    rt = runtime_dir()
    # Each runtime source sees only the runtime's headers, so its object is shared by every scene; each shape
    # sees its own folder too, and only the glue sees all of them.
    jobs = [(src, [rt]) for src in runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES, TRACER_SOURCES)]
    jobs += [(d / f"{e.c_name}.c", [rt, d]) for d, e in zip(dirs, entries)]
    jobs.append((glue, [rt, *dirs]))
    objects = clib.compile_objects(jobs, extra_flags=["-pthread"])
    lib = clib.link_shared(objects, libs=["-lm", "-pthread"], tag="scene")
    return BuildResult(library=lib, entries=entries, leaf_index=leaf_index, generated=generated)
