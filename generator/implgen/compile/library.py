"""Shapes -> one shared library: generate C for each shape (cached), the glue that lists them, compile with
runtime_c and link.

Caches, all under cachedir.cache_dir() (`$IMPLGEN_CACHE`, else `$XDG_CACHE_HOME/implgen`, else
`~/.cache/implgen`; created 0700 and refused unless it is ours alone -- cachedir's notes):
  spec/<key>.json a parsed spec, keyed by its content (spec/cache.py): what the build needs of it;
  gen/<key>/      generated .c/.h of one shape, each sealed; the key (speccache.spec_key) hashes the spec's
                  content (equation, params, bounds, folded values, name) and implgen's own generator + template
                  sources, so editing a spec or upgrading implgen regenerates, and nothing else does;
  obj/<name>-<hash>.o  one object per C source (clib: the source, the headers it can see, the flags and the
                  compiler): the runtime's objects are compiled once and shared by every library;
  glue/glue-<key>.c the C list of a library's shapes, keyed by their C names and implgen's fingerprint, sealed;
  lib/scene-<hash>.so the linked library (clib, keyed by its objects' keys), sealed and checked before dlopen.
Generated files are sources of code, so they are sealed like the objects (cachedir.write_entry): a truncated
or edited one is generated again, never compiled. An unchanged set of shapes therefore neither imports SymPy
nor runs the C compiler the second time, and a new shape costs one generation, one small compilation (its .c
and the glue) and a link.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from implgen import cachedir
from implgen.compile import clib
from implgen.errors import UserError
from implgen.resources import (
    MESH_SOURCES,
    SHAPE_SOURCES,
    SOLVER_SOURCES,
    TRACER_SOURCES,
    runtime_dir,
    runtime_sources,
)
from implgen.spec.fingerprint import implgen_fingerprint
from implgen.spec.model import Spec


@dataclass(frozen=True)
class ShapeEntry:
    """One shape of a library: its spec (possibly renamed, or with params folded) under its C name."""

    spec: Spec
    c_name: str
    folded: bool


def _gen_key(spec: Spec, fname: str) -> str:
    return hashlib.sha256(f"gen\0{spec.spec_key}\0{fname}".encode()).hexdigest()


def _generated_ok(folder: Path, spec: Spec) -> bool:
    """The folder holds this spec's sealed .c and .h (and is a folder of ours, not a link)."""
    if cachedir.folder_problem(folder) is not None:
        return False
    return all(cachedir.check_entry(folder / f, _gen_key(spec, f)) for f in (f"{spec.name}.c", f"{spec.name}.h"))


def generated_dir(spec: Spec) -> tuple[Path, bool]:
    """Folder with <name>.c/.h for this spec, generated on a cache miss. Returns (folder, was_generated)."""
    target = cachedir.cache_dir("gen") / spec.spec_key
    if _generated_ok(target, spec):
        cachedir.touch(target)
        return target, False
    from implgen.codegen.emit import generate  # SymPy: only when there is something to generate

    files = generate(spec, langs=("c",))
    tmp = cachedir.temp_path(target.parent)
    try:
        os.mkdir(tmp, 0o700)
        for fname, text in files.items():
            cachedir.write_entry(tmp / fname, text.encode("utf-8"), _gen_key(spec, fname))
    except OSError as err:
        cachedir.remove_entry(tmp)
        raise UserError(cachedir.label(), f"cannot write in {target.parent}: {err.strerror or err}") from None
    if os.path.lexists(target) and not _generated_ok(target, spec):
        cachedir.remove_entry(target)  # broken (it did not verify): made again
    try:
        os.replace(tmp, target)  # atomic: a parallel build sees all files or none
    except OSError:  # another process won the race; use its copy
        cachedir.remove_entry(tmp)
    cachedir.touch(target)
    return target, True


def _glue(entries: Sequence[ShapeEntry]) -> Path:
    """The C file that lists the shapes for the tracer (templates/scene/glue.c.j2), cached by what it is made
    of: the shapes' C names and implgen's fingerprint (which covers the template)."""
    names = "\0".join(e.c_name for e in entries)
    key = hashlib.sha256(f"glue\0{implgen_fingerprint()}\0{names}".encode()).hexdigest()
    glue = cachedir.cache_dir("glue") / f"glue-{key[:32]}.c"
    if not cachedir.check_entry(glue, key):
        from implgen.codegen.templating import environment  # Jinja2, only when the glue is new

        data = environment().get_template("scene/glue.c.j2").render(entries=entries).encode()
        try:
            cachedir.write_entry(glue, data, key)
        except OSError as err:
            raise UserError(cachedir.label(), f"cannot write {glue}: {err.strerror or err}") from None
    return glue


LIBRARY_FLAGS = ("-pthread",)


def _runtime_jobs() -> list[tuple[Path, list[Path]]]:
    rt = runtime_dir()
    return [(src, [rt]) for src in runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES, MESH_SOURCES, TRACER_SOURCES)]


def runtime_progress() -> tuple[int, int]:
    """(the runtime's objects in the build cache, the runtime's sources): all there once it has been compiled,
    which happens once per cache (the viewer says so while it lasts)."""
    return clib.objects_present(_runtime_jobs(), LIBRARY_FLAGS)


def build_library(entries: Sequence[ShapeEntry], extra_flags: Sequence[str] = ()) -> tuple[Path, int]:
    """The tracer library holding these shapes: (its path, how many shapes were generated on this call).
    extra_flags: more compiler flags for every object (bench/floor.py's instrumented build: -DRT_TRACE)."""
    dirs, generated = [], 0
    for e in entries:
        d, fresh = generated_dir(e.spec)
        dirs.append(d)
        generated += fresh
    glue = _glue(entries)
    rt = runtime_dir()
    # Each runtime source sees only the runtime's headers, so its object is shared by every library; each shape
    # sees its own folder too, and only the glue sees all of them.
    jobs = _runtime_jobs()
    jobs += [(d / f"{e.c_name}.c", [rt, d]) for d, e in zip(dirs, entries)]
    jobs.append((glue, [rt, *dirs]))
    flags = [*LIBRARY_FLAGS, *extra_flags]
    return clib.build_jobs(jobs, extra_flags=flags, libs=["-lm", "-pthread"], tag="scene"), generated
