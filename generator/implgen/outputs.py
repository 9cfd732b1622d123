"""Where results go: output paths checked before any work, files written atomically with the usual mode.

A file is written under a temporary name in its own folder and renamed into place, so a failure or a crash
leaves nothing half-written. It is created with mode 0666 less the umask, like any file a program makes
(`tempfile.mkstemp` would make it 0600).
"""

from __future__ import annotations

import os
import secrets
import stat
from collections.abc import Callable, Mapping
from pathlib import Path

from implgen.errors import UserError


def _folder_of(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")


def _kind(path: Path) -> str | None:
    """'a folder', 'a fifo', ... for an existing non-regular path; None for a regular file or nothing."""
    try:
        mode = path.stat().st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder"
    return "a fifo" if stat.S_ISFIFO(mode) else "a device or socket"


def _temp_name() -> str:
    return f".ig-{secrets.token_hex(6)}.tmp"  # short: a name the user may use takes at most NAME_MAX - 20


def _name_max(folder: Path) -> int:
    try:
        return os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        return 255


def _check_names(option: str, folder: Path, names: list[str]) -> None:
    """Names still to be created under the existing `folder` must fit the file system."""
    limit = _name_max(folder)
    for name in names:
        if len(os.fsencode(name)) > limit:
            raise UserError(option, f"the name {name[:40]}... is longer than {limit} bytes")
    full = os.fsencode(os.path.abspath(os.path.join(folder, *names)))
    if len(full) >= 4096:
        raise UserError(option, "the path is longer than 4095 bytes")


def _check_not_dangling(option: str, path: Path) -> None:
    """A name that does not exist but is a link: to a missing target, or in a loop. mkdir would fail there."""
    if os.path.lexists(path) and not path.exists():
        raise UserError(option, f"{path} is a link to nothing (a missing target or a loop of links)")


def _check_writable_folder(option: str, folder: Path) -> None:
    """`folder` exists and a file can be created in it: tried for real (create and remove an empty file),
    since permission bits do not tell (root, read-only mounts, /proc)."""
    if not folder.exists():
        _check_not_dangling(option, folder)
        raise UserError(option, f"the folder {folder} does not exist")
    if not folder.is_dir():
        raise UserError(option, f"{folder} is not a folder")
    probe = folder / _temp_name()
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
    except OSError as err:
        raise UserError(option, f"cannot write in {folder} ({err.strerror or err})") from None
    probe.unlink()


def _stat_errors(check: Callable[..., None]) -> Callable[..., None]:
    """An OSError while looking at the path (a name too long, a loop of links) is the path's problem."""

    def checked(path: Path, option: str, *args: object) -> None:
        try:
            check(Path(path), option, *args)
        except OSError as err:
            raise UserError(f"{option} {path}", f"cannot use this path ({err.strerror or err})") from None

    return checked


@_stat_errors
def check_output_file(path: Path, option: str, suffixes: tuple[str, ...]) -> None:
    """An output file the command will create or replace: right suffix, not a folder or a fifo, a name the
    file system takes, in a folder where a file can be created. `option` names it in messages as the user
    typed it (e.g. `-o`)."""
    label = f"{option} {path}"
    kind = _kind(path)
    if kind:
        raise UserError(label, f"is {kind}, not a file to write")
    if path.suffix.lower() not in suffixes:
        raise UserError(label, f"the output must end in {' or '.join(suffixes)}")
    folder = _folder_of(path)
    _check_writable_folder(label, folder)
    _check_names(label, folder, [path.name])


@_stat_errors
def check_output_folder(path: Path, option: str) -> None:
    """An output folder the command will create if needed: not an existing file, under a folder where a
    file can be created, every missing name one the file system takes."""
    label = f"{option} {path}"
    if path.exists():
        if not path.is_dir():
            raise UserError(label, "exists and is not a folder")
        _check_writable_folder(label, path)
        return
    _check_not_dangling(label, path)
    missing = [path.name]
    ancestor = path.parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        _check_not_dangling(label, ancestor)
        missing.insert(0, ancestor.name)
        ancestor = ancestor.parent
    ancestor = ancestor if str(ancestor) else Path(".")
    _check_writable_folder(label, ancestor)
    _check_names(label, ancestor, [name for name in missing if name not in ("", ".")])


def staged(folder: Path, write: Callable[[object], None]) -> Path:
    """A new temporary file in `folder` (`.ig-*.tmp`, never taken for an output) written through
    `write(binary_file)`; the caller renames it into place. A failure removes it."""
    tmp = Path(folder) / _temp_name()
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)  # the umask applies, as for any file
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return tmp


def atomic_write(path: Path, write: Callable[[object], None]) -> None:
    """Create `path` through `write(binary_file)`: a temporary file in the same folder, renamed into place."""
    path = Path(path)
    tmp = staged(_folder_of(path), write)
    try:
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_text_files(files: Mapping[str, str], outdir: Path, option: str = "-o") -> list[Path]:
    """Write {file name: text} into `outdir` (created if missing), each file atomically. A failure the checks
    could not foresee (a full disk, a folder removed meanwhile) is one line naming `option`."""
    written = []
    try:
        outdir.mkdir(parents=True, exist_ok=True)
        for fname, text in files.items():
            data = text.encode("utf-8")
            atomic_write(outdir / fname, lambda fh, data=data: fh.write(data))
            written.append(outdir / fname)
    except OSError as err:
        raise UserError(f"{option} {outdir}", f"cannot write {err.filename or outdir}: {err.strerror or err}") from None
    return written
