"""implgen against POV-Ray 3.7 on the same scenes, and how intersection cost grows with degree.

    .venv/bin/python bench/povray_compare.py [--quick] [-o bench/results/povray] [--runs N] [--scenes a,b]

For each scene in bench/scenes/ (torus, piriform, heart sextic, Chmutov octic, the torus again seen from 10^4
units through a telephoto lens, Chmutov surfaces of degree 12 and 16, a spiky superellipsoid of degree 20;
ground plane, one light, shadows, 800x600, 1 sample) it
  1. exports the same scene to POV-Ray (`polynomial { ... sturm }`, expanded exactly from our spec; matched
     camera: POV-Ray is left-handed, so `right -x*aspect`; our fov is vertical, POV-Ray's angle horizontal);
  2. times both programs as subprocesses (wall clock, median of --runs runs, interleaved) on 1 thread and on
     all threads, and also records each program's own render-time figure;
  3. renders coverage masks (ours: the tracer with a flat white unlit material, black background, no
     plane; POV-Ray: `finish { ambient 1 diffuse 0 }`, black background, no plane, no light), counts the
     pixels where they disagree and decides each disputed pixel exactly: its primary ray is mapped to object
     space in rational arithmetic, f(o + t d) is expanded over Q, t is clipped to the object's box, and
     Descartes' rule of signs with bisection on integers (implgen.roots.exactray, implgen.roots.descartes)
     decides whether a real root lies there;
  4. times the generated C intersectors of a dense degree-n family (n = 2..20): coefficients, solve, total;
  5. writes report.md, results.json and the images into the output folder.
Every number in the report comes from this one run.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SCENES = ("torus", "piriform", "heart", "chmutov", "torus_far", "chmutov12", "chmutov16", "spiky20")
IMPLGEN = Path(sys.executable).parent / "implgen"


def _ensure_current_install() -> None:
    """The venv holds an installed copy of implgen; reinstall it from this tree if it predates the exporter."""
    try:
        from implgen.export.povray import scene_pov  # noqa: F401
    except ImportError:
        print("installing implgen from", ROOT, "(the installed copy has no scene exporter)")
        subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", str(ROOT)], check=True)


_ensure_current_install()

from implgen.export import povray as pv  # noqa: E402
from implgen.measure.machine import cpu_model  # noqa: E402
from implgen.roots.exactray import ExactJudge, Placed  # noqa: E402
from implgen.scene.camera import camera_rays  # noqa: E402
from implgen.scene.load import load_scene  # noqa: E402

# --------------------------------------------------------------------------------------------- POV-Ray


def ensure_povray() -> str:
    exe = shutil.which("povray")
    if exe:
        return exe
    print("POV-Ray is missing: installing Debian's package `povray` ...")
    apt = ["apt-get", "install", "-y", "povray"]
    if os.geteuid() != 0 and shutil.which("sudo"):
        apt = ["sudo", *apt]
    if subprocess.run(apt, check=False).returncode != 0:
        subprocess.run([*apt[:-3], "update"] if apt[0] == "sudo" else ["apt-get", "update"], check=False)
        subprocess.run(apt, check=False)
    exe = shutil.which("povray")
    if not exe:
        sys.exit("error: could not install POV-Ray (try `apt-get install -y povray` as root); nothing measured")
    return exe


def povray_version(exe: str) -> str:
    p = subprocess.run([exe, "--version"], capture_output=True, text=True, check=False)
    m = re.search(r"POV-Ray\s+([\d.]+\S*)", p.stdout + p.stderr)
    return m.group(1) if m else "unknown"


def run_povray(exe: str, pov: Path, out: Path, w: int, h: int, threads: int) -> tuple[float, float]:
    """(wall seconds, POV-Ray's own trace time). No antialiasing, no display, linear output."""
    cmd = [exe, f"+I{pov}", f"+O{out}", f"+W{w}", f"+H{h}", "-A", f"+WT{threads}", "-D", "-P", "+FN", "File_Gamma=1.0"]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, check=False, cwd=pov.parent)
    wall = time.perf_counter() - t0
    if p.returncode != 0 or not out.exists():
        raise RuntimeError(f"POV-Ray failed on {pov}:\n{p.stderr[-2000:]}")
    m = re.search(r"Trace Time:.*\(([\d.]+) seconds\)", p.stderr)
    return wall, float(m.group(1)) if m else float("nan")


def run_ours(scene: Path, out: Path, w: int, h: int, threads: int) -> tuple[float, float]:
    """(wall seconds of `implgen render`, the render time it prints)."""
    cmd = [
        str(IMPLGEN),
        "render",
        str(scene),
        "-o",
        str(out),
        "--width",
        str(w),
        "--height",
        str(h),
        "--spp",
        "1",
        "--threads",
        str(threads),
    ]
    env = {**os.environ, "TQDM_DISABLE": "1"}
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"implgen render failed on {scene}:\n{p.stderr[-2000:]}")
    m = re.search(r"([\d.]+) s on \d+ thread", p.stdout + p.stderr)
    return wall, float(m.group(1)) if m else float("nan")


# ------------------------------------------------------------------------------------------ coverage


def camera_ray(scene, x: float, y: float, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    """Primary ray through image point (x, y) (pixel centre = +0.5), as runtime_c/tracer_render.c builds it."""
    return camera_rays(scene.camera, w, h, x, y)


def our_mask(scene_path: Path, w: int, h: int, threads: int) -> np.ndarray:
    """Hit-or-not per pixel from our tracer itself: flat white unlit objects, no plane, black background."""
    from implgen.scene.render import render
    from implgen.yamlfile import read_yaml

    raw = read_yaml(scene_path)
    raw["objects"] = [o for o in raw["objects"] if o.get("name") != "ground"]
    for o in raw["objects"]:
        o["material"] = {"color": [1, 1, 1], "ambient": 1.0, "diffuse": 0.0, "specular": 0.0}
        if "shape" in o:
            o["shape"] = str((scene_path.parent / o["shape"]).resolve())
    raw["lights"] = []
    raw["background"] = [0, 0, 0]
    img = render(raw, width=w, height=h, spp=1, threads=threads, max_depth=0)
    return img[..., 0] > 0.5


def pov_mask(png: Path) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(png).convert("L"), dtype=np.uint8) > 127


class PixelJudge:
    """Does the primary ray of a pixel truly hit an object inside its box? The exact judge of the scene's shapes
    (implgen.roots.exactray.ExactJudge: f(o + t d) expanded over Q, t clipped to the object's box as exported with
    `clipped_by`, and the integer Descartes/bisection test on that interval); the ground plane is left out, as
    the coverage masks leave it out."""

    def __init__(self, scene, w: int, h: int):
        self.scene, self.w, self.h = scene, w, h
        leaves = [lf for lf in scene.leaves() if not (lf.spec.degree == 1 and lf.spec.name == "ground")]
        self.exact = ExactJudge([Placed.of(lf.spec, lf.params, lf.matrix) for lf in leaves])

    def hits(self, px: int, py: int) -> bool:
        return self.exact.hits(*camera_ray(self.scene, px + 0.5, py + 0.5, self.w, self.h))


# ------------------------------------------------------------------------------------- degree family


def degree_family(degrees, rays: int, reps: int) -> list[dict]:
    """For each degree n, the dense degree-n surface's generated C timed by bench/c/degree_cost.c (rays rays,
    reps passes): ns per ray for coefficients, solve and total, and the generated code's operation counts."""
    import ctypes

    from implgen.codegen.emit import derivation_ops
    from implgen.resources import runtime_dir

    rt = runtime_dir()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for n in degrees:
            spec, der, lib = build_degree_cost(n, rt, Path(tmp))
            out = (ctypes.c_double * 5)()
            lib.degree_cost.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_ulonglong, ctypes.POINTER(ctypes.c_double)]
            if lib.degree_cost(rays, reps, 12345, out) != 0:
                raise RuntimeError("degree_cost failed")
            rows.append(
                {
                    "degree": spec.degree,
                    "coeffs_ns": out[0],
                    "solve_ns": out[1],
                    "total_ns": out[2],
                    "roots_per_ray": out[3],
                    "hit_fraction": out[4],
                    "ops_coeffs": derivation_ops(der, "coeffs"),
                    "ops_value": derivation_ops(der, "value"),
                    "ops_gradient": derivation_ops(der, "gradient"),
                }
            )
            r = rows[-1]
            print(
                f"  degree {n:2d}: coeffs {r['coeffs_ns']:8.1f} ns  solve {r['solve_ns']:9.1f} ns  "
                f"total {r['total_ns']:9.1f} ns  ops {r['ops_coeffs']}"
            )
    return rows


def build_degree_cost(n: int, rt: Path, tmp: Path):
    """The dense degree-n surface (n/2 offset unit spheres) as a spec, its derivation, and its generated C
    (written into tmp) built with the runtime's roots and shape code and bench/c/degree_cost.c, loaded."""
    from implgen.codegen.derive import derive
    from implgen.codegen.emit import generate
    from implgen.compile import clib as cbuild
    from implgen.measure.gen import dense_equation
    from implgen.spec.entry import parse_spec

    k = n // 2
    name = f"dense{n}"
    bounds = {"x": [-1.2, 0.3 * (k - 1) + 1.2], "y": [-1.2, 0.1 * (k - 1) + 1.2], "z": [-1.2, 1.2]}
    spec = parse_spec({"name": name, "equation": dense_equation(n), "bounds": bounds}, "<bench>")
    der = derive(spec)
    files = generate(spec, ("c",), der)
    for fname, text in files.items():
        (tmp / fname).write_text(text)
    sources = [
        *sorted(p for p in rt.glob("*.c") if p.name.startswith(("roots", "shape")) and p.name != "roots_bench.c"),
        tmp / f"{name}.c",
        ROOT / "bench" / "c" / "degree_cost.c",
    ]
    lib = cbuild.load(
        cbuild.build_shared(sources, include_dirs=[rt, tmp], extra_flags=[f"-DSHAPE_SYM={name}_shape"], tag=f"deg{n}")
    )
    return spec, der, lib


# -------------------------------------------------------------------------------------------- images


def side_by_side(ours: Path, theirs: Path, out: Path, width: int = 800) -> None:
    from PIL import Image, ImageDraw

    a, b = Image.open(ours).convert("RGB"), Image.open(theirs).convert("RGB")
    both = Image.new("RGB", (a.width + b.width, max(a.height, b.height)))
    both.paste(a, (0, 0))
    both.paste(b, (a.width, 0))
    both = both.resize((width, round(width * both.height / both.width)), Image.LANCZOS)
    dr = ImageDraw.Draw(both)
    for x, label in ((6, "implgen"), (width // 2 + 6, "POV-Ray 3.7")):
        dr.rectangle([x - 3, 3, x + 8 * len(label), 17], fill=(0, 0, 0))
        dr.text((x, 5), label, fill=(255, 255, 255))
    both.save(out, optimize=True)


def disagreement_image(ours: np.ndarray, theirs: np.ndarray, out: Path) -> None:
    """Grey: both hit. Black: both miss. Red: only implgen hits. Blue: only POV-Ray hits. Dilated 1 px."""
    from PIL import Image

    img = np.zeros(ours.shape + (3,), np.uint8)
    img[ours & theirs] = (90, 90, 90)
    only_o, only_p = ours & ~theirs, theirs & ~ours

    def grow(m):
        g = m.copy()
        g[1:] |= m[:-1]
        g[:-1] |= m[1:]
        g[:, 1:] |= m[:, :-1]
        g[:, :-1] |= m[:, 1:]  # noqa: E702
        return g

    img[grow(only_o)] = (255, 40, 40)
    img[grow(only_p)] = (60, 140, 255)
    Image.fromarray(img).save(out, optimize=True)


def degree_plot(rows: list[dict], out: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    deg = [r["degree"] for r in rows]
    fig, ax = plt.subplots(figsize=(6.4, 4.0), dpi=100)
    for key, label in (("coeffs_ns", "coefficients"), ("solve_ns", "solve"), ("total_ns", "total (ig_shape_roots)")):
        ax.plot(deg, [r[key] for r in rows], marker="o", label=label)
    ax.set_xlabel("degree of f")
    ax.set_ylabel("ns per ray (1 thread)")
    ax.set_yscale("log")
    ax.set_xticks(deg)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    ax.set_title("Generated C intersector, dense degree-n family")
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)


# ---------------------------------------------------------------------------------------------- main


@dataclass(frozen=True)
class Options:
    """The command line as the run uses it: --runs and the image size settled by --quick, the scenes a list."""

    quick: bool
    out: Path
    runs: int
    w: int
    h: int
    scenes: list[str]
    max_verdicts: int
    edge_checks: int


@dataclass(frozen=True)
class Setup:
    """What every scene shares once the run starts: POV-Ray's executable, where the .pov files go, the thread
    counts timed, and the core count the untimed renders (warm-ups, masks) use."""

    exe: str
    povdir: Path
    ncpu: int
    threads: list[int]


def main(argv=None) -> int:
    """The module docstring's steps: 1-3 for each scene in turn, then 4 and 5."""
    opt = parse_options(argv)
    setup = prepare(opt)
    results = results_header(opt, setup)
    rng = np.random.default_rng(2024)  # which disputed and silhouette pixels are checked exactly
    for name in opt.scenes:
        results["scenes"][name] = compare_scene(name, opt, setup, rng)  # steps 1-3
    results["degree"] = cost_against_degree(opt)  # step 4
    write_outputs(results, opt.out)  # step 5
    return 0


def parse_options(argv) -> Options:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="1 run per timing, 400x300, fewer rays (a smoke test)")
    ap.add_argument("-o", "--out", type=Path, default=ROOT / "bench" / "results" / "povray")
    ap.add_argument("--runs", type=int, default=None, help="timed runs per configuration (default 3, quick 1)")
    ap.add_argument("--max-verdicts", type=int, default=1500, help="exact checks per scene (random sample)")
    ap.add_argument(
        "--edge-checks",
        type=int,
        default=300,
        help="agreed silhouette pixels checked exactly per scene (random sample)",
    )
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated subset of bench/scenes (default: all)")
    args = ap.parse_args(argv)
    scenes = [s for s in args.scenes.split(",") if s]
    unknown = sorted(set(scenes) - set(SCENES))
    if unknown:
        ap.error(f"--scenes: unknown scene(s) {', '.join(unknown)}; choose from {', '.join(SCENES)}")
    w, h = (400, 300) if args.quick else (800, 600)
    return Options(
        quick=args.quick,
        out=args.out.resolve(),
        runs=args.runs or (1 if args.quick else 3),
        w=w,
        h=h,
        scenes=scenes,
        max_verdicts=args.max_verdicts,
        edge_checks=args.edge_checks,
    )


def prepare(opt: Options) -> Setup:
    """The output folders (full-size renders in full/, the exported scenes in pov/), POV-Ray (installed if
    missing), and the thread counts: 1 and all cores."""
    (opt.out / "full").mkdir(parents=True, exist_ok=True)
    povdir = opt.out / "pov"
    povdir.mkdir(exist_ok=True)
    exe = ensure_povray()
    ncpu = os.cpu_count() or 1
    return Setup(exe=exe, povdir=povdir, ncpu=ncpu, threads=[1] if ncpu == 1 else [1, ncpu])


def results_header(opt: Options, setup: Setup) -> dict:
    """results.json before any measurement: the machine, POV-Ray's version and the settings; printed too."""
    results: dict = {
        "machine": machine_info(),
        "povray": povray_version(setup.exe),
        "width": opt.w,
        "height": opt.h,
        "runs": opt.runs,
        "threads": setup.threads,
        "scenes": {},
    }
    print(
        f"POV-Ray {results['povray']}; {results['machine']['cpu']} x{setup.ncpu}; {opt.w}x{opt.h}, "
        f"{opt.runs} run(s) each"
    )
    return results


def compare_scene(name: str, opt: Options, setup: Setup, rng: np.random.Generator) -> dict:
    """Steps 1-3 on one scene: export it to POV-Ray, time both programs, compare their coverage masks."""
    path = ROOT / "bench" / "scenes" / f"{name}.yaml"
    scene = load_scene(path)
    pov, povc = export_scene(scene, name, opt, setup)
    ours_png, pov_png = opt.out / "full" / f"{name}_implgen.png", opt.out / "full" / f"{name}_povray.png"
    timing = time_scene(name, path, pov, ours_png, pov_png, opt, setup)
    side_by_side(ours_png, pov_png, opt.out / f"{name}_side_by_side.png")
    rec: dict = {"degree": max(leaf.spec.degree for leaf in scene.leaves()), "timing": timing}
    rec["coverage"] = compare_coverage(name, path, scene, povc, opt, setup, rng)
    return rec


def export_scene(scene, name: str, opt: Options, setup: Setup) -> tuple[Path, Path]:
    """Step 1: the scene as POV-Ray text, shaded and as a coverage scene (flat white, no plane, no light)."""
    pov, povc = setup.povdir / f"{name}.pov", setup.povdir / f"{name}_coverage.pov"
    pov.write_text(pv.scene_pov(scene, opt.w, opt.h))
    povc.write_text(pv.scene_pov(scene, opt.w, opt.h, coverage=True))
    return pov, povc


def time_scene(name: str, path: Path, pov: Path, ours_png: Path, pov_png: Path, opt: Options, setup: Setup) -> dict:
    """Step 2: one warm-up render each, then both programs timed on each thread count; printed as it goes."""
    run_ours(path, ours_png, opt.w, opt.h, setup.ncpu)  # warm-up: builds and caches the tracer
    run_povray(setup.exe, pov, pov_png, opt.w, opt.h, setup.ncpu)  # warm-up: file cache
    timing = {}
    for th in setup.threads:
        t = time_both(path, pov, ours_png, pov_png, th, opt, setup.exe)
        timing[str(th)] = t
        print(
            f"{name:9s} {th} thread(s): implgen {t['ours_wall']:.3f} s (render {t['ours_render']:.3f}), "
            f"POV-Ray {t['pov_wall']:.3f} s (trace {t['pov_trace']:.3f}) -> POV/implgen "
            f"{t['ratio_wall']:.2f}x wall, {t['ratio_render']:.2f}x render"
        )
    return timing


def time_both(path: Path, pov: Path, ours_png: Path, pov_png: Path, th: int, opt: Options, exe: str) -> dict:
    """--runs runs of each program on `th` threads, interleaved so both see the same machine load: the
    medians of wall clock and of each program's own figure, and POV-Ray / implgen ratios of both."""
    o_wall, o_own, p_wall, p_own = [], [], [], []
    for _ in range(opt.runs):
        a, b = run_ours(path, ours_png, opt.w, opt.h, th)
        o_wall.append(a)
        o_own.append(b)
        a, b = run_povray(exe, pov, pov_png, opt.w, opt.h, th)
        p_wall.append(a)
        p_own.append(b)
    t = {
        "ours_wall": statistics.median(o_wall),
        "ours_render": statistics.median(o_own),
        "pov_wall": statistics.median(p_wall),
        "pov_trace": statistics.median(p_own),
        "ours_wall_all": o_wall,
        "pov_wall_all": p_wall,
    }
    t["ratio_wall"] = t["pov_wall"] / t["ours_wall"]
    t["ratio_render"] = t["pov_trace"] / t["ours_render"]
    return t


def compare_coverage(
    name: str, path: Path, scene, povc: Path, opt: Options, setup: Setup, rng: np.random.Generator
) -> dict:
    """Step 3: both coverage masks, the disagreement image, a sample of the disputed pixels decided exactly,
    and a sample of the silhouette pixels both agree on checked the same way; printed too."""
    mo = our_mask(path, opt.w, opt.h, setup.ncpu)
    mask_png = opt.out / "full" / f"{name}_povray_mask.png"
    run_povray(setup.exe, povc, mask_png, opt.w, opt.h, setup.ncpu)
    mp = pov_mask(mask_png)
    dis = np.argwhere(mo != mp)
    disagreement_image(mo, mp, opt.out / f"{name}_disagreement.png")
    sample = dis if len(dis) <= opt.max_verdicts else dis[rng.choice(len(dis), opt.max_verdicts, replace=False)]
    judge = PixelJudge(scene, opt.w, opt.h)
    t0 = time.perf_counter()
    ours_right, pov_right, examples = decide_disputed(judge, sample, mo, mp)
    edge = silhouette(mo)
    nedge, both_wrong = check_agreed_silhouette(judge, edge & (mo == mp), mo, opt.edge_checks, rng)
    c = {
        "edge_checked": int(nedge),
        "edge_both_wrong": int(both_wrong),
        "edge_pixels": int(edge.sum()),
        "pixels": opt.w * opt.h,
        "implgen_hits": int(mo.sum()),
        "povray_hits": int(mp.sum()),
        "disputed": int(len(dis)),
        "disputed_fraction": len(dis) / (opt.w * opt.h),
        "only_implgen": int((mo & ~mp).sum()),
        "only_povray": int((mp & ~mo).sum()),
        "checked": int(len(sample)),
        "implgen_right": ours_right,
        "povray_right": pov_right,
        "check_seconds": time.perf_counter() - t0,  # the disputed and the silhouette checks
        "examples": examples,
    }
    print(
        f"{name:9s} coverage: {c['disputed']} disputed pixels ({100 * c['disputed_fraction']:.3f} %), "
        f"checked {c['checked']}: implgen right on {ours_right}, POV-Ray right on {pov_right} "
        f"({c['check_seconds']:.1f} s); agreed silhouette pixels checked {c['edge_checked']}, "
        f"both wrong on {c['edge_both_wrong']}"
    )
    return c


def decide_disputed(judge: PixelJudge, sample: np.ndarray, mo: np.ndarray, mp: np.ndarray) -> tuple[int, int, list]:
    """Each sampled disputed pixel (row, column) decided exactly: how many implgen's mask has right, how many
    POV-Ray's, and the first five as examples."""
    ours_right = pov_right = 0
    examples = []
    for yy, xx in sample:
        truth = judge.hits(int(xx), int(yy))
        if truth == bool(mo[yy, xx]):
            ours_right += 1
        else:
            pov_right += 1
        if len(examples) < 5:
            examples.append(
                {
                    "x": int(xx),
                    "y": int(yy),
                    "exact_hit": truth,
                    "implgen": bool(mo[yy, xx]),
                    "povray": bool(mp[yy, xx]),
                }
            )
    return ours_right, pov_right, examples


def silhouette(mo: np.ndarray) -> np.ndarray:
    """The pixels of a mask next to (4-neighbours) a pixel of the other value: a hit beside a miss."""
    edge = np.zeros_like(mo)
    edge[1:] |= mo[1:] != mo[:-1]
    edge[:-1] |= mo[1:] != mo[:-1]
    edge[:, 1:] |= mo[:, 1:] != mo[:, :-1]
    edge[:, :-1] |= mo[:, 1:] != mo[:, :-1]
    return edge


def check_agreed_silhouette(
    judge: PixelJudge, agreed: np.ndarray, mo: np.ndarray, n: int, rng: np.random.Generator
) -> tuple[int, int]:
    """A check on the agreement itself: up to n silhouette pixels both programs agree on (mask `agreed`),
    decided exactly; (how many checked, on how many both are wrong)."""
    agreed_edge = np.argwhere(agreed)
    nedge = min(len(agreed_edge), n)
    esample = agreed_edge[rng.choice(len(agreed_edge), nedge, replace=False)] if nedge else agreed_edge[:0]
    both_wrong = sum(judge.hits(int(xx), int(yy)) != bool(mo[yy, xx]) for yy, xx in esample)
    return nedge, both_wrong


def cost_against_degree(opt: Options) -> list[dict]:
    """Step 4: the generated C intersectors of the dense degree-n family timed (n = 2, 4, .., 20), and plotted."""
    print("cost against degree (generated C, dense family):")
    degrees = list(range(2, 21, 2))
    rows = degree_family(degrees, rays=2000 if opt.quick else 20000, reps=3 if opt.quick else 7)
    degree_plot(rows, opt.out / "degree_cost.png")
    return rows


def write_outputs(results: dict, out: Path) -> None:
    """Step 5 (the images are already there): results.json and report.md."""
    (out / "results.json").write_text(json.dumps(results, indent=1))
    write_report(results, out)
    print("wrote", out / "report.md")


def machine_info() -> dict:
    return {
        "cpu": cpu_model(),
        "cores": os.cpu_count(),
        "system": platform.platform(),
        "date": time.strftime("%Y-%m-%d %H:%M:%S %Z"),
        "load_before": os.getloadavg()[0],
    }


def write_report(r: dict, out: Path) -> None:
    """report.md from results.json's dict, section by section; each but the last ends with the blank line before
    the next."""
    lines = [
        *report_title(r),
        *render_time_section(r),
        *speedup_section(r),
        *coverage_section(r),
        *images_section(r),
        *degree_section(r),
        *targets_section(r),
    ]
    (out / "report.md").write_text("\n".join(lines) + "\n")


def report_title(r: dict) -> list[str]:
    m = r["machine"]
    return [
        f"# implgen against POV-Ray {r['povray']}",
        "",
        f"Generated by `bench/povray_compare.py` on {m['date']}: {m['cpu']}, "
        f"{m['cores']} cores, {m['system']}. {r['width']}x{r['height']}, 1 sample, "
        f"median of {r['runs']} interleaved run(s). Load average before the run: "
        f"{m['load_before']:.2f} (other jobs may have shared the CPU).",
        "",
    ]


def render_time_section(r: dict) -> list[str]:
    L = [
        "## Render time",
        "",
        "Wall = the whole subprocess (`implgen render` includes Python start-up and the cached-build lookup; "
        "POV-Ray includes parsing). Render = each program's own figure (implgen's render loop; POV-Ray's "
        '"Trace Time"). Ratio = POV-Ray / implgen (> 1: implgen faster).',
        "",
        "| scene | degree | threads | implgen wall s | POV-Ray wall s | ratio (wall) | implgen render s "
        "| POV-Ray trace s | ratio (render) |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in r["scenes"].items():
        for t in r["threads"]:
            x = s["timing"][str(t)]
            L.append(
                f"| {name} | {s['degree']} | {t} | {x['ours_wall']:.3f} | {x['pov_wall']:.3f} | "
                f"{x['ratio_wall']:.2f}x | {x['ours_render']:.3f} | {x['pov_trace']:.3f} | {x['ratio_render']:.2f}x |"
            )
    return [*L, ""]


def speedup_section(r: dict) -> list[str]:
    """All cores against one (the first and last thread counts), wall clock and each program's own figure."""
    one, allc = str(r["threads"][0]), str(r["threads"][-1])
    L = [
        "## Multi-core speed-up (all cores against one, wall clock)",
        "",
        "| scene | implgen | POV-Ray |",
        "|---|---|---|",
    ]
    for name, s in r["scenes"].items():
        a, b = s["timing"][one], s["timing"][allc]
        L.append(
            f"| {name} | {a['ours_wall'] / b['ours_wall']:.2f}x (render {a['ours_render'] / b['ours_render']:.2f}x) | "
            f"{a['pov_wall'] / b['pov_wall']:.2f}x (trace {a['pov_trace'] / b['pov_trace']:.2f}x) |"
        )
    return [*L, ""]


def coverage_section(r: dict) -> list[str]:
    L = [
        "## Coverage (object hit or not, per pixel)",
        "",
        "Disputed = pixels where one program sees the object and the other does not. Each checked disputed "
        "pixel is decided exactly (ray mapped to object space in rationals, f(o + t d) expanded over Q, t "
        "clipped to the object's box, a real root there decided by Descartes' rule of signs with bisection "
        "on integers: implgen.roots.descartes).",
        "",
        "Silhouette pixels (a hit next to a miss) on which both agree are also sampled and checked the same "
        "way, to test the agreement itself.",
        "",
        "| scene | implgen hits | POV-Ray hits | disputed | % of image | only implgen | only POV-Ray | checked "
        "| implgen right | POV-Ray right | agreed silhouette px checked | both wrong |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, s in r["scenes"].items():
        c = s["coverage"]
        L.append(
            f"| {name} | {c['implgen_hits']} | {c['povray_hits']} | {c['disputed']} | "
            f"{100 * c['disputed_fraction']:.3f} | {c['only_implgen']} | {c['only_povray']} | {c['checked']} | "
            f"{c['implgen_right']} | {c['povray_right']} | {c['edge_checked']} | {c['edge_both_wrong']} |"
        )
    return [*L, ""]


def images_section(r: dict) -> list[str]:
    L = [
        "Images (left implgen, right POV-Ray) and disagreement maps (red: only implgen hits, blue: only "
        "POV-Ray hits, dilated by one pixel to be visible):",
        "",
    ]
    for name in r["scenes"]:
        L += [f"![{name}]({name}_side_by_side.png) ![{name} disagreement]({name}_disagreement.png)", ""]
    return L


def degree_section(r: dict) -> list[str]:
    L = [
        "## Cost against degree",
        "",
        "Generated C for a dense family (product of n/2 offset unit spheres minus 0.01, every monomial present), "
        "timed in C on one thread over rays aimed into the box; ns per ray, median of the passes. "
        "Coefficients = the generated `<name>_coeffs`; solve = `ig_real_roots` on those coefficients over the "
        "clipped interval; total = `ig_shape_roots` (clip, shift, coefficients, solve). Ops = arithmetic "
        "operations of the generated code (`implgen.codegen.emit.derivation_ops`).",
        "",
        "| degree | coeffs ns | solve ns | total ns | roots/ray | ops coeffs | ops value | ops gradient |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for d in r["degree"]:
        L.append(
            f"| {d['degree']} | {d['coeffs_ns']:.1f} | {d['solve_ns']:.1f} | {d['total_ns']:.1f} | "
            f"{d['roots_per_ray']:.2f} | {d['ops_coeffs']} | {d['ops_value']} | {d['ops_gradient']} |"
        )
    return [*L, "", "![cost against degree](degree_cost.png)", ""]


def targets_section(r: dict) -> list[str]:
    return ["## Targets", "", *(f"- {line}" for line in targets(r))]


def targets(r: dict) -> list[str]:
    out = []
    for name, s in r["scenes"].items():
        x = s["timing"]["1"]
        need = 5.0 if s["degree"] >= 6 else 2.0
        ok_w, ok_r = x["ratio_wall"] >= need, x["ratio_render"] >= need
        out.append(
            f"{name} (degree {s['degree']}), 1 thread, at least {need:g}x faster: wall {x['ratio_wall']:.2f}x "
            f"{'MET' if ok_w else 'MISSED'}; render-only {x['ratio_render']:.2f}x {'MET' if ok_r else 'MISSED'}"
        )
    for name, s in r["scenes"].items():
        c = s["coverage"]
        ours_wrong, pov_wrong = c["povray_right"], c["implgen_right"]
        verdict = (
            "MET" if ours_wrong < pov_wrong else ("TIE (not strictly met)" if ours_wrong == pov_wrong else "MISSED")
        )
        out.append(
            f"{name}: disputed pixels checked {c['checked']}; implgen wrong on {ours_wrong}, POV-Ray wrong on "
            f"{pov_wrong}: fewer disagreements with the exact reference {verdict}"
        )
    return out


if __name__ == "__main__":
    sys.exit(main())
