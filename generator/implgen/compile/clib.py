"""Compile C sources into a shared library, cached by content hash, and load it with ctypes.

Used for the root-solver library behind `implgen.roots.solvers` and for each scene's tracer. Each source is
compiled to its own cached object file (`obj/`) and the objects are linked (`lib/`), so a scene that differs
from a cached one only in its shapes compiles just those shapes and the glue, and links (the runtime's objects
are reused): a new equation costs tens of milliseconds of C compilation instead of seconds.

An object's key hashes the compiler (its path and `--version`), the flags, the source text and every header
its include folders hold; a library's key hashes the compiler, the link command and its objects' keys. The
key is in the entry's name and in its seal (cachedir: the sidecar with the entry's SHA-256), and an entry is
used only when its seal verifies -- when a library is planned, and again right before `dlopen` -- so an
unchanged input compiles nothing the second time, any change rebuilds, and a truncated, empty or replaced
entry is built again instead of loaded. A cached library is found before its objects are looked at, so a
cached scene hashes one library, not every object.

A compiler that fails, or that exits 0 without writing anything (`CC=true`), is a UserError naming `CC`: one
line with the compiler, the file and the compiler's first error line.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import shutil
import subprocess
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from implgen import cachedir
from implgen.errors import UserError, out_of_files, out_of_files_error

# The project's C standard and warnings, stated once: every build here, the tests' C drivers (tests/conftest.py)
# and what `implgen demo` says it compiled with.
WARNING_FLAGS: tuple[str, ...] = ("-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic")
BASE_FLAGS: tuple[str, ...] = (*WARNING_FLAGS, "-O3", "-fPIC")
# AddressSanitizer and UndefinedBehaviorSanitizer, any report fatal: the tests' C drivers and the Embree checks
SANITIZE_FLAGS: tuple[str, ...] = (
    "-O1",
    "-g",
    "-fsanitize=address,undefined",
    "-fno-sanitize-recover=all",
    "-fno-omit-frame-pointer",
)
KEY_FORMAT = "clib-2"  # part of every key: entries of an earlier layout are never taken for these

# The libraries this process holds loaded (a live ctypes handle): eviction leaves them alone. Weak, so a library
# the process has let go of (the viewer's previous equation) may be evicted like any other; its mapping, if the
# dynamic loader keeps one, does not need the file.
_in_use: weakref.WeakValueDictionary[Path, ctypes.CDLL] = weakref.WeakValueDictionary()


# What needs a compiler (rendering, meshes, the C solvers behind generated Python) says which package brings one;
# generating code and share pages need none (docs/dependencies.md#a-c-compiler-at-run-time)
NO_COMPILER_HINT = "rendering and meshing need one: install gcc (Debian, Ubuntu: apt-get install gcc) or set CC"


def compiler() -> str:
    """The C compiler: `$CC`, else `cc`."""
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        raise UserError("CC", f"no C compiler found (tried {cc!r}); {NO_COMPILER_HINT}")
    return cc


@cache
def _compiler_identity(cc: str) -> str:
    """What names the compiler in a key: where it is and what it says its version is."""
    try:
        out = subprocess.run([cc, "--version"], capture_output=True, text=True, check=False, timeout=60)
        version = out.stdout.strip()
    except (OSError, subprocess.SubprocessError) as err:
        raise UserError("CC", f"cannot run the C compiler {cc!r}: {err}") from None
    return f"{shutil.which(cc)}\0{version}"


def _digest(cc: str, parts: Sequence[str]):  # -> a hashlib sha256 object
    h = hashlib.sha256()
    h.update(f"{KEY_FORMAT}\0{_compiler_identity(cc)}\0".encode())
    h.update("\0".join(parts).encode())
    return h


def _headers_into(h, include_dirs: Sequence[Path], read: dict[Path, bytes]) -> None:
    """Every header in `include_dirs` into the key: each one's name and text, in name order. `read` holds what
    this build has read already, one entry per folder: the runtime's headers are in every object's key, and a
    cached start reads them once, not once per source."""
    for inc in map(Path, include_dirs):
        if inc not in read:
            read[inc] = b"".join(
                b"\0hdr\0" + hd.name.encode() + b"\0" + hd.read_bytes() for hd in sorted(inc.glob("*.h"))
            )
        h.update(read[inc])


@dataclass(frozen=True)
class Job:
    """One cache entry to make: where it goes, its key, what it is made from (for messages) and the command
    that writes it to a given output name."""

    target: Path
    key: str
    what: str
    command: Callable[[str], list[str]]


def _first_error(stderr: str) -> str:
    lines = [ln.strip() for ln in stderr.splitlines() if ln.strip()]
    for ln in lines:
        if "error" in ln.lower():
            return ln[:300]
    return lines[0][:300] if lines else "no message"


def _run(job: Job) -> Path:
    """Build `job.target` unless its sealed entry verifies: the compiler writes a temporary name in the same
    folder, which is sealed (checked non-empty, hashed, renamed, sidecar written)."""
    if cachedir.check_entry(job.target, job.key):
        return job.target
    tmp = cachedir.temp_path(job.target.parent, job.target.suffix)
    cmd = job.command(str(tmp))
    try:
        proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    except OSError as err:
        if out_of_files(err):
            raise out_of_files_error("CC", err) from None
        raise UserError("CC", f"cannot run the C compiler {cmd[0]!r} on {job.what}: {err.strerror or err}") from None
    if proc.returncode != 0:
        cachedir.unlink_quietly(tmp)
        raise UserError(
            "CC", f"{cmd[0]} failed on {job.what} (exit status {proc.returncode}): {_first_error(proc.stderr)}"
        )
    try:
        cachedir.seal(tmp, job.target, job.key)
    except cachedir.EmptyOutput:
        raise UserError(
            "CC", f"{cmd[0]} exited 0 on {job.what} but wrote nothing; is CC a C compiler? nothing was cached"
        ) from None
    except OSError as err:
        cachedir.unlink_quietly(tmp)
        raise UserError(cachedir.label(), f"cannot write {job.target.name}: {err.strerror or err}") from None
    return job.target


def _writable(folder: Path) -> None:
    """A build needs to write in the cache: a read-only one (shared with workers) is one line, not a traceback."""
    if not os.access(folder, os.W_OK | os.X_OK):
        raise UserError(
            cachedir.label(),
            f"{folder} is read-only and lacks an entry this build needs; build it where the cache is writable, "
            f"or point {cachedir.ENV} at a folder of your own",
        )


def _object_job(
    source: Path,
    include_dirs: Sequence[Path],
    extra_flags: Sequence[str],
    cc: str,
    folder: Path,
    read: dict[Path, bytes],
) -> Job:
    """The cached object for one source, in `folder` (obj/): its key hashes the source text, every header in
    `include_dirs` (`read`: _headers_into), the flags and the compiler."""
    flags = [*BASE_FLAGS, *extra_flags]
    h = _digest(cc, flags)
    h.update(b"\0src\0" + Path(source).read_bytes())
    _headers_into(h, include_dirs, read)
    key = h.hexdigest()
    target = folder / f"{Path(source).stem}-{key[:32]}.o"
    includes = [f"-I{inc}" for inc in include_dirs]
    return Job(target, key, Path(source).name, lambda tmp: [cc, *flags, "-c", str(source), "-o", tmp, *includes])


def objects_present(jobs: Sequence[tuple[Path, Sequence[Path]]], extra_flags: Sequence[str] = ()) -> tuple[int, int]:
    """(how many of these sources' objects the build cache holds, how many sources): a build's progress, as a
    page can show it while the runtime is compiled for the first time. Looks at the files only (a build in
    progress renames each sealed object into place)."""
    cc, folder, read = compiler(), cachedir.cache_dir("obj"), {}
    objects = [_object_job(src, inc, [*extra_flags], cc, folder, read) for src, inc in jobs]
    return sum(job.target.is_file() for job in objects), len(objects)


def _build_all(jobs: Sequence[Job]) -> None:
    missing = [job for job in jobs if not cachedir.check_entry(job.target, job.key)]
    if missing:
        _writable(missing[0].target.parent)
    if len(missing) == 1:
        _run(missing[0])
    elif missing:
        from concurrent.futures import ThreadPoolExecutor  # only when there is more than one to compile

        with ThreadPoolExecutor(max_workers=min(len(missing), os.cpu_count() or 1)) as pool:
            list(pool.map(_run, missing))


def _library_job(objects: Sequence[Job], libs: Sequence[str], tag: str) -> Job:
    cc = compiler()
    h = _digest(cc, ["-shared", *BASE_FLAGS, *libs])
    for obj in objects:
        h.update(b"\0obj\0" + obj.key.encode())
    key = h.hexdigest()
    target = cachedir.cache_dir("lib") / f"{tag}-{key[:32]}.so"
    paths = [str(o.target) for o in objects]
    return Job(target, key, target.name, lambda tmp: [cc, "-shared", "-o", tmp, *paths, *libs])


def build_jobs(
    jobs: Sequence[tuple[Path, Sequence[Path]]],
    extra_flags: Sequence[str] = (),
    libs: Sequence[str] = ("-lm",),
    tag: str = "lib",
) -> Path:
    """One shared library from C sources, each with the include folders it sees. A library whose seal
    verifies is returned at once (its objects are not looked at); otherwise the missing objects are compiled,
    the library linked and sealed, and the cache brought back within its bound (cachesize.evict)."""
    cc, folder, read = compiler(), cachedir.cache_dir("obj"), {}  # once per library: each is a few system calls
    objects = [_object_job(src, inc, extra_flags, cc, folder, read) for src, inc in jobs]
    lib = _library_job(objects, libs, tag)
    if cachedir.check_entry(lib.target, lib.key):
        return lib.target
    _build_all(objects)
    _writable(lib.target.parent)
    _run(lib)
    from implgen.compile import cachesize  # only after a link: a cached start needs none of the eviction

    cachesize.evict(keep={*_in_use.keys(), lib.target})
    return lib.target


def build_shared(
    sources: Sequence[Path],
    include_dirs: Sequence[Path] = (),
    extra_flags: Sequence[str] = (),
    libs: Sequence[str] = ("-lm",),
    tag: str = "lib",
) -> Path:
    """Compile `sources` (each seeing every header in `include_dirs`) into one shared library and return its
    path (reused when already built): build_jobs."""
    return build_jobs([(Path(s), include_dirs) for s in sources], extra_flags, libs, tag)


def _descriptors_left() -> None:
    """Raise the line for running out of file descriptors if no file can be opened now."""
    try:
        os.close(os.open(os.devnull, os.O_RDONLY))
    except OSError as err:
        if out_of_files(err):
            raise out_of_files_error(cachedir.label(), err) from None


def load(path: Path) -> ctypes.CDLL:
    """Load a library built by build_shared, after checking it once more: a regular file of ours that nobody
    else can write, in a folder of ours, whose bytes hash to its seal, and whose seal is the key its name was
    built for. Anything else is refused (one line), never loaded.

    Between this check and dlopen only this user (or root) could change the file, since the folder and the
    file are ours and nobody else may write them; dlopen is given the path (a /proc/self/fd path would
    be remembered by the dynamic loader under a name that the next library's fd could reuse)."""
    path = Path(path)
    for folder in (path.parent, path.parent.parent):  # lib/ and the cache root: nobody else may write them
        problem = cachedir.folder_problem(folder)
        if problem:
            raise UserError(cachedir.label(), f"{folder} {problem}; {path.name} is not loaded from it")
    key = cachedir.seal_key(path)
    if key is None or not path.stem.endswith("-" + key[:32]) or not cachedir.check_entry(path, key):
        raise UserError(
            cachedir.label(),
            f"{path.name} changed since it was built (its seal does not match); not loaded; run again to rebuild it",
        )
    try:
        lib = ctypes.CDLL(str(path))
    except OSError as err:
        _descriptors_left()  # dlopen's error has no errno: a sound library that could not be opened is kept
        cachedir.remove_entry(path)
        raise UserError("CC", f"the library {path.name} built by {compiler()} does not load: {err}") from None
    _in_use[path] = lib
    return lib
