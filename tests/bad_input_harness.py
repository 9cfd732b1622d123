"""Bad-input cases run as the user runs them, held to the contract (tests/test_bad_specs.py,
tests/test_bad_scenes.py).

A Case is a folder of files (text, bytes, a fifo, a folder, a symbolic link) and a command line run in that
folder through `implgen.cli.main`. All cases of a suite run in one child process (tests/bad_input_runner.py)
limited to 300 MB of address space, each case stopped after 5 s. Each must: exit with status 2, print
exactly one line on stderr that names the file or option and says the problem, print nothing on stdout,
create or change no file, and run no code (the payloads would create a file named PWNED).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RUNNER = Path(__file__).resolve().parent / "bad_input_runner.py"
SHAPES = ROOT / "examples" / "shapes"
SPHERE = str(SHAPES / "sphere.yaml")

FIFO = "<fifo>"
FOLDER = "<folder>"


@dataclass(frozen=True)
class Link:
    target: str


@dataclass
class Case:
    id: str
    argv: list[str]
    fragment: str  # what the message must say
    files: dict[str, str | bytes | Link] = field(default_factory=dict)
    names: str | None = None  # the file or option the message must name; default: the first argument

    def named(self) -> str:
        return self.names if self.names is not None else self.argv[0 if self.argv[0] != "render" else 1]


def materialize(case: Case, root: Path) -> Path:
    folder = root / case.id
    folder.mkdir(parents=True)
    for rel, content in case.files.items():
        path = folder / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        if content == FIFO:
            os.mkfifo(path)
        elif content == FOLDER:
            path.mkdir()
        elif isinstance(content, Link):
            path.symlink_to(content.target)
        elif isinstance(content, bytes):
            path.write_bytes(content)
        else:
            path.write_text(content, encoding="utf-8")
    return folder


def run_batch(cases: list[Case], root: Path) -> tuple[dict[str, dict], int]:
    """Run every case in one child process; ({case id: result}, the child's peak resident bytes)."""
    ids = [c.id for c in cases]
    assert len(set(ids)) == len(ids), "case ids must be unique"
    jobs = [{"id": c.id, "dir": str(materialize(c, root)), "argv": c.argv} for c in cases]
    listing = root / "cases.json"
    listing.write_text(json.dumps(jobs))
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    proc = subprocess.run(
        [sys.executable, str(RUNNER), str(listing)],
        capture_output=True,
        text=True,
        timeout=60 + 6 * len(cases),
        env=env,
        cwd=root,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    report = json.loads(proc.stdout)
    return {r["id"]: r for r in report["results"]}, report["max_rss_bytes"]


def check(case: Case, result: dict) -> None:
    assert result["exception"] is None, result["exception"]
    err = result["stderr"]
    assert result["code"] == 2, (result["code"], err)
    assert result["stdout"] == "", result["stdout"]
    assert err.count("\n") == 1 and err.endswith("\n") and err.startswith("implgen: error: "), repr(err)
    assert case.named() in err, f"{case.named()!r} not named in {err!r}"
    assert case.fragment in err, f"{case.fragment!r} not in {err!r}"
    assert "Traceback" not in err
    assert result["changed"] == [], f"files created or changed: {result['changed']}"
    assert result["seconds"] < 5.0
