"""Whole-process time of a tiny `implgen render` whose scene is already built, against bare Python.

    .venv/bin/python bench/startup.py [--runs 5] [--size 16x12] [-o bench/results/startup.md]

With a fresh build cache (a temporary folder as $IMPLGEN_CACHE), each scene of bench/scenes/ is rendered once
cold (parse, generate, compile: timed once, for reference), then, round by round and interleaved so a change
in the machine's load hits every command alike, the same tiny render again (everything cached) beside
`python -c pass` and `python -c "import numpy"`. Prints the medians and writes them, with the machine, to the
results file. Each timed command is a new process, measured from spawn to exit, as a user waits for it.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from implgen.measure.machine import describe as machine
from implgen.measure.machine import load_average, write_results

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "bench" / "scenes"
TARGET = 0.15  # seconds for a cached render, the whole process, spawn to exit
HEAVY = ("sympy", "matplotlib", "tqdm", "dask", "distributed", "imageio", "starlette", "uvicorn", "jinja2")
HEAVY += ("asyncio", "implgen.animation.cluster", "implgen.animation.batch")  # Dask's side: not a still's


def implgen_command() -> list[str]:
    script = Path(sys.executable).parent / "implgen"  # the console script a user runs
    return [str(script)] if script.exists() else [sys.executable, "-m", "implgen.cli"]


def timed(cmd: list[str], env: dict) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, check=False)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise SystemExit(f"bench/startup.py: {' '.join(cmd)} failed:\n{proc.stderr}")
    return seconds


def heavy_imports(render_args: list[str], env: dict) -> list[str]:
    """Which heavy modules a cached render imports (expected: none)."""
    code = (
        "import sys\nfrom implgen.cli import main\n"
        f"main({render_args!r})\nprint('heavy:' + ','.join(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    line = [x for x in out.stdout.splitlines() if x.startswith("heavy:")][-1]
    return [m for m in line.removeprefix("heavy:").split(",") if m]


def runtime_compile_times(tmp: Path) -> list[tuple[str, float]]:
    """Seconds to compile each C runtime source once with the build flags (what the first build of a new
    cache pays, one file per core; afterwards the cache keeps the objects), slowest first."""
    from implgen.compile.clib import BASE_FLAGS, compiler
    from implgen.resources import runtime_dir

    src = runtime_dir()
    out = []
    for c in sorted(src.glob("*.c")):
        cmd = [compiler(), *BASE_FLAGS, "-c", str(c), "-o", str(tmp / (c.stem + ".o")), f"-I{src}"]
        out.append((c.name, timed(cmd, dict(os.environ))))
    return sorted(out, key=lambda x: -x[1])


@dataclass
class Measured:
    """What one run of the script measured: seconds per command and round, the cold first renders, the heavy
    modules a cached render imported, the runtime's compile times, and the load average before."""

    times: dict[str, list[float]]
    cold: dict[str, float]
    heavy: list[str]
    compile_times: list[tuple[str, float]]
    load_before: str
    load_after: str = ""


def measure(runs: int, width: int, height: int) -> Measured:
    """Fill a fresh cache with one cold render per scene, then time every command in `runs` interleaved rounds."""
    load_before = load_average()
    with tempfile.TemporaryDirectory(prefix="implgen-startup-") as tmp:
        env = dict(os.environ, IMPLGEN_CACHE=str(Path(tmp) / "cache"))
        png = str(Path(tmp) / "out.png")
        render_args = {
            s.stem: ["render", str(s), "-o", png, "-q", "--width", str(width), "--height", str(height)]
            for s in sorted(SCENES.glob("*.yaml"))
        }
        commands = {"python -c pass": [sys.executable, "-c", "pass"]}
        commands["python -c 'import numpy'"] = [sys.executable, "-c", "import numpy"]
        cold = {}
        for name, a in render_args.items():
            cold[name] = timed(implgen_command() + a, env)  # parse, generate, compile: fills the cache
            commands[f"implgen render {name} (cached)"] = implgen_command() + a
        heavy = heavy_imports(next(iter(render_args.values())), env)
        compile_times = runtime_compile_times(Path(tmp))
        times: dict[str, list[float]] = {k: [] for k in commands}
        for _ in range(max(1, runs)):
            for k, cmd in commands.items():
                times[k].append(timed(cmd, env))
    return Measured(times, cold, heavy, compile_times, load_before, load_average())


def busy(before: str, after: str) -> bool:
    """Whether the load averages say other work shared the machine: the 1-minute figure above half the cores
    before the run, or above three quarters after it (the run itself adds up to about one)."""
    try:
        first = [float(load.split(",")[0]) for load in (before, after)]
    except ValueError:
        return False
    cores = os.cpu_count() or 1
    return first[0] > 0.5 * cores or first[1] > 0.75 * cores


def table(m: Measured) -> list[str]:
    med = {k: statistics.median(v) for k, v in m.times.items()}
    base, numpy_base = med["python -c pass"], med["python -c 'import numpy'"]
    lines = [
        "| command | median (s) | min (s) | max (s) | × `python -c pass` | × `import numpy` | cold (s) |",
        "|---|---:|---:|---:|---:|---:|---:|",
    ]
    for k, v in m.times.items():
        name = k.removeprefix("implgen render ").removesuffix(" (cached)")
        c = f"{m.cold[name]:.2f}" if name in m.cold else ""
        lines.append(
            f"| {k} | {med[k]:.3f} | {min(v):.3f} | {max(v):.3f} | {med[k] / base:.2f} | "
            f"{med[k] / numpy_base:.2f} | {c} |"
        )
    worst = max(v for k, v in med.items() if k.startswith("implgen"))
    verdict = "met" if worst <= TARGET else "missed"
    lines += [
        "",
        f"Slowest cached render: {worst:.3f} s ({worst / numpy_base:.2f}× `import numpy`), target {TARGET} s: "
        f"**{verdict}**. Heavy modules a cached render imports ({', '.join(HEAVY)}): {', '.join(m.heavy) or 'none'}.",
    ]
    if busy(m.load_before, m.load_after):
        lines += [
            "",
            "The machine was busy with other work (a load average above half its cores): every command here, bare "
            "Python and `import numpy` too, ran slower than it would alone, so the seconds are not comparable "
            "with the target or with a quiet machine's; the ratios to `import numpy` are.",
        ]
    return lines


def report(m: Measured, runs: int, size: str) -> str:
    width, height = (int(v) for v in size.lower().split("x"))
    lines = [
        "# Start-up: a tiny cached render against bare Python",
        "",
        f"Written by `bench/startup.py --runs {runs} --size {size}` on {machine()}. Load average "
        f"before: {m.load_before}; after: {m.load_after}.",
        "",
        f"Whole-process wall time from spawn to exit, median of {runs} interleaved rounds. The render is "
        f"`implgen render SCENE -o OUT.png -q --width {width} --height {height}` with the scene's shapes already "
        "parsed, generated and compiled (the build cache is warm); the cold column is its first run with an "
        "empty cache (parse with SymPy, generate, compile), timed once.",
        "",
        *table(m),
        "",
        "## First build of the C runtime",
        "",
        "Wall seconds to compile each runtime source once with the build flags (timed once each, one after "
        "another; a first build runs one compiler per core, and the build cache keeps every object after that). "
        f"Total: {sum(t for _, t in m.compile_times):.2f} s.",
        "",
        "| source | compile (s) |",
        "|---|---:|",
        *(f"| {name} | {t:.2f} |" for name, t in m.compile_times),
        "",
    ]
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="timed rounds (default 5)")
    ap.add_argument("--size", default="16x12", help="image size of the tiny render (default 16x12)")
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "startup.md")
    args = ap.parse_args()
    width, height = (int(v) for v in args.size.lower().split("x"))
    text = report(measure(args.runs, width, height), args.runs, args.size)
    print(text)
    write_results(args.output, text)
    print(f"wrote {args.output}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
