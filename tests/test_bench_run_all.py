"""bench/run_all.sh checks every benchmark name before the first (long) run starts."""

from __future__ import annotations

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_an_unknown_name_stops_before_any_benchmark_runs() -> None:
    # "startup" comes first and would take seconds; the bad name after it must stop the script before it
    p = subprocess.run(
        ["sh", str(ROOT / "bench" / "run_all.sh"), "startup", "nope"], capture_output=True, text=True, timeout=60
    )
    assert p.returncode == 2
    assert p.stderr.strip() == "bench/run_all.sh: unknown benchmark 'nope'"
    assert p.stdout == ""
