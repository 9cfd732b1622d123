"""A pytest plugin (tests/conftest.py loads it): tests that run a program from a Debian package say so with
`@pytest.mark.needs_program("povray")`. When one of the programs is not on PATH the test is skipped, with a
reason naming the package to install -- unless IMPLGEN_REQUIRE_ALL is set (to anything but the empty
string), as CI sets it: then the test fails, so a test that never ran cannot pass for one that did.

Tests that compile against a C library from a Debian package say `@pytest.mark.needs_library("embree3")`: the
library counts as installed when the C compiler builds and links a two-line program that includes its header
and calls it (LIBRARIES), and is skipped or failed alike.

`make test` installs the packages when it runs as root (CI does), and otherwise says in one line which tests
will be skipped (docs/testing.md#programs-from-debian-packages).
"""

from __future__ import annotations

import functools
import os
import shutil
import subprocess
import tempfile

import pytest

#: the Debian package each program comes from
PACKAGES = {
    "chromium": "chromium",
    "chromedriver": "chromium-driver",
    "povray": "povray",
    "glslangValidator": "glslang-tools",
    "blender": "blender",
}
#: C libraries: the Debian package, a header the program includes, and an expression of the library it links
LIBRARIES = {
    "embree3": ("libembree-dev", "embree3/rtcore.h", "rtcNewDevice(0) != 0"),
}
REQUIRE_ALL = "IMPLGEN_REQUIRE_ALL"


def missing(programs: tuple[str, ...]) -> list[str]:
    return [p for p in programs if shutil.which(p) is None]


@functools.cache
def library_links(name: str) -> bool:
    """Does the C compiler build and link a program that includes the library's header and calls it?"""
    _, header, call = LIBRARIES[name]
    cc = os.environ.get("CC", "cc")
    if shutil.which(cc) is None:
        return False
    source = f"#include <{header}>\nint main(void) {{ return {call}; }}\n"
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [cc, "-xc", "-", "-o", os.path.join(tmp, "a.out"), f"-l{name}"]
        try:
            proc = subprocess.run(cmd, input=source, capture_output=True, text=True, timeout=120)
        except (OSError, subprocess.SubprocessError):
            return False
    return proc.returncode == 0


def check(programs: tuple[str, ...], libraries: tuple[str, ...] = ()) -> None:
    """Skip (or, with IMPLGEN_REQUIRE_ALL set, fail) the running test when a program or a library is not
    installed."""
    gone = missing(programs) + [f"lib{lib}" for lib in libraries if not library_links(lib)]
    if not gone:
        return
    names = {**PACKAGES, **{f"lib{lib}": pkg for lib, (pkg, _, _) in LIBRARIES.items()}}
    packages = " ".join(dict.fromkeys(names.get(p, p) for p in gone))
    what = f"{' and '.join(gone)} not installed (Debian: apt-get install {packages})"
    if os.environ.get(REQUIRE_ALL):
        pytest.fail(f"{what}, and {REQUIRE_ALL} is set", pytrace=False)
    pytest.skip(what)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "needs_program(*names): the test runs these programs; skipped (or failed) when one is missing"
    )
    config.addinivalue_line(
        "markers", "needs_library(*names): the test links these C libraries; skipped (or failed) when one is missing"
    )


@pytest.hookimpl(tryfirst=True)  # before the test's fixtures start a server or a browser
def pytest_runtest_setup(item: pytest.Item) -> None:
    for mark in item.iter_markers("needs_program"):
        check(mark.args)
    for mark in item.iter_markers("needs_library"):
        check((), mark.args)
