"""The CLI keeps NumPy's OpenBLAS pool from starting: its threads spin on the cores the render's threads need
(the measurement is in docs/tracer.md; no test here times anything)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCENE = ROOT / "bench" / "scenes" / "heart.yaml"


def _render_and_report(tmp_path: Path, env: dict) -> list[str]:
    script = (
        "import os, sys\n"
        "from implgen.cli import main\n"
        f"code = main(['render', {str(SCENE)!r}, '-q', '--width', '16', '--height', '12', '--threads', '2', "
        f"'-o', {str(tmp_path / 'h.png')!r}])\n"
        "print(os.environ.get('OPENBLAS_NUM_THREADS'), len(os.listdir('/proc/self/task')), code)\n"
    )
    p = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)
    assert p.returncode == 0, p.stderr
    return p.stdout.strip().splitlines()[-1].split()


def test_a_render_leaves_no_blas_threads_behind(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_NUM_THREADS"}
    value, threads, code = _render_and_report(tmp_path, env)
    assert (value, code) == ("1", "0")
    assert threads == "1"  # NumPy imported, the render's threads joined: only the main thread is left


def test_a_users_own_setting_is_kept(tmp_path: Path) -> None:
    value, _, code = _render_and_report(tmp_path, dict(os.environ, OPENBLAS_NUM_THREADS="2"))
    assert (value, code) == ("2", "0")
