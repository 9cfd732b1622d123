"""Run bad-input cases through the real command line (`implgen.cli.main`) in this one process, held to the
contract's bounds: at most MEMORY_LIMIT of address space for the whole process (RLIMIT_AS: a case that
needs more fails with MemoryError) and at most SECONDS per case (an alarm stops it).

    python bad_input_runner.py CASES.json      -> a JSON list of results on stdout

Each case is {"id", "dir", "argv"}: the command runs with `dir` as its working directory. A result holds the
exit status, stdout, stderr, the seconds taken, the exception if any other escaped, and every file created,
changed or removed under `dir`. Used by tests/bad_input_harness.py; not a test module itself.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import resource
import signal
import sys
import time
import traceback

MEMORY_LIMIT = 300 << 20
SECONDS = 5.0


class Timeout(BaseException):
    pass


def _ring(signum, frame):
    raise Timeout(f"more than {SECONDS} s")


def snapshot(folder: str) -> dict[str, tuple]:
    out = {}
    for base, dirs, files in os.walk(folder):
        for name in dirs + files:
            path = os.path.join(base, name)
            try:
                info = os.lstat(path)
            except OSError:
                continue
            out[os.path.relpath(path, folder)] = (info.st_mode, info.st_size, info.st_mtime_ns)
    return out


def run_case(case: dict) -> dict:
    from implgen.cli import main

    os.chdir(case["dir"])
    before = snapshot(case["dir"])
    out, err = io.StringIO(), io.StringIO()
    result: dict = {"id": case["id"], "exception": None}
    start = time.perf_counter()
    signal.setitimer(signal.ITIMER_REAL, SECONDS)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            result["code"] = main(case["argv"])
    except BaseException as exc:  # anything but a clean exit is what the test reports
        result["code"] = None
        result["exception"] = "".join(traceback.format_exception_only(exc)).strip()[:2000]
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
    result["seconds"] = time.perf_counter() - start
    after = snapshot(case["dir"])
    result["changed"] = sorted(k for k in set(before) | set(after) if before.get(k) != after.get(k))
    result["stdout"], result["stderr"] = out.getvalue(), err.getvalue()
    return result


def main() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))
    signal.signal(signal.SIGALRM, _ring)
    # Imported before any case is timed: the first case should not pay for SymPy's import.
    import implgen.animation.batch  # noqa: F401  (a still's path no longer imports it; Dask's cases do)
    import implgen.animation.command  # noqa: F401
    import implgen.codegen.command  # noqa: F401
    import implgen.codegen.emit  # noqa: F401

    with open(sys.argv[1], encoding="utf-8") as fh:
        cases = json.load(fh)
    results = [run_case(case) for case in cases]
    json.dump({"results": results, "max_rss_bytes": peak_rss()}, sys.stdout)


def peak_rss() -> int:
    """This process's own peak resident size. Linux's VmHWM belongs to the address space made at exec;
    getrusage's ru_maxrss is kept across exec, so it would report the parent's size at the fork (pytest's,
    late in a full run) rather than this runner's."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


if __name__ == "__main__":
    main()
