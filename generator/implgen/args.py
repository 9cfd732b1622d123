"""The argument parser every implgen command builds (ground floor: it imports nothing but the error type).

A bad option is a UserError (one line naming the option or the command, exit status 2), never argparse's usage
text and its own exit.
"""

from __future__ import annotations

import argparse
from typing import Any

from implgen.errors import UserError


class ArgumentParser(argparse.ArgumentParser):
    """argparse for every implgen command: `label` names the command in error messages (default: prog)."""

    def __init__(self, *args: Any, label: str | None = None, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.label = label or self.prog

    def error(self, message: str) -> Any:
        raise UserError(self.label, message)
