"""The one exception type for bad user input: the CLI turns it into a one-line message and exit status 2; and
the line for running out of file descriptors, which is the machine's state, not a broken file or a bug."""

from __future__ import annotations

import errno
from pathlib import Path

OUT_OF_FILES = (errno.EMFILE, errno.ENFILE)  # this process's descriptors, or the system's, have run out


class UserError(Exception):
    """Bad input from a user file or the command line.

    `source` names the file (or option) at fault; `message` says what is wrong, in one line. `position`, when
    known, is the index of the character at fault in the text the message is about (an equation: the viewer puts
    a caret under it).
    """

    def __init__(self, source: str | Path | None, message: str, position: int | None = None) -> None:
        self.source = _one_line(str(source)) if source is not None else None
        self.message = _one_line(str(message))
        self.position = position
        super().__init__(str(self))

    def __str__(self) -> str:
        return f"{self.source}: {self.message}" if self.source else self.message


def _one_line(text: str) -> str:
    """White space folded to single spaces; anything unprintable (terminal escapes, NUL) shown as \\xNN."""
    return printable(" ".join(text.split()))


def printable(text: str) -> str:
    """`text` with anything unprintable (a newline, a terminal escape, NUL) shown as \\xNN or \\uNNNN, as error
    lines show it: what success lines print of a path the user gave (`-o`), so output stays one line each."""
    return "".join(
        ch if ch.isprintable() else f"\\x{ord(ch):02x}" if ord(ch) < 0x100 else f"\\u{ord(ch):04x}" for ch in text
    )


def out_of_files(err: BaseException) -> bool:
    """Whether `err` says no more files can be opened now (EMFILE, ENFILE)."""
    return isinstance(err, OSError) and err.errno in OUT_OF_FILES


def out_of_files_error(source: str | Path | None, err: OSError) -> UserError:
    """The line for an OSError that out_of_files() recognises: what ran out, and what to do."""
    if err.errno == errno.ENFILE:
        return UserError(source, "too many open files on this system (ENFILE): try again when fewer are open")
    try:
        import resource

        limit = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
        shown = "" if limit == resource.RLIM_INFINITY else f" (this process may open {limit}: ulimit -n)"
    except (ImportError, OSError, ValueError):
        shown = ""
    return UserError(source, f"too many open files{shown}: try again with fewer open, or raise the limit")
