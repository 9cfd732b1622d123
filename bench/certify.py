"""Certified pixels (docs/certify.md): certified answers against the exact judge, the pixels not certified per
degree, and what `--certify` costs against the plain render.

    .venv/bin/python bench/certify.py [--pixels 2000] [--disputed 3000] [--runs 5] [--scenes a,b]
        [-o bench/results/certify.md]
        [--base-python /work/main/.venv/bin/python]

Scenes: the POV-Ray comparison's (bench/scenes/*.yaml) and the examples (examples/scenes/*.yaml). For each:
  1. judge: --pixels pixels drawn at random at the scene's own size, each centre ray certified (rt_certify_ray) and
     every certified answer decided exactly (implgen.measure.certcheck, implgen.roots.exactray); scenes with CSG
     objects are not judged (the exact judge knows leaves only; their CSG pixels are never certified anyway);
     1b. the pixels POV-Ray disputes (bench/povray_compare.py's disagreement pictures; at most --disputed a
     scene, drawn at random), judged the same way;
  2. per degree: the whole certify map at the scene's own size, 1 sample; per degree of the object a pixel's code
     is about, its pixels and those not certified;
  3. cost: --runs times, one render context each, the plain render (rt_render_run) then the certify pass
     (rt_render_certify) on all cores, at the scene's own size and samples; medians, and the ratio
     (render + certify) / render;
  4. with --base-python: the plain render of a few scenes timed by the base checkout's implgen and by this one,
     alternately, one thread (the plain render must not slow down).
Every figure comes from this one run; the machine and the load average before and after head the file.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from implgen.measure.certcheck import check_pixels, sample_pixels
from implgen.measure.machine import describe, load_average, write_results
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene
from implgen.scene.model import Leaf
from implgen.scene.render import usable_cores
from implgen.scene.renderjob import RenderJob
from implgen.scene.tracer import CScene

ROOT = Path(__file__).resolve().parents[1]
POVRAY = sorted((ROOT / "bench" / "scenes").glob("*.yaml"))
EXAMPLES = sorted((ROOT / "examples" / "scenes").glob("*.yaml"))
TIMED_BASE = ("torus", "heart", "chmutov", "glassware")


def _degree(node) -> int:
    return node.spec.degree if isinstance(node, Leaf) else max(_degree(node.left), _degree(node.right))


def judge(sc, cs, pixels: int) -> dict:
    """Step 1: certified answers of a sample of centre rays against the exact judge."""
    if any(not isinstance(n, Leaf) for n in sc.objects):
        return {"judged": None}
    got = check_pixels(sc, cs, sc.width, sc.height, sample_pixels(sc.width, sc.height, pixels, seed=1))
    return {"judged": got.judged, "wrong": len(got.wrong), "sampled": pixels, "counts": got.counts}


def disputed(name: str, sc, cs, most: int) -> dict | None:
    """Step 1b: the pixels bench/povray_compare.py found disputed with POV-Ray (its disagreement picture's red and
    blue, dilated by a pixel: a superset), all of them or a random `most` of them, judged as in step 1."""
    from PIL import Image

    png = ROOT / "bench" / "results" / "povray" / f"{name}_disagreement.png"
    if not png.exists():
        return None
    with Image.open(png) as im:
        rgb = np.asarray(im.convert("RGB")).astype(int)
    if rgb.shape[:2] != (sc.height, sc.width):
        return None
    flagged = (rgb[..., 0] == 255) | (rgb[..., 2] == 255)
    ys, xs = np.nonzero(flagged)
    pix = np.stack([xs, ys], axis=1)
    if len(pix) > most:
        pix = pix[np.random.default_rng(2).choice(len(pix), size=most, replace=False)]
    got = check_pixels(sc, cs, sc.width, sc.height, pix)
    return {"flagged": int(flagged.sum()), "checked": len(pix), "judged": got.judged, "wrong": len(got.wrong)}


def per_degree(sc, cs) -> dict[int, list[int]]:
    """Step 2: per degree, [pixels, not certified] over the whole certify map at 1 sample."""
    with RenderJob(cs, sc.width, sc.height, 1, 0, usable_cores()) as job:
        codes, objects = job.certify()
    degrees = np.array([_degree(n) for n in sc.objects])
    out: dict[int, list[int]] = {}
    about = objects >= 0
    for deg in sorted(set(degrees.tolist())):
        mine = about & (degrees[np.clip(objects, 0, None)] == deg)
        out[deg] = [int(mine.sum()), int((mine & (codes > 1)).sum())]
    return out


def cost(sc, cs, runs: int) -> dict:
    """Step 3: the plain render and the certify pass, run by run in one context each; medians and the ratio."""
    plain, cert = [], []
    for _ in range(runs):
        with RenderJob(cs, sc.width, sc.height, sc.spp, sc.max_depth, usable_cores()) as job:
            job.run()
            job.certify()
            plain.append(job.seconds)
            cert.append(job.certify_seconds)
    p, c = statistics.median(plain), statistics.median(cert)
    return {"render": p, "certify": c, "ratio": (p + c) / p}


BASE_SNIPPET = """
import sys
from implgen.scene.render import RenderInfo, render
info = RenderInfo()
render(sys.argv[1], threads=1, info=info)
print(info.seconds)
"""


def base_timing(base_python: str, runs: int) -> list[tuple[str, float, float]]:
    """Step 4: the plain render, one thread, by the base checkout's Python and this one, alternately."""
    rows = []
    for name in TIMED_BASE:
        path = next(p for p in POVRAY + EXAMPLES if p.stem == name)
        times: dict[str, list[float]] = {"base": [], "this": []}
        for k in range(runs):
            order = ("base", "this") if k % 2 == 0 else ("this", "base")
            for who in order:
                exe = base_python if who == "base" else sys.executable
                out = subprocess.run([exe, "-c", BASE_SNIPPET, str(path)], capture_output=True, text=True, check=True)
                times[who].append(float(out.stdout.strip().splitlines()[-1]))
        rows.append((name, statistics.median(times["base"]), statistics.median(times["this"])))
    return rows


def run_scene(path: Path, opt) -> dict:
    sc = load_scene(path)
    cs = CScene(sc, build_scene(sc))
    try:
        t0 = time.perf_counter()
        out = {"judge": judge(sc, cs, opt.pixels), "disputed": disputed(path.stem, sc, cs, opt.disputed)}
        out["judge_seconds"] = time.perf_counter() - t0
        out["degree"] = per_degree(sc, cs)
        out["cost"] = cost(sc, cs, opt.runs)
        out["size"] = f"{sc.width}x{sc.height}, {sc.spp} spp"
    finally:
        cs.close()
    print(f"{path.stem}: {out}", flush=True)
    return out


def report(results: dict, base_rows, load_before: str, load_after: str, opt) -> str:
    lines = [
        "# Certified pixels: exact agreement, pixels not certified, cost",
        "",
        f"Machine: {describe()}. Load average before: {load_before}; after: {load_after}.",
        f"Command: `.venv/bin/python bench/certify.py --pixels {opt.pixels} --disputed {opt.disputed} --runs {opt.runs}"
        + (f" --base-python {opt.base_python}`." if opt.base_python else "`."),
        "",
        "## Certified answers against the exact judge",
        "",
        "| scene | pixels sampled | certified, judged | judged wrong |",
        "|---|---|---|---|",
    ]
    for name, r in results.items():
        j = r["judge"]
        if j["judged"] is None:
            lines.append(f"| {name} | - | not judged (CSG objects) | - |")
        else:
            lines.append(f"| {name} | {j['sampled']} | {j['judged']} | {j['wrong']} |")
    lines += _disputed_table(results)
    lines += _degree_table(results) + _cost_table(results) + _base_table(base_rows)
    return "\n".join(lines) + "\n"


def _disputed_table(results: dict) -> list[str]:
    lines = ["", "## Pixels POV-Ray disputes (bench/results/povray's disagreement pictures, dilated by 1 px)", ""]
    lines += ["| scene | flagged | checked | certified, judged | judged wrong |", "|---|---|---|---|---|"]
    for name, r in results.items():
        d = r.get("disputed")
        if d is not None:
            lines.append(f"| {name} | {d['flagged']} | {d['checked']} | {d['judged']} | {d['wrong']} |")
    return lines


def _degree_table(results: dict) -> list[str]:
    lines = ["", "## Pixels not certified, per degree (whole maps, 1 sample, POV-Ray comparison scenes)", ""]
    lines += ["| degree | object pixels | not certified | fraction |", "|---|---|---|---|"]
    total: dict[int, list[int]] = {}
    for name, r in results.items():
        if not any(p.stem == name for p in POVRAY):
            continue
        for deg, (n, bad) in r["degree"].items():
            row = total.setdefault(deg, [0, 0])
            row[0] += n
            row[1] += bad
    for deg in sorted(total):
        n, bad = total[deg]
        lines.append(f"| {deg} | {n} | {bad} | {100.0 * bad / max(n, 1):.3f} % |")
    lines += ["", "Per scene and degree: " + "; ".join(f"{k} {v['degree']}" for k, v in results.items()) + "."]
    return lines


def _cost_table(results: dict) -> list[str]:
    lines = ["", "## Cost of --certify (medians, all cores, scene's own size and samples)", ""]
    lines += ["| scene | size | render s | certify pass s | (render + certify) / render |", "|---|---|---|---|---|"]
    for name, r in results.items():
        c = r["cost"]
        lines.append(f"| {name} | {r['size']} | {c['render']:.3f} | {c['certify']:.3f} | {c['ratio']:.2f} |")
    return lines


def _base_table(rows) -> list[str]:
    if not rows:
        return []
    lines = ["", "## The plain render, base checkout against this one (one thread, medians)", ""]
    lines += ["| scene | base s | this s | this / base |", "|---|---|---|---|"]
    lines += [f"| {n} | {b:.3f} | {t:.3f} | {t / b:.3f} |" for n, b, t in rows]
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pixels", type=int, default=2000)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--disputed", type=int, default=3000, help="at most this many disputed pixels a scene")
    ap.add_argument("--scenes", default="", help="comma-separated scene names (default: all)")
    ap.add_argument("--base-python", help="the Python of a base checkout's venv, to time its plain render")
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "bench" / "results" / "certify.md")
    opt = ap.parse_args()
    wanted = {s for s in opt.scenes.split(",") if s}
    paths = [p for p in POVRAY + EXAMPLES if not wanted or p.stem in wanted]
    before = load_average()
    results = {p.stem: run_scene(p, opt) for p in paths}
    base_rows = base_timing(opt.base_python, opt.runs) if opt.base_python else []
    text = report(results, base_rows, before, load_average(), opt)
    write_results(opt.output, text)
    print(text)


if __name__ == "__main__":
    main()
