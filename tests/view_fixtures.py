"""What the viewer's tests share: the scene of two balls on a floor (picking), and `implgen view` started in
its own process, its address read from its first line."""

from __future__ import annotations

import subprocess
import sys
from contextlib import contextmanager

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
def view_process(*args: str, env: dict | None = None):
    """`implgen view ARGS --no-browser --port 0` in a child process; yields its http:// address."""
    cmd = [sys.executable, "-m", "implgen.cli", "view", *args, "--no-browser", "--port", "0"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, text=True, env=env)
    try:
        line = proc.stdout.readline()
        yield "http://" + line.split("http://", 1)[1].split()[0]
    finally:
        proc.terminate()
        proc.wait(30)
