"""The build cache folder: where it is, whether it may be trusted, its sealed entries, and its size bound.

Where: `$IMPLGEN_CACHE`, else `$XDG_CACHE_HOME/implgen`, else `~/.cache/implgen`. On the ground floor because
two rooms keep entries there: the spec cache (spec/cache.py: parsed specs) and the compile room
(compile/: generated C, objects, libraries).

The cache holds shared libraries that implgen loads into its own process, so it is code, and the rule is:
nothing is loaded as code unless this user owns it, nobody else can write it, and it is the entry that was
built for this source. Hence:

- **The folder.** The root and each subfolder are created 0700 and checked on every use (`os.lstat`, so a
  symbolic link in place of a folder is refused, not followed): a folder that is not ours, or that group or
  others may write, is refused with one line naming `IMPLGEN_CACHE` (or the path) and the fix. Whoever can
  write a folder can replace what is in it, and a replaced library runs its constructor in our process.
- **Sealed entries.** What is built is written under a temporary name in the same folder, flushed, renamed
  into place, then sealed by a sidecar `<entry>.sha256` (written the same way, after the entry) that holds the
  entry's key (the hash of what it was built from: source text, headers, compiler and command), its size and
  the SHA-256 of its bytes. An entry is used only when both files are regular, ours, not writable by group
  or others, the sidecar names the key we expect, and the bytes hash to the recorded value; anything else
  (truncated, empty, replaced, missing sidecar) is a miss, and the caller builds it again over it. The key
  also sits in the entry's name, so a name is predictable but never trusted for its own sake. A file that
  cannot be opened because the process is out of descriptors is not a miss: that is said as it is
  (errors.out_of_files_error), never as a broken seal or a compiler that wrote nothing.
- **The bound.** `$IMPLGEN_CACHE_MAX_MB` (default 500, checked here with the folder): each use of an entry
  touches its mtime, and after a new library is linked the least recently used entries are removed until
  the cache fits (compile/cachesize.py, which also lists the cache for `implgen cache info|clear`).

Layout (the only names `implgen cache clear` and eviction touch; nothing outside these patterns is removed,
and no symbolic link is followed):

    spec/<40 hex>.json            a parsed spec (data; its key is inside it and it is validated on reading)
    gen/<24 hex>/<name>.{c,h}     generated C of one shape, each file sealed
    glue/glue-<32 hex>.c          the C list of a library's shapes, sealed
    obj/<stem>-<32 hex>.o         one object per C source, sealed
    lib/<tag>-<32 hex>.so         a linked library, sealed
    roots_reference/<24 hex>.json exact reference roots (measure/cases/reference.py: data, read back only as numbers)
"""

from __future__ import annotations

import hashlib
import math
import os
import re
import secrets
import shutil
import stat
from pathlib import Path

from implgen.errors import UserError, out_of_files, out_of_files_error

ENV = "IMPLGEN_CACHE"
MAX_ENV = "IMPLGEN_CACHE_MAX_MB"
DEFAULT_MAX_MB = 500.0
SEAL = ".sha256"
_SEAL_HEADER = "implgen-cache-entry 1"
_SEAL_MAX = 512  # bytes: a sidecar is one short line
TMP_PREFIX = ".tmp-"
_TEMP_NAME = re.compile(r"\.tmp-([0-9]{1,10})-[0-9a-f]{16}")  # temp_path's names: the writer's process id

used_here: set[Path] = set()  # entries this process built or used (compile/cachesize.py: eviction)


# ------------------------------------------------------------------------------------------- the folder


def cache_root() -> Path:
    """The cache folder's path (nothing created or checked)."""
    env = os.environ.get(ENV)
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "implgen"


def label(root: Path | None = None) -> str:
    """How messages name the cache: the variable that set it, else its path."""
    root = cache_root() if root is None else root
    return f"{ENV}={root}" if os.environ.get(ENV) else f"build cache {root}"


def _euid() -> int:
    return os.geteuid() if hasattr(os, "geteuid") else -1


def folder_problem(path: Path) -> str | None:
    """Why `path` cannot hold cache entries (missing, a link, not a folder, not ours, writable by others),
    or None when it may."""
    return _problem_and_fix(path, path)[0]


def _problem_and_fix(path: Path, root: Path) -> tuple[str | None, str]:
    try:
        st = os.lstat(path)
    except OSError as err:
        return f"cannot be used ({err.strerror or err})", f"point {ENV} at a folder of your own"
    elsewhere = f"point {ENV} at a folder of your own" if path == root else "remove it (implgen cache clear)"
    if stat.S_ISLNK(st.st_mode):
        return "is a symbolic link, not a folder (links are not followed)", (
            f"point {ENV} at the folder itself" if path == root else "remove it (implgen cache clear)"
        )
    if not stat.S_ISDIR(st.st_mode):
        return "is not a folder", elsewhere
    if _euid() >= 0 and st.st_uid != _euid():
        return f"is owned by user id {st.st_uid}, not by you (id {_euid()})", elsewhere
    if st.st_mode & 0o022:
        who = " and ".join(w for w, bit in (("group", 0o020), ("others", 0o002)) if st.st_mode & bit)
        return f"is writable by {who} (mode {stat.S_IMODE(st.st_mode):04o})", f"run chmod go-w {path}"
    return None, ""


def _checked_folder(path: Path, root: Path) -> None:
    """Create `path` 0700 if missing, then refuse it unless it is a folder of ours nobody else can write.

    Refused, not repaired: a folder someone else could write may already hold their files, so making it ours
    now would not make what is in it ours."""
    try:
        if path == root and not os.path.lexists(root):
            root.parent.mkdir(parents=True, exist_ok=True)
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:
            pass
    except OSError as err:
        raise UserError(label(root), f"cannot create {path}: {err.strerror or err}") from None
    problem, fix = _problem_and_fix(path, root)
    if problem is not None:
        raise UserError(label(root), f"{path} {problem}; it holds code implgen would load, so it is refused; {fix}")


def cache_dir(sub: str | None = None) -> Path:
    """The cache folder, or its subfolder `sub`, created 0700 on demand and checked (see the module's notes):
    the root and the subfolder must each be a real folder (not a link), owned by this user, not writable by
    group or others. Anything else is a UserError naming $IMPLGEN_CACHE (or the path) and the fix. Also checks
    $IMPLGEN_CACHE_MAX_MB, so a bad value is refused before any work."""
    max_bytes()
    root = cache_root()
    _checked_folder(root, root)
    if sub is None:
        return root
    path = root / sub
    _checked_folder(path, root)
    return path


def max_bytes() -> int:
    """The size bound in bytes, from $IMPLGEN_CACHE_MAX_MB (a positive number of megabytes, default 500)."""
    text = os.environ.get(MAX_ENV, "").strip()
    if not text:
        return int(DEFAULT_MAX_MB * 1e6)
    try:
        mb = float(text)
    except ValueError:
        mb = math.nan
    if not (math.isfinite(mb) and 0 < mb <= 1e9):
        raise UserError(MAX_ENV, f"{text[:40]!r} is not a size in megabytes: give a number above 0, e.g. 500")
    return int(mb * 1e6)


# ---------------------------------------------------------------------------------------- sealed entries


def _open_checked(path: Path) -> int | None:
    """An fd on `path` if it is a regular file (not a link), ours, not writable by group or others; else None.
    O_NONBLOCK: a fifo in place of an entry must not hang us."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | getattr(os, "O_NONBLOCK", 0))
    except OSError as err:
        if out_of_files(err):  # not a miss: the entry may be sound, and a rebuild would fail the same way
            raise out_of_files_error(label(), err) from None
        return None
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode) or (_euid() >= 0 and st.st_uid != _euid()) or st.st_mode & 0o022:
        os.close(fd)
        return None
    return fd


def _read_fd(fd: int, limit: int) -> bytes | None:
    chunks, total = [], 0
    while True:
        chunk = os.read(fd, 1 << 20)
        if not chunk:
            return b"".join(chunks)
        total += len(chunk)
        if total > limit:
            return None
        chunks.append(chunk)


def read_file(path: Path, limit: int) -> bytes | None:
    """The bytes of an unsealed cache file (a spec entry: data, validated by its reader) if it is a regular
    file of ours that nobody else can write and at most `limit` bytes; else None (a miss)."""
    fd = _open_checked(path)
    if fd is None:
        return None
    try:
        return _read_fd(fd, limit)
    except OSError:
        return None
    finally:
        os.close(fd)


def _seal_text(key: str, size: int, digest: str) -> bytes:
    return f"{_SEAL_HEADER} {key} {size} {digest}\n".encode()


def _seal_fields(path: Path) -> list[str] | None:
    seal = read_file(path.with_name(path.name + SEAL), _SEAL_MAX)
    if seal is None:
        return None
    fields = seal.decode("ascii", "replace").split()
    if len(fields) != 5 or " ".join(fields[:2]) != _SEAL_HEADER or not fields[3].isdigit():
        return None
    return fields


def seal_key(path: Path) -> str | None:
    """The key the seal of `path` records (not yet verified against the bytes), or None."""
    fields = _seal_fields(path)
    return None if fields is None else fields[2]


def read_entry(path: Path, key: str, limit: int = 1 << 30) -> bytes | None:
    """The bytes of the sealed entry `path` when it is the one built for `key`: the entry and its sidecar
    regular files of ours that nobody else can write, the sidecar naming `key`, the size and SHA-256 of the
    bytes those recorded, and the entry not empty. None otherwise (the caller rebuilds). A hit is touched."""
    fields = _seal_fields(path)
    if fields is None or fields[2] != key:
        return None
    size = int(fields[3])
    if size <= 0 or size > limit:
        return None
    data = read_file(path, size)
    if data is None or len(data) != size or hashlib.sha256(data).hexdigest() != fields[4]:
        return None
    touch(path)
    return data


def check_entry(path: Path, key: str) -> bool:
    """read_entry, for an entry whose bytes the caller does not need (an object, a library before dlopen)."""
    return read_entry(path, key) is not None


def touch(path: Path) -> None:
    """Mark an entry used now (its mtime: least-recently-used eviction). A read-only cache is left as it is."""
    used_here.add(Path(path))
    try:
        os.utime(path, follow_symlinks=False)
    except OSError:
        pass


def temp_path(folder: Path, suffix: str = "") -> Path:
    """A fresh name in `folder` for something being written, `.tmp-<pid>-<16 hex><suffix>`: ignored by readers; the
    process id says who writes it, so that a temporary is removed only once that process has gone (writer)."""
    return folder / f"{TMP_PREFIX}{os.getpid()}-{secrets.token_hex(8)}{suffix}"


def writer(name: str) -> int | None:
    """The id of the process that named a temporary (temp_path), or None for a name without one (an earlier
    version's)."""
    m = _TEMP_NAME.match(name)
    return int(m.group(1)) if m else None


def running(pid: int) -> bool:
    """Whether process `pid` exists (a zombie, ended but not reaped, still does)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's: it exists
        return True
    return True


def remove_temporaries(pid: int) -> int:
    """Remove what process `pid`, which has ended (and been reaped), left half-written in the cache's subfolders;
    returns how many. Only names that temp_path gave that process are touched."""
    prefix = f"{TMP_PREFIX}{pid}-"
    removed = 0
    try:
        subs = [e.path for e in os.scandir(cache_root()) if e.is_dir(follow_symlinks=False)]
    except OSError:
        return 0
    for sub in subs:
        try:
            names = [e.path for e in os.scandir(sub) if e.name.startswith(prefix) and writer(e.name) == pid]
        except OSError:
            continue
        for path in names:
            unlink_quietly(Path(path))
            removed += not os.path.lexists(path)
    return removed


def _write_new(path: Path, data: bytes) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    try:
        view = memoryview(data)
        while view:
            view = view[os.write(fd, view) :]
        os.fsync(fd)
    finally:
        os.close(fd)


def write_file(path: Path, data: bytes) -> None:
    """Write `path` atomically, mode 0600: a temporary name in the same folder, flushed, renamed into place."""
    tmp = temp_path(path.parent)
    try:
        _write_new(tmp, data)
        _replace(tmp, path)
    except BaseException:
        unlink_quietly(tmp)
        raise
    used_here.add(Path(path))


def _replace(tmp: Path, path: Path) -> None:
    """os.replace, after removing a folder that sits where the entry goes (a broken entry is rebuilt)."""
    if os.path.isdir(path) and not os.path.islink(path):
        shutil.rmtree(path, ignore_errors=True)
    os.replace(tmp, path)


class EmptyOutput(Exception):
    """What should have become an entry is empty or not a regular file (a compiler that wrote nothing)."""


def seal(tmp: Path, path: Path, key: str) -> None:
    """Make the file `tmp` (written by us or by a compiler, in the entry's folder) the entry `path` for `key`:
    mode 0600, flushed, hashed, renamed into place, then its sidecar written the same way. Raises EmptyOutput
    (and removes `tmp`) when there is nothing to seal."""
    try:
        fd = os.open(tmp, os.O_RDONLY | os.O_NOFOLLOW)
    except OSError as err:
        if out_of_files(err):  # the compiler's output may be there: not "wrote nothing"
            unlink_quietly(tmp)
            raise out_of_files_error(label(), err) from None
        raise EmptyOutput(str(tmp)) from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_size == 0:
            raise EmptyOutput(str(tmp))
        os.fchmod(fd, 0o600)  # a linker makes its output 0777 less the umask; an entry is for us alone
        data = _read_fd(fd, st.st_size)
        os.fsync(fd)
    except BaseException:
        os.close(fd)
        unlink_quietly(tmp)
        raise
    os.close(fd)
    if not data:  # None: it grew while being read
        unlink_quietly(tmp)
        raise EmptyOutput(str(tmp))
    _replace(tmp, path)
    write_file(path.with_name(path.name + SEAL), _seal_text(key, len(data), hashlib.sha256(data).hexdigest()))
    used_here.add(Path(path))


def write_entry(path: Path, data: bytes, key: str) -> None:
    """Write `data` as the sealed entry `path` for `key` (see seal)."""
    tmp = temp_path(path.parent)
    try:
        _write_new(tmp, data)
    except BaseException:
        unlink_quietly(tmp)
        raise
    seal(tmp, path, key)


def remove_entry(path: Path) -> None:
    """Remove an entry and its sidecar (a file, or a folder of files; a link itself, never what it points to)."""
    for p in (path.with_name(path.name + SEAL), path):
        if os.path.isdir(p) and not os.path.islink(p):
            shutil.rmtree(p, ignore_errors=True)
        else:
            unlink_quietly(p)


def unlink_quietly(path: Path) -> None:
    """Remove a file or a link (never what it points to); one already gone, or that cannot go, is left."""
    try:
        os.unlink(path)
    except OSError:
        pass
