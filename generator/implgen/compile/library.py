"""Shapes -> one shared library: generate C for each shape (cached), the glue that lists them, compile with
runtime_c and link.

Caches, all under cachedir.cache_dir() (`$IMPLGEN_CACHE`, else `$XDG_CACHE_HOME/implgen`, else
`~/.cache/implgen`):
  spec/<key>.json a parsed spec, keyed by its content (codegen/speccache.py): what the build needs of it;
  gen/<key>/      generated .c/.h of one shape; the key (speccache.spec_key) hashes the spec's content
                  (equation, params, bounds, folded values, name) and implgen's own generator + template
                  sources, so editing a spec or upgrading implgen regenerates, and nothing else does;
  obj/<name>-<hash>.o  one object per C source (clib.compile_object hashes the source and the headers it
                  can see): the runtime's objects are compiled once and shared by every library;
  glue/glue-<key>.c the C list of a library's shapes, keyed by their C names and implgen's fingerprint;
  scene-<hash>.so the linked library (clib.link_shared, keyed by its objects).
An unchanged set of shapes therefore neither imports SymPy nor runs the C compiler the second time, and a new
shape costs one generation, one small compilation (its .c and the glue) and a link.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from implgen.cachedir import cache_dir
from implgen.codegen.fingerprint import implgen_fingerprint
from implgen.codegen.specmodel import Spec
from implgen.compile import clib
from implgen.outputs import atomic_write
from implgen.resources import SHAPE_SOURCES, SOLVER_SOURCES, TRACER_SOURCES, runtime_dir, runtime_sources


@dataclass(frozen=True)
class ShapeEntry:
    """One shape of a library: its spec (possibly renamed, or with params folded) under its C name."""

    spec: Spec
    c_name: str
    folded: bool


def generated_dir(spec: Spec) -> tuple[Path, bool]:
    """Folder with <name>.c/.h for this spec, generated on a cache miss. Returns (folder, was_generated)."""
    target = cache_dir() / "gen" / spec.spec_key
    if (target / f"{spec.name}.c").exists() and (target / f"{spec.name}.h").exists():
        return target, False
    from implgen.codegen.emit import generate  # SymPy: only when there is something to generate

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


def _glue(entries: Sequence[ShapeEntry]) -> Path:
    """The C file that lists the shapes for the tracer (templates/scene/glue.c.j2), cached by what it is made
    of: the shapes' C names and implgen's fingerprint (which covers the template)."""
    names = "\0".join(e.c_name for e in entries)
    key = hashlib.sha256(f"{implgen_fingerprint()}\0{names}".encode()).hexdigest()[:20]
    glue = cache_dir() / "glue" / f"glue-{key}.c"
    if not glue.exists():
        from implgen.codegen.templating import environment  # Jinja2, only when the glue is new

        data = environment().get_template("scene/glue.c.j2").render(entries=entries).encode()
        glue.parent.mkdir(parents=True, exist_ok=True)
        atomic_write(glue, lambda fh: fh.write(data))
    return glue


def build_library(entries: Sequence[ShapeEntry]) -> tuple[Path, int]:
    """The tracer library holding these shapes: (its path, how many shapes were generated on this call)."""
    dirs, generated = [], 0
    for e in entries:
        d, fresh = generated_dir(e.spec)
        dirs.append(d)
        generated += fresh
    glue = _glue(entries)
    rt = runtime_dir()
    # Each runtime source sees only the runtime's headers, so its object is shared by every library; each shape
    # sees its own folder too, and only the glue sees all of them.
    jobs = [(src, [rt]) for src in runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES, TRACER_SOURCES)]
    jobs += [(d / f"{e.c_name}.c", [rt, d]) for d, e in zip(dirs, entries)]
    jobs.append((glue, [rt, *dirs]))
    objects = clib.compile_objects(jobs, extra_flags=["-pthread"])
    return clib.link_shared(objects, libs=["-lm", "-pthread"], tag="scene"), generated
