"""The argument parser every implgen command builds (ground floor: it imports nothing but the error type).

A bad option is a UserError (one line naming the option or the command, exit status 2), never argparse's usage
text and its own exit. `--help` ends with the command's examples, printed as written.
"""

from __future__ import annotations

import argparse
import textwrap
from collections.abc import Sequence
from typing import Any

from implgen.errors import UserError

WIDTH = 100  # the description is wrapped to this; the examples are printed as written


def examples_text(examples: Sequence[tuple[str, str]]) -> str:
    """(what it does, the command line) pairs as an "examples:" block a person can copy from."""
    lines = ["examples:"]
    for what, command in examples:
        lines += [f"  # {what}", f"  {command}"]
    return "\n".join(lines)


class ArgumentParser(argparse.ArgumentParser):
    """argparse for every implgen command: `label` names the command in error messages (default: prog);
    `examples` (what it does, the command line) pairs become the help's "examples:" epilog."""

    def __init__(
        self,
        *args: Any,
        label: str | None = None,
        examples: Sequence[tuple[str, str]] = (),
        description: str | None = None,
        **kwargs: Any,
    ) -> None:
        if description is not None:
            description = "\n\n".join(textwrap.fill(p, WIDTH) for p in description.split("\n\n"))
        if examples:
            kwargs.setdefault("epilog", examples_text(examples))
        kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, description=description, **kwargs)
        self.label = label or self.prog

    def error(self, message: str) -> Any:
        raise UserError(self.label, message)
