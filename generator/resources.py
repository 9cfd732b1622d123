"""Where the package data (templates, C runtime sources) lives once installed."""

from __future__ import annotations

from pathlib import Path

_PACKAGE_DIR = Path(__file__).resolve().parent


def templates_dir() -> Path:
    """Folder holding the Jinja2 templates (`c/`, `python/`)."""
    return _PACKAGE_DIR / "templates" if (_PACKAGE_DIR / "templates").is_dir() else _PACKAGE_DIR.parent / "templates"


def runtime_dir() -> Path:
    """Folder holding the hand-written C runtime sources (`*.c`, `*.h`)."""
    return _PACKAGE_DIR / "runtime_c" if (_PACKAGE_DIR / "runtime_c").is_dir() else _PACKAGE_DIR.parent / "runtime_c"
