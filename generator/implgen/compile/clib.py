"""Compile C sources into a shared library, cached by content hash, and load it with ctypes.

Used for the root-solver library behind `implgen.roots.solvers` and for each scene's tracer. The cache key covers
the source texts, the headers, the flags and the compiler's version, so an unchanged input compiles nothing
the second time and any change rebuilds. Each source is compiled to its own cached object file and the
objects are linked, so a scene that differs from a cached one only in its shapes compiles just those shapes
and the glue, and links (the runtime's objects are reused): a new equation costs tens of milliseconds of C
compilation instead of seconds. The cache folder is `$IMPLGEN_CACHE`, else `$XDG_CACHE_HOME/implgen`, else
`~/.cache/implgen`. Builds go to a temporary name and are renamed into place, so parallel processes never
see a half-written library.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path

from implgen.cachedir import cache_dir
from implgen.errors import UserError

# The project's C standard and warnings, stated once: every build here, the tests' C drivers (tests/conftest.py)
# and what `implgen demo` says it compiled with.
WARNING_FLAGS: tuple[str, ...] = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic")
BASE_FLAGS: tuple[str, ...] = (*WARNING_FLAGS, "-O3", "-fPIC")


def compiler() -> str:
    """The C compiler: `$CC`, else `cc`."""
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        raise UserError("CC", f"no C compiler found (tried {cc!r}); install gcc or set CC")
    return cc


@cache
def _compiler_version(cc: str) -> str:
    out = subprocess.run([cc, "--version"], capture_output=True, text=True, check=False)
    return out.stdout.strip()


def _digest(cc: str, parts: Sequence[str]):  # -> a hashlib sha256 object
    h = hashlib.sha256()
    h.update(_compiler_version(cc).encode())
    h.update("\0".join(parts).encode())
    return h


def _headers_into(h, include_dirs: Sequence[Path]) -> None:
    for inc in include_dirs:
        for header in sorted(Path(inc).glob("*.h")):
            h.update(b"\0hdr\0" + header.name.encode() + b"\0" + header.read_bytes())


def _run_compiler(cmd: list[str], tmp: str) -> None:
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise RuntimeError(f"C compilation failed: {' '.join(cmd)}\n{proc.stderr}")


def _build_into(target: Path, suffix: str, cmd_for: Callable[[str], list[str]]) -> Path:
    """Run the command built for a temporary output name, then rename it to `target` (atomic)."""
    if target.exists():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.stem}-", suffix=suffix, dir=target.parent)
    os.close(fd)
    _run_compiler(cmd_for(tmp), tmp)
    os.replace(tmp, target)
    return target


def _object_job(
    source: Path, include_dirs: Sequence[Path], extra_flags: Sequence[str]
) -> tuple[Path, Callable[[str], list[str]]]:
    """The cached object's path for one source (its key: the source text, every header in `include_dirs`, the
    flags and the compiler's version) and the command that compiles it to a given output name."""
    cc = compiler()
    flags = [*BASE_FLAGS, *extra_flags]
    h = _digest(cc, flags)
    h.update(b"\0src\0" + Path(source).read_bytes())
    _headers_into(h, include_dirs)
    target = cache_dir() / "obj" / f"{Path(source).stem}-{h.hexdigest()[:20]}.o"
    includes = [f"-I{inc}" for inc in include_dirs]
    return target, lambda tmp: [cc, *flags, "-c", str(source), "-o", tmp, *includes]


def compile_object(source: Path, include_dirs: Sequence[Path] = (), extra_flags: Sequence[str] = ()) -> Path:
    """Compile one C source into an object file, cached under `obj/` by the source text, every header in
    `include_dirs`, the flags and the compiler's version. Returns its path."""
    target, cmd_for = _object_job(source, include_dirs, extra_flags)
    return _build_into(target, ".o", cmd_for)


def compile_objects(jobs: Sequence[tuple[Path, Sequence[Path]]], extra_flags: Sequence[str] = ()) -> list[Path]:
    """compile_object for each (source, include_dirs), the missing ones in parallel (one per core)."""
    planned = [_object_job(src, inc, extra_flags) for src, inc in jobs]
    missing = [job for job in planned if not job[0].exists()]
    if len(missing) == 1:
        _build_into(missing[0][0], ".o", missing[0][1])
    elif missing:
        from concurrent.futures import ThreadPoolExecutor  # only when there is more than one to compile

        with ThreadPoolExecutor(max_workers=min(len(missing), os.cpu_count() or 1)) as pool:
            list(pool.map(lambda job: _build_into(job[0], ".o", job[1]), missing))
    return [target for target, _ in planned]


def link_shared(objects: Sequence[Path], libs: Sequence[str] = ("-lm",), tag: str = "lib") -> Path:
    """Link object files built by compile_object into a shared library, cached by the objects' names (which
    carry their content hashes) and the libraries."""
    cc = compiler()
    h = _digest(cc, [*BASE_FLAGS, *libs])
    for obj in objects:
        h.update(b"\0obj\0" + Path(obj).name.encode())
    target = cache_dir() / f"{tag}-{h.hexdigest()[:20]}.so"
    return _build_into(target, ".so", lambda tmp: [cc, "-shared", "-o", tmp, *(str(o) for o in objects), *libs])


def build_shared(
    sources: Sequence[Path],
    include_dirs: Sequence[Path] = (),
    extra_flags: Sequence[str] = (),
    libs: Sequence[str] = ("-lm",),
    tag: str = "lib",
) -> Path:
    """Compile `sources` into one shared library and return its path (reused when already built).

    Each source becomes a cached object (compile_object, every header in `include_dirs` part of its key),
    then the objects are linked (link_shared). Raises RuntimeError with the compiler's output when
    compilation fails (a bug in implgen, not in user input).
    """
    objects = compile_objects([(Path(s), include_dirs) for s in sources], extra_flags)
    return link_shared(objects, libs, tag)


def load(path: Path) -> ctypes.CDLL:
    """Load a shared library built by `build_shared`."""
    return ctypes.CDLL(str(path))
