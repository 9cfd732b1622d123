"""What the viewer's tests share: the scene of two balls on a floor (picking), and `implgen view` started in
its own process, its address read from its first line."""

from __future__ import annotations

import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

# Two balls, left and right of the camera's axis, on a floor below them.
BALLS_SCENE = {
    "image": {"width": 64, "height": 48},
    "camera": {"position": [0, 0, 10], "look_at": [0, 0, 0], "fov": 40},
    "lights": [{"position": [0, 5, 5], "color": [1, 1, 1]}],
    "objects": [
        {"equation": "y + 2", "name": "floor"},
        {"equation": "(x + 2)^2 + y^2 + z^2 - 1", "name": "left"},
        {"equation": "(x - 2)^2 + y^2 + z^2 - 1", "name": "right"},
    ],
}


@contextmanager
def view_server(*args: str, env: dict | None = None, session: bool = False, stderr=None):
    """`implgen view ARGS --no-browser --port 0` in a child process (`session`: in a session, and so a process
    group, of its own, as a terminal's job is); yields (the process, its http:// address). SIGINT as in a
    terminal whoever started the tests: a background job's (`make test &`) is ignored, and a Python started so
    would never see Ctrl-C (implgen_proc._as_in_a_terminal)."""
    from implgen_proc import _as_in_a_terminal

    cmd = [sys.executable, "-m", "implgen.cli", "view", *args, "--no-browser", "--port", "0"]
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=stderr,
        text=True,
        env=env,
        start_new_session=session,
        preexec_fn=_as_in_a_terminal,
    )
    try:
        line = proc.stdout.readline()
        yield proc, "http://" + line.split("http://", 1)[1].split()[0]
    finally:
        if proc.poll() is None:
            proc.terminate()
        proc.wait(30)


@contextmanager
def view_process(*args: str, env: dict | None = None):
    """`implgen view ARGS --no-browser --port 0` in a child process; yields its http:// address."""
    with view_server(*args, env=env) as (_, url):
        yield url


def _stat(pid: int | str) -> list[str] | None:
    """/proc/PID/stat's fields after the command's name (state, ppid, ...), or None when there is no such process."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None


def mesh_children(pid: int) -> list[int]:
    """The mesh processes (implgen.mesh.job) that process `pid` started and that still run, from /proc."""
    out = []
    for d in Path("/proc").iterdir():
        stat = _stat(d.name) if d.name.isdigit() else None
        if stat is None or stat[1] != str(pid) or stat[0] == "Z":
            continue
        try:
            if b"implgen.mesh.job" in (d / "cmdline").read_bytes():
                out.append(int(d.name))
        except OSError:
            continue
    return out


def running(pid: int) -> bool:
    """Whether process `pid` runs (a zombie, ended but not reaped, does not)."""
    stat = _stat(pid)
    return stat is not None and stat[0] != "Z"
