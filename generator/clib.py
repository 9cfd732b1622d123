"""Compile C sources into a shared library, cached by content hash, and load it with ctypes.

Used for the root-solver library behind `implgen.roots.solvers` and for each scene's tracer. The cache key covers
the source texts, the flags and the compiler's version, so an unchanged input compiles nothing the second
time and any change rebuilds. The cache folder is `$IMPLGEN_CACHE`, else `$XDG_CACHE_HOME/implgen`, else
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
from collections.abc import Sequence
from functools import cache
from pathlib import Path

from implgen.errors import UserError

BASE_FLAGS: tuple[str, ...] = ("-std=c99", "-O3", "-fPIC", "-Wall", "-Wextra", "-Werror", "-pedantic")


def cache_dir() -> Path:
    """The build cache folder (created on demand)."""
    env = os.environ.get("IMPLGEN_CACHE")
    if env:
        root = Path(env)
    else:
        xdg = os.environ.get("XDG_CACHE_HOME")
        root = (Path(xdg) if xdg else Path.home() / ".cache") / "implgen"
    root.mkdir(parents=True, exist_ok=True)
    return root


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


def build_shared(
    sources: Sequence[Path],
    include_dirs: Sequence[Path] = (),
    extra_flags: Sequence[str] = (),
    libs: Sequence[str] = ("-lm",),
    tag: str = "lib",
) -> Path:
    """Compile `sources` into one shared library and return its path (reused when already built).

    Every header in `include_dirs` is part of the cache key too. Raises RuntimeError with the compiler's
    output when compilation fails (a bug in implgen, not in user input).
    """
    cc = compiler()
    flags = [*BASE_FLAGS, *extra_flags]
    h = hashlib.sha256()
    h.update(_compiler_version(cc).encode())
    h.update("\0".join([*flags, *libs]).encode())
    for src in sources:
        h.update(b"\0src\0" + Path(src).read_bytes())
    for inc in include_dirs:
        for header in sorted(Path(inc).glob("*.h")):
            h.update(b"\0hdr\0" + header.name.encode() + b"\0" + header.read_bytes())
    target = cache_dir() / f"{tag}-{h.hexdigest()[:20]}.so"
    if target.exists():
        return target
    fd, tmp = tempfile.mkstemp(prefix=f".{tag}-", suffix=".so", dir=target.parent)
    os.close(fd)
    cmd = [cc, *flags, "-shared", "-o", tmp, *(str(s) for s in sources)]
    cmd += [f"-I{inc}" for inc in include_dirs]
    cmd += list(libs)
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        os.unlink(tmp)
        raise RuntimeError(f"C compilation failed: {' '.join(cmd)}\n{proc.stderr}")
    os.replace(tmp, target)
    return target


def load(path: Path) -> ctypes.CDLL:
    """Load a shared library built by `build_shared`."""
    return ctypes.CDLL(str(path))
