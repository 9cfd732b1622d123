"""What the build cache holds, and keeping it within its size bound: the inventory, least-recently-used
eviction, and `implgen cache clear`'s removal.

The inventory knows the cache's layout (cachedir's notes) by name patterns and nothing else: a file that does
not match is never counted or removed, so a cache folder pointed at by mistake at a folder of the user's own
loses nothing but implgen's entries, and a symbolic link (in place of a subfolder or an entry) is removed
itself, never followed.

The bound is `$IMPLGEN_CACHE_MAX_MB` (cachedir.max_bytes, default 500 MB). clib calls evict() after it links
a new library -- the moment the cache grows by more than a spec entry -- and each use of an entry touches
its mtime (cachedir.touch), so "least recently used" does not depend on the file system keeping access
times. Never evicted: the libraries this process holds loaded (clib keeps a weak map of live handles), what
another process used in the last GRACE_SECONDS (it may be linking those objects now; this process's own
entries may go, oldest first, since its library is linked), and `roots_reference/` (the tests' exact
reference roots: minutes to compute, written by measure/cases/reference.py without touching them on use, so their
mtime says nothing of their use). Leftovers of an earlier layout and of interrupted writes go first.

Temporaries (cachedir.temp_path: `.tmp-<pid>-...`, renamed into place when whole) are counted too: "writing"
while the process whose id the name holds runs, never removed (it will rename or remove it itself); a
"leftover" once that process has gone (killed mid-compile: a stopped mesh's), removed at every
evict() whatever the bound, and by `implgen cache clear`. Only the name's own process decides, so a concurrent
build's temporaries are safe; a name without an id (an earlier version's) is a leftover after GRACE_SECONDS,
and any temporary after STALE_SECONDS (its id may have been taken by another process since).
"""

from __future__ import annotations

import os
import re
import stat
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from implgen import cachedir

GRACE_SECONDS = 60.0
STALE_SECONDS = 3600.0  # no build writes one file for an hour

# kind -> (subfolder, what a name must look like). Folders of `gen` are units; the rest are files.
KINDS: dict[str, tuple[str, re.Pattern[str]]] = {
    "lib": ("lib", re.compile(r"[a-z0-9_-]+-[0-9a-f]{32}\.so\Z")),
    "obj": ("obj", re.compile(r"[A-Za-z0-9_.-]+-[0-9a-f]{32}\.o\Z")),
    "glue": ("glue", re.compile(r"glue-[0-9a-f]{32}\.c\Z")),
    "gen": ("gen", re.compile(r"[0-9a-f]{24}\Z")),
    "spec": ("spec", re.compile(r"[0-9a-f]{40}\.json\Z")),
    "roots_reference": ("roots_reference", re.compile(r"[0-9a-f]{24}\.(json|pkl)\Z")),
}
NOT_EVICTED = ("roots_reference", "writing")
# What earlier versions of implgen left (libraries at the top, 20-hex names, no seals): never loaded again,
# removed by `implgen cache clear` and first by eviction.
_OLD = {
    "": re.compile(r"[a-z0-9_-]+-[0-9a-f]{20}\.so\Z"),
    "obj": re.compile(r"[A-Za-z0-9_.-]+-[0-9a-f]{20}\.o\Z"),
    "glue": re.compile(r"glue-[0-9a-f]{20}\.c\Z"),
}


@dataclass
class Unit:
    """One removable thing in the cache: an entry with its sidecar, a gen folder, a leftover."""

    kind: str
    path: Path
    size: int
    mtime: float


def _lstat(path: Path) -> os.stat_result | None:
    try:
        return os.lstat(path)
    except OSError:
        return None


def _folder_size(path: Path) -> int:
    total = 0
    try:
        with os.scandir(path) as it:
            for e in it:
                st = e.stat(follow_symlinks=False)
                total += _folder_size(Path(e.path)) if stat.S_ISDIR(st.st_mode) else st.st_size
    except OSError:
        pass
    return total


def _temporary_kind(name: str, age: float) -> str:
    """A temporary is "writing" while the process that named it runs (the id in its name: cachedir.temp_path),
    else a "leftover"; a name without a process id (an earlier version's) is a leftover after GRACE_SECONDS, and
    any after STALE_SECONDS (its id taken by another process since)."""
    pid = cachedir.writer(name)
    if age > STALE_SECONDS:
        return "leftover"
    if pid is None:
        return "leftover" if age > GRACE_SECONDS else "writing"
    return "writing" if cachedir.running(pid) else "leftover"


def _units_in(root: Path, sub: str, kind: str, pattern: re.Pattern[str]) -> Iterable[Unit]:
    folder = root / sub if sub else root
    st = _lstat(folder)
    if st is None or not stat.S_ISDIR(st.st_mode):  # a link in place of a subfolder is never followed
        return
    now = time.time()
    try:
        with os.scandir(folder) as it:
            names = sorted(e.name for e in it)
    except OSError:
        return
    for name in names:
        path = folder / name
        st = _lstat(path)
        if st is None:
            continue
        if name.startswith((cachedir.TMP_PREFIX, ".gen-", ".ig-")) and sub:
            if kind == "old":  # the folder's own kind lists it (obj/ and glue/ are looked at twice)
                continue
            size = _folder_size(path) if stat.S_ISDIR(st.st_mode) else st.st_size
            yield Unit(_temporary_kind(name, now - st.st_mtime), path, size, st.st_mtime)
            continue
        if name.endswith(cachedir.SEAL) and pattern.match(name.removesuffix(cachedir.SEAL)):
            if _lstat(path.with_name(name.removesuffix(cachedir.SEAL))) is None:  # the seal of nothing
                yield Unit("leftover", path, st.st_size, st.st_mtime)
            continue
        if not pattern.match(name):
            continue
        if stat.S_ISDIR(st.st_mode):
            size = _folder_size(path)
        else:
            side = _lstat(path.with_name(name + cachedir.SEAL))
            size = st.st_size + (side.st_size if side is not None else 0)
        yield Unit(kind, path, size, st.st_mtime)


def inventory(root: Path | None = None) -> list[Unit]:
    """Everything the cache holds that implgen may remove, by the layout's patterns (nothing else)."""
    root = cachedir.cache_root() if root is None else root
    units = []
    for kind, (sub, pattern) in KINDS.items():
        units += _units_in(root, sub, kind, pattern)
    for sub, pattern in _OLD.items():
        units += _units_in(root, sub, "old", pattern)
    return units


def evict(keep: Iterable[Path] = (), bound: int | None = None) -> list[Unit]:
    """Remove least-recently-used entries until the cache is within `bound` bytes (default: cachedir.max_bytes()).

    Never removed: `keep` (the libraries this process holds loaded), `roots_reference/`, and what another
    process used in the last GRACE_SECONDS (it may be linking those objects now; what this process used itself
    may go, oldest first, since its library is linked). Leftovers of earlier versions go first. Returns what
    was removed."""
    bound = cachedir.max_bytes() if bound is None else bound
    units = inventory()
    removed = _remove([u for u in units if u.kind == "leftover"])  # their writers have gone: at every use
    units = [u for u in units if u.kind != "leftover"]
    total = sum(u.size for u in units)
    if total <= bound:
        return removed
    kept = {Path(p) for p in keep}
    now = time.time()

    def removable(u: Unit) -> bool:
        if u.kind in NOT_EVICTED or u.path in kept:
            return False
        return u.path in cachedir.used_here or now - u.mtime > GRACE_SECONDS

    for u in sorted(filter(removable, units), key=lambda u: (u.kind != "old", u.mtime)):
        if total <= bound:
            break
        removed += _remove([u])
        total -= u.size
    return removed


def _remove(units: list[Unit]) -> list[Unit]:
    for u in units:
        cachedir.remove_entry(u.path)
        cachedir.used_here.discard(u.path)
    return units


def clear(root: Path) -> tuple[list[Unit], list[Unit]]:
    """Remove every unit of the inventory (the layout's patterns only; links are removed, not followed), then
    the subfolders if they are left empty. Returns (what was removed, what could not be: a read-only cache)."""
    removed, failed = [], []
    for u in inventory(root):
        if u.kind == "writing":  # a build running now renames it into place: left to it
            continue
        cachedir.remove_entry(u.path)
        cachedir.used_here.discard(u.path)
        (failed if os.path.lexists(u.path) else removed).append(u)
    for sub, _ in KINDS.values():
        path = root / sub
        st = _lstat(path)
        if st is not None and stat.S_ISLNK(st.st_mode):
            cachedir.unlink_quietly(path)  # a link in place of a subfolder: the link goes, its target stays
        else:
            try:
                os.rmdir(path)
            except OSError:
                pass  # not empty (files implgen does not know) or absent
    return removed, failed
