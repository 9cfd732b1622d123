"""Programs from Debian packages (chromium, chromium-driver, povray, clang-format): as an ordinary user a missing
one skips what needs it, with one line or a reason naming the package; with IMPLGEN_REQUIRE_ALL set (CI) it
fails instead; as root `make` installs it. Run in child processes with PATH cut down to a folder of our own."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
TESTS = ROOT / "tests"

SAMPLE = """
import shutil
import pytest

@pytest.mark.needs_program("povray")
def test_needs_povray():
    assert shutil.which("povray")

@pytest.mark.needs_program("chromium", "chromedriver")
def test_needs_the_browser():
    assert shutil.which("chromium")

@pytest.mark.needs_program("implgen-fake-tool")
def test_needs_a_program_that_is_there():
    assert shutil.which("implgen-fake-tool")

def test_needs_nothing():
    pass
"""


def _bin(folder: Path, **scripts: str) -> Path:
    folder.mkdir(exist_ok=True)
    for name, body in scripts.items():
        path = folder / name
        path.write_text(f"#!/bin/sh\n{body}\n")
        path.chmod(0o755)
    return folder


def _pytest(args: list[str], path: Path, cwd: Path, require_all: bool) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if k != "IMPLGEN_REQUIRE_ALL"}
    env.update(PATH=str(path), PYTHONPATH=str(TESTS), **({"IMPLGEN_REQUIRE_ALL": "1"} if require_all else {}))
    cmd = [sys.executable, "-m", "pytest", "-q", "-rsE", "-p", "no:cacheprovider", *args]
    return subprocess.run(cmd, capture_output=True, text=True, cwd=cwd, env=env, timeout=300)


def test_the_marker_skips_naming_the_package_or_fails_when_all_are_required(tmp_path):
    (tmp_path / "pytest.ini").write_text("[pytest]\n")
    (tmp_path / "test_sample.py").write_text(SAMPLE)
    path = _bin(tmp_path / "bin", **{"implgen-fake-tool": "exit 0"})
    args = ["-p", "needs_program", "test_sample.py"]

    p = _pytest(args, path, tmp_path, require_all=False)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "2 passed, 2 skipped" in p.stdout
    assert "povray not installed (Debian: apt-get install povray)" in p.stdout
    assert "chromium and chromedriver not installed (Debian: apt-get install chromium chromium-driver)" in p.stdout

    p = _pytest(args, path, tmp_path, require_all=True)
    assert p.returncode == 1
    assert "2 passed, 2 errors" in p.stdout and "skipped" not in p.stdout
    assert "povray not installed (Debian: apt-get install povray), and IMPLGEN_REQUIRE_ALL is set" in p.stdout


def test_the_browser_and_povray_tests_carry_the_marker(tmp_path):
    """The real test modules, run with an empty PATH: every test that needs a program is skipped, naming its
    package, and none of them runs; with IMPLGEN_REQUIRE_ALL each is an error."""
    modules = ["tests/test_view_browser.py", "tests/test_povray_compare.py"]
    empty = _bin(tmp_path / "empty")
    p = _pytest(["-m", "needs_program", *modules], empty, ROOT, require_all=False)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "6 skipped" in p.stdout and "passed" not in p.stdout
    assert "apt-get install chromium chromium-driver" in p.stdout and "apt-get install povray" in p.stdout
    p = _pytest(["-m", "needs_program", *modules], empty, ROOT, require_all=True)
    assert p.returncode == 1 and "6 errors" in p.stdout and "skipped" not in p.stdout


def _make(targets: list[str], path: Path, require_all: bool = False) -> subprocess.CompletedProcess:
    env = {"PATH": str(path), **({"IMPLGEN_REQUIRE_ALL": "1"} if require_all else {})}  # no MAKEFLAGS from a parent
    cmd = [shutil.which("make"), "-s", "-C", str(ROOT), *targets]
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)


@pytest.mark.needs_program("make")
@pytest.mark.parametrize("uid", ["1000", "0"])
def test_make_installs_as_root_and_otherwise_says_what_is_skipped(tmp_path, uid):
    log = tmp_path / "apt.log"
    path = _bin(tmp_path / "bin", id=f"echo {uid}", **{"apt-get": f'echo "$*" >> {log}'})
    (path / "find").symlink_to(shutil.which("find"))  # the Makefile lists its sources with find
    p = _make(["browser", "povray", "tools"], path)
    assert p.returncode == 0, p.stderr
    if uid == "0":
        assert p.stdout == ""
        installs = [line for line in log.read_text().splitlines() if line.startswith("install")]
        assert installs == [f"install -y -qq {pkgs}" for pkgs in ("chromium chromium-driver", "povray", "clang-format")]
        return
    assert not log.exists()
    assert p.stdout.splitlines() == [
        "make: chromium chromedriver not installed: the browser tests will be skipped "
        "(as root: apt-get install chromium chromium-driver)",
        "make: povray not installed: the POV-Ray render tests will be skipped (as root: apt-get install povray)",
        "make: clang-format not installed: the C style check will be skipped (as root: apt-get install clang-format)",
    ]
    p = _make(["povray"], path, require_all=True)
    assert p.returncode != 0 and not log.exists()
    assert "make: povray not installed and IMPLGEN_REQUIRE_ALL is set (as root: apt-get install povray)" in p.stderr


@pytest.mark.needs_program("make")
def test_make_does_nothing_when_the_programs_are_there(tmp_path):
    log = tmp_path / "apt.log"
    fakes = {name: "exit 0" for name in ("chromium", "chromedriver", "povray", "clang-format")}
    path = _bin(tmp_path / "bin", id="echo 1000", **{"apt-get": f'echo "$*" >> {log}'}, **fakes)
    (path / "find").symlink_to(shutil.which("find"))
    p = _make(["browser", "povray", "tools"], path, require_all=True)
    assert (p.returncode, p.stdout, p.stderr) == (0, "", "") and not log.exists()


def test_the_embree_tests_carry_the_library_marker(tmp_path):
    """Without a C compiler that links libembree3 (here: none on PATH) every Embree test is skipped with one
    reason naming libembree-dev; with IMPLGEN_REQUIRE_ALL each is an error."""
    empty = _bin(tmp_path / "empty")
    p = _pytest(["tests/test_embree.py"], empty, ROOT, require_all=False)
    assert p.returncode == 0, p.stdout + p.stderr
    assert "passed" not in p.stdout and re.search(r"\d+ skipped", p.stdout)
    assert "libembree3 not installed (Debian: apt-get install libembree-dev)" in p.stdout
    p = _pytest(["tests/test_embree.py"], empty, ROOT, require_all=True)
    assert p.returncode == 1 and "skipped" not in p.stdout and "passed" not in p.stdout


@pytest.mark.needs_program("make")
@pytest.mark.parametrize("uid", ["1000", "0"])
def test_make_embree_checks_the_header(tmp_path, uid):
    """`make embree` looks for Embree's header (a library has no program to find): missing, root installs
    libembree-dev, anyone else gets one line, and IMPLGEN_REQUIRE_ALL stops."""
    log = tmp_path / "apt.log"
    path = _bin(tmp_path / "bin", id=f"echo {uid}", **{"apt-get": f'echo "$*" >> {log}'})
    for tool in ("find", "test"):
        if shutil.which(tool):
            (path / tool).symlink_to(shutil.which(tool))
    gone = f"EMBREE_HEADER={tmp_path / 'none' / 'rtcore.h'}"
    p = _make(["embree", gone], path)
    assert p.returncode == 0, p.stderr
    if uid == "0":
        assert [x for x in log.read_text().splitlines() if x.startswith("install")] == ["install -y -qq libembree-dev"]
        return
    assert not log.exists()
    assert p.stdout.splitlines() == [
        f"make: {tmp_path / 'none' / 'rtcore.h'} not installed: the Embree tests will be skipped "
        "(as root: apt-get install libembree-dev)"
    ]
    p = _make(["embree", gone], path, require_all=True)
    assert p.returncode != 0 and "IMPLGEN_REQUIRE_ALL is set (as root: apt-get install libembree-dev)" in p.stderr
