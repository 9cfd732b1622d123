"""A pytest plugin (tests/conftest.py loads it): tests that run a program from a Debian package say so with
`@pytest.mark.needs_program("povray")`. When one of the programs is not on PATH the test is skipped, with a
reason naming the package to install -- unless IMPLGEN_REQUIRE_ALL is set (to anything but the empty
string), as CI sets it: then the test fails, so a test that never ran cannot pass for one that did.

`make test` installs the packages when it runs as root (CI does), and otherwise says in one line which tests
will be skipped (docs/testing.md#programs-from-debian-packages).
"""

from __future__ import annotations

import os
import shutil

import pytest

#: the Debian package each program comes from
PACKAGES = {
    "chromium": "chromium",
    "chromedriver": "chromium-driver",
    "povray": "povray",
    "glslangValidator": "glslang-tools",
}
REQUIRE_ALL = "IMPLGEN_REQUIRE_ALL"


def missing(programs: tuple[str, ...]) -> list[str]:
    return [p for p in programs if shutil.which(p) is None]


def check(programs: tuple[str, ...]) -> None:
    """Skip (or, with IMPLGEN_REQUIRE_ALL set, fail) the running test when a program is not installed."""
    gone = missing(programs)
    if not gone:
        return
    packages = " ".join(dict.fromkeys(PACKAGES.get(p, p) for p in gone))
    what = f"{' and '.join(gone)} not installed (Debian: apt-get install {packages})"
    if os.environ.get(REQUIRE_ALL):
        pytest.fail(f"{what}, and {REQUIRE_ALL} is set", pytrace=False)
    pytest.skip(what)


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line(
        "markers", "needs_program(*names): the test runs these programs; skipped (or failed) when one is missing"
    )


@pytest.hookimpl(tryfirst=True)  # before the test's fixtures start a server or a browser
def pytest_runtest_setup(item: pytest.Item) -> None:
    for mark in item.iter_markers("needs_program"):
        check(mark.args)
