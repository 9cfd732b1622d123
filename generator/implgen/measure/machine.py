"""What machine a benchmark ran on, for the header of every results file the benchmarks write, and writing that
file."""

from __future__ import annotations

import os
import platform
import subprocess
from pathlib import Path


def cpu_model() -> str:
    """The CPU's model name as `lscpu` gives it, else what the platform module knows."""
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=False).stdout
    except OSError:
        out = ""
    for line in out.splitlines():
        if line.startswith("Model name:"):
            return line.split(":", 1)[1].strip()
    return platform.processor() or "unknown CPU"


def describe() -> str:
    """One line: CPU model, cores, system, Python version."""
    return (
        f"{cpu_model()}, {os.cpu_count()} cores, {platform.system()} {platform.machine()}, "
        f"Python {platform.python_version()}"
    )


def load_average() -> str:
    """The 1, 5 and 15 minute load averages: above about 1 per core, other work shared the machine."""
    try:
        return ", ".join(f"{v:.2f}" for v in os.getloadavg())
    except OSError:
        return "unknown"


def write_results(path: Path, text: str) -> None:
    """Write a results file whole (a temporary name renamed into place: an interrupted run leaves the old one)."""
    from implgen.outputs import atomic_write

    data = text.encode("utf-8")
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, lambda fh: fh.write(data))


def write_section(path: Path, begin: str, end: str, section: str) -> None:
    """Put `section` (from its `begin` marker to its `end` marker) into the results file in place of the one
    there, or at its end: the file's other sections stay."""
    old = path.read_text(encoding="utf-8") if path.exists() else ""
    if begin in old and end in old:
        text = old[: old.index(begin)] + section.rstrip("\n") + old[old.index(end) + len(end) :]
    else:
        text = (old.rstrip("\n") + "\n\n" if old.strip() else "") + section.rstrip("\n") + "\n"
    write_results(path, text)
