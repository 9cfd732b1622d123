"""The installed `implgen` command run as the user runs it: a child process, its exit status, stdout and stderr.

The command is the one beside this Python (`.venv/bin/implgen`), so a test sees what the installed package
does, tracebacks and signal handling included. The build cache is the caller's ($IMPLGEN_CACHE).
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

IMPLGEN = shutil.which("implgen", path=str(Path(sys.executable).parent)) or "implgen"


@dataclass
class Ran:
    code: int
    out: str
    err: str
    seconds: float


def env() -> dict[str, str]:
    return dict(os.environ, OPENBLAS_NUM_THREADS="1", PYTHONUNBUFFERED="1")


def implgen(*args: str, cwd: Path | None = None, timeout: float = 60) -> Ran:
    import time

    t0 = time.monotonic()
    proc = subprocess.run(
        [IMPLGEN, *map(str, args)], capture_output=True, text=True, timeout=timeout, cwd=cwd, env=env()
    )
    return Ran(proc.returncode, proc.stdout, proc.stderr, time.monotonic() - t0)


def _as_in_a_terminal() -> None:
    """Ctrl-C as a user's terminal sends it: a shell that runs a job in the background (`make test &`, a CI
    runner) starts it with SIGINT ignored, and a Python started so never installs KeyboardInterrupt."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def start(*args: str, cwd: Path | None = None) -> subprocess.Popen:
    """The command started in the background (stdout and stderr piped, text), with SIGINT as in a terminal."""
    return subprocess.Popen(
        [IMPLGEN, *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
        env=env(),
        preexec_fn=_as_in_a_terminal,
    )


def assert_one_line(ran: Ran, *fragments: str, code: int = 2) -> None:
    """The bad-input contract: exit status `code`, one line on stderr holding every fragment, no traceback."""
    assert ran.code == code, (ran.code, ran.err[-3000:])
    assert "Traceback" not in ran.err, ran.err[-3000:]
    assert ran.err.count("\n") == 1 and ran.err.startswith("implgen: error: "), ran.err[-3000:]
    for fragment in fragments:
        assert fragment in ran.err, (fragment, ran.err)
