"""runtime_c/numerics.h, helper by helper: tests/c/test_numerics.c's named cases under ASan + UBSan, each a
pytest case of its own; and every helper the header defines has a case there."""

from __future__ import annotations

import re

import pytest

from cdriver import CDriver, case_names
from conftest import CDIR, RUNTIME

SOURCE = CDIR / "test_numerics.c"
CASES = case_names(SOURCE)


@pytest.fixture(scope="module")
def driver(tmp_path_factory) -> CDriver:
    return CDriver.build(tmp_path_factory.mktemp("numerics") / "test_numerics", [SOURCE])


@pytest.mark.parametrize("case", CASES)
def test_numerics_case(driver, case):
    driver.check(case)


def test_every_helper_has_a_case():
    """A helper added to numerics.h without a test of its own fails here."""
    helpers = re.findall(r"static inline \w+ (ig_\w+)\(", (RUNTIME / "numerics.h").read_text())
    source = SOURCE.read_text()
    bodies = re.split(r"\nstatic void ", source)
    tested = {h for h in helpers for body in bodies if body.split("(")[0] in CASES and f"{h}(" in body}
    assert len(helpers) >= 14 and set(helpers) == tested, sorted(set(helpers) - tested)


def test_a_failing_case_is_named_and_the_others_still_run(tmp_path, monkeypatch):
    """The harness itself: a failing CHECK names its case and line; the cases after it run; a crash in one case
    is reported by name when that case is run again alone."""
    src = tmp_path / "t.c"
    src.write_text(
        '#include "ctest.h"\n#include <stdlib.h>\n'
        "static void good(ctest *t) { CHECK(t, 1 + 1 == 2); }\n"
        "static void bad(ctest *t) { CHECK(t, 1 + 1 == 3); }\n"
        'static void crash(ctest *t) { (void)t; if (getenv("CRASH")) abort(); }\n'
        "static const ctest_case CASES[] = {CTEST_CASE(bad), CTEST_CASE(crash), CTEST_CASE(good)};\n"
        "int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }\n"
    )
    assert case_names(src) == ["bad", "crash", "good"]
    d = CDriver.build(tmp_path / "t", [src])
    d.check("good")
    with pytest.raises(AssertionError, match=r"case bad failed:\n  bad: .*t\.c:4: 1 \+ 1 == 3"):
        d.check("bad")
    d2 = CDriver(d.exe)
    monkeypatch.setenv("CRASH", "1")
    with pytest.raises(AssertionError, match="case crash did not finish"):
        d2.check("crash")
    d2.check("good")  # not reported by the crashed run: run alone, and it passes


def test_a_leak_fails_the_case_that_leaks(tmp_path):
    """LeakSanitizer reports at exit, after every case said ok: the run's exit status is not ignored, each case
    is run again alone, and only the case that leaks fails."""
    src = tmp_path / "t.c"
    src.write_text(
        '#include "ctest.h"\n#include <stdlib.h>\n'
        "static void good(ctest *t) { CHECK(t, 1 + 1 == 2); }\n"
        "static void leaky(ctest *t) { char *p = malloc(64); CHECK(t, p != NULL); if (p) p[0] = 1; }\n"
        "static const ctest_case CASES[] = {CTEST_CASE(good), CTEST_CASE(leaky)};\n"
        "int main(int argc, char **argv) { return ctest_main(CASES, CTEST_COUNT(CASES), argc, argv); }\n"
    )
    d = CDriver.build(tmp_path / "t", [src])
    d.check("good")
    with pytest.raises(AssertionError, match=r"(?s)case leaky exited 1:.*LeakSanitizer"):
        d.check("leaky")
