"""C test drivers written with tests/c/ctest.h, reported to pytest case by case.

A driver's cases are read from its source (its `CTEST_CASE(name)` table), so pytest lists them by name
before anything is compiled. The driver is built once (ASan + UBSan) and run once for all its cases; a case
the run did not report (a sanitizer abort ends the process) is run again on its own, so one crash names
its case and does not hide the others. A run that exits non-zero although no case failed (LeakSanitizer
reports at exit) has every case run again alone, and a case passes only when its own run exits 0."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

from conftest import compile_c

CASE = re.compile(r"CTEST_CASE\((\w+)\)")


def case_names(source: Path) -> list[str]:
    """The cases of a driver, in the order of its table."""
    return CASE.findall(source.read_text())


class CDriver:
    """One compiled driver and what its cases printed."""

    def __init__(self, exe: Path) -> None:
        self.exe = exe
        self.results: dict[str, tuple[bool, str]] = {}
        self._ran_all = False
        self._clean = False  # the run of all cases exited 0, or 1 with a failed case

    @classmethod
    def build(cls, out: Path, sources, **kwargs) -> CDriver:
        return cls(compile_c(out, sources, **kwargs))

    def _run(self, *names: str) -> tuple[int, str]:
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1", UBSAN_OPTIONS="print_stacktrace=1")
        proc = subprocess.run([str(self.exe), *names], capture_output=True, text=True, timeout=600, env=env)
        detail: list[str] = []
        for line in proc.stdout.splitlines():
            verdict = re.fullmatch(r"(ok|FAIL) (\w+)", line)
            if verdict:
                self.results[verdict[2]] = (verdict[1] == "ok", "\n".join(detail))
                detail = []
            else:
                detail.append(line)
        return proc.returncode, "\n".join([*detail, proc.stderr.strip()])

    def check(self, name: str) -> str:
        """Fails the calling test unless case `name` passed; what the case printed (its figures)."""
        if not self._ran_all:
            self._ran_all = True
            code, _ = self._run()
            failed = any(not ok for ok, _ in self.results.values())
            self._clean = code == 0 or (code == 1 and failed)
        if name not in self.results or not self._clean:
            self.results.pop(name, None)
            code, rest = self._run(name)
            assert name in self.results, f"case {name} did not finish (exit status {code}):\n{rest}"
            assert code == (0 if self.results[name][0] else 1), f"case {name} exited {code}:\n{rest}"
        ok, detail = self.results[name]
        assert ok, f"case {name} failed:\n{detail}"
        return detail
