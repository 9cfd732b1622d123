"""The generated GLSL against the C solvers and the exact judge, ray by ray: the tests' and
bench/glsl_compare.py's measurement.

A case is a grid of rays (a camera's pixels, or any rays), each rounded to float32 once: that float ray is
what all three answer for. The GLSL runs in headless Chromium (implgen.measure.webgl) and writes, per ray, its
status bits (IG_HIT, IG_UNSURE), t and the number of shape evaluations; the C side is the generated
intersector's `first_hit` (the runtime's clip, shift and first-root solver, in double); every ray where the two
disagree, and every ray the GLSL flagged, is decided exactly (implgen.roots.exactray). Where the GLSL and C
agree and the GLSL did not flag, C's answer stands (a sample of such silhouette pixels is judged too).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from implgen.codegen.backends.glsl.printer import glsl_name
from implgen.codegen.backends.glsl.program import program, shape_defines
from implgen.codegen.emit import generate
from implgen.roots import exactray
from implgen.scene.camera import camera_rays as scene_camera_rays
from implgen.scene.model import Camera

IG_HIT, IG_UNSURE, IG_EARLIER = 1, 2, 4

RAY_MAIN = """
uniform highp sampler2D ig_test_orig; // xyz: origin, w: tmin
uniform highp sampler2D ig_test_dir;  // xyz: direction, w: tmax
out vec4 ig_test_out;

void main()
{
    ivec2 px = ivec2(gl_FragCoord.xy);
    vec4 o = texelFetch(ig_test_orig, px, 0);
    vec4 d = texelFetch(ig_test_dir, px, 0);
    float t;
    vec3 n;
    int status = IG_SHAPE_HIT(o.xyz, d.xyz, o.w, d.w, t, n);
    ig_test_out = vec4(float(status), t, float(ig_ray_steps), length(n));
}
"""


@dataclass
class Case:
    """Rays at one shape: float32 origins and directions (h, w, 3), and the working interval (h, w)."""

    label: str
    spec: object
    params: dict[str, float]
    origins: np.ndarray
    dirs: np.ndarray
    tmin: np.ndarray
    tmax: np.ndarray

    @property
    def size(self) -> tuple[int, int]:
        return self.origins.shape[1], self.origins.shape[0]


def camera_rays(eye, look_at, up, fov: float, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Pixel-centre rays as runtime_c/tracer_render.c builds them (double, implgen.scene.camera), (h, w, 3);
    row 0 is the top row."""
    w_px, h_px = size
    ys, xs = np.mgrid[0:h_px, 0:w_px] + 0.5
    cam = Camera(position=tuple(map(float, eye)), look_at=tuple(map(float, look_at)), up=tuple(map(float, up)), fov=fov)
    eye, d = scene_camera_rays(cam, w_px, h_px, xs, ys)
    return np.broadcast_to(eye, d.shape).copy(), d


def sphere_interval(o: np.ndarray, d: np.ndarray, centre, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """[tmin, tmax] of t >= 0 inside the sphere, in double; tmin > tmax where the ray misses it."""
    oc = o - np.asarray(centre, float)
    dd = (d * d).sum(-1)
    tm = -(oc * d).sum(-1) / dd
    q = oc + tm[..., None] * d
    h2 = radius * radius - (q * q).sum(-1)
    half = np.sqrt(np.maximum(h2, 0.0) / dd)
    t0, t1 = np.maximum(tm - half, 0.0), tm + half
    miss = (h2 < 0) | (t1 < t0)
    return np.where(miss, 1.0, t0), np.where(miss, 0.0, t1)


def make_case(label: str, spec, o, d, tmin=0.0, tmax=np.inf, params=None) -> Case:
    """A case from double rays (..., 3) laid out as an image (h, w, 3): everything rounded to float32 once."""
    o, d = np.asarray(o, float), np.asarray(d, float)
    shape = np.broadcast_shapes(o.shape, d.shape)
    f32 = lambda a, s: np.ascontiguousarray(np.broadcast_to(np.asarray(a, float), s), np.float32)  # noqa: E731
    params = dict(spec.params if params is None else params)
    return Case(label, spec, params, f32(o, shape), f32(d, shape), f32(tmin, shape[:-1]), f32(tmax, shape[:-1]))


def glsl_text(spec) -> str:
    return generate(spec, ("glsl",))[f"{spec.name}.glsl"]


def run_glsl(gl, case: Case, defines: dict[str, str] | None = None, band: int = 32) -> dict:
    """The generated GLSL over the case's rays in the browser: status, t, steps per ray, and draw time (ms)."""
    prefix = glsl_name(case.spec.name)
    dialect = getattr(gl, "dialect", "es")  # implgen.measure.glslegl's desktop GL takes GLSL 4.50
    frag = program([glsl_text(case.spec)], RAY_MAIN, dialect, {**shape_defines(prefix), **(defines or {})})
    orig = np.concatenate([case.origins, case.tmin[..., None]], -1)
    dirs = np.concatenate([case.dirs, case.tmax[..., None]], -1)
    uniforms = {f"{prefix}_params": list(case.params.values())} if case.params else {}
    out, ms = gl.run(frag, case.size, uniforms, orig, dirs, band)
    status = out[..., 0].astype(np.int32)
    return {"status": status, "t": out[..., 1], "steps": out[..., 2].astype(np.int32), "ms": ms}


def python_module(spec) -> ModuleType:
    text = generate(spec, ("python",))[f"{spec.name}.py"]
    module = ModuleType(f"_glslcheck_{spec.name}")
    exec(compile(text, f"<generated {spec.name}.py>", "exec"), module.__dict__)  # noqa: S102 -- our own output
    return module


def run_c(case: Case) -> np.ndarray:
    """The C solvers' nearest root per ray (double, through the generated first_hit); inf on a miss."""
    module = python_module(case.spec)
    o = case.origins.astype(float).reshape(-1, 3)
    d = case.dirs.astype(float).reshape(-1, 3)
    t = module.first_hit(o, d, case.tmin.astype(float).ravel(), case.tmax.astype(float).ravel(), **case.params)
    return np.asarray(t).reshape(case.tmin.shape)


class Judge:
    """Exact verdicts for single rays of a case (implgen.roots.exactray), with the C side's padded box."""

    def __init__(self, case: Case) -> None:
        self.case = case
        self.shape = exactray.Placed.of(case.spec, case.params)

    def __call__(self, row: int, col: int) -> bool:
        c = self.case
        return self.shape.meets(c.origins[row, col], c.dirs[row, col], c.tmin[row, col], c.tmax[row, col])


@dataclass
class Comparison:
    label: str
    degree: int
    pixels: int
    object_pixels: int  # where the exact answer is a hit (C's answer where nobody was judged)
    glsl_hits: int
    c_hits: int
    flagged: int  # IG_UNSURE: the hit or miss is a guess
    earlier: int  # IG_EARLIER: a certain hit, with an undecided stretch before t
    disagree: int
    judged: int
    sampled: bool  # the judged pixels were a sample of the disputed and flagged ones: counts extrapolated
    glsl_wrong: float
    glsl_wrong_unflagged: float
    c_wrong: float
    flagged_right: float
    silhouette_checked: int = 0
    silhouette_both_wrong: int = 0
    steps_mean: float = 0.0
    steps_max: int = 0
    t_rel_err_median: float = 0.0
    t_rel_err_max: float = 0.0
    ms: float = 0.0
    examples: list = field(default_factory=list)

    @property
    def wrong_share(self) -> float:
        return self.glsl_wrong / max(self.object_pixels, 1)


def silhouette(mask: np.ndarray) -> np.ndarray:
    edge = np.zeros_like(mask)
    for axis in (0, 1):
        diff = np.diff(mask, axis=axis) != 0
        lo = [slice(None)] * 2
        hi = [slice(None)] * 2
        lo[axis], hi[axis] = slice(None, -1), slice(1, None)
        edge[tuple(lo)] |= diff
        edge[tuple(hi)] |= diff
    return edge


def compare(
    case: Case, glsl: dict, c_t: np.ndarray, max_judged: int = 4000, silhouette_checks: int = 0, seed: int = 1
) -> Comparison:
    """Counts over the case (see the module docstring); judged pixels beyond max_judged are sampled."""
    rng = np.random.default_rng(seed)
    hit = (glsl["status"] & IG_HIT) != 0
    unsure = (glsl["status"] & IG_UNSURE) != 0
    chit = np.isfinite(c_t)
    disputed = np.argwhere((hit != chit) | unsure)
    sampled = len(disputed) > max_judged
    pick = disputed[rng.choice(len(disputed), max_judged, replace=False)] if sampled else disputed
    judge = Judge(case)
    scale = len(disputed) / max(len(pick), 1)
    glsl_wrong = glsl_wrong_unflagged = c_wrong = flagged_right = 0
    truth_minus_c = 0
    examples = []
    for r, c in pick:
        truth = judge(int(r), int(c))
        g, cc, u = bool(hit[r, c]), bool(chit[r, c]), bool(unsure[r, c])
        glsl_wrong += g != truth
        glsl_wrong_unflagged += (g != truth) and not u
        c_wrong += cc != truth
        flagged_right += u and g == truth
        truth_minus_c += int(truth) - int(cc)
        if g != truth and len(examples) < 5:
            examples.append({"row": int(r), "col": int(c), "exact": truth, "glsl": g, "c": cc, "unsure": u})
    both_checked = both_wrong = 0
    if silhouette_checks:
        agreed = np.argwhere(silhouette(chit) & (hit == chit) & ~unsure)
        take = agreed[rng.choice(len(agreed), min(silhouette_checks, len(agreed)), replace=False)]
        both_checked = len(take)
        both_wrong = sum(judge(int(r), int(c)) != bool(chit[r, c]) for r, c in take)
    both = hit & chit & (glsl["status"] == IG_HIT)  # certified hits with nothing undecided before them
    rel = np.abs(glsl["t"][both] - c_t[both]) / np.maximum(np.abs(c_t[both]), 1e-30)
    return Comparison(
        label=case.label,
        degree=case.spec.degree,
        pixels=hit.size,
        object_pixels=int(chit.sum() + round(truth_minus_c * scale)),
        glsl_hits=int(hit.sum()),
        c_hits=int(chit.sum()),
        flagged=int(unsure.sum()),
        earlier=int(((glsl["status"] & IG_EARLIER) != 0).sum()),
        disagree=int((hit != chit).sum()),
        judged=len(pick),
        sampled=sampled,
        glsl_wrong=glsl_wrong * scale,
        glsl_wrong_unflagged=glsl_wrong_unflagged * scale,
        c_wrong=c_wrong * scale,
        flagged_right=flagged_right * scale,
        silhouette_checked=both_checked,
        silhouette_both_wrong=int(both_wrong),
        steps_mean=float(glsl["steps"].mean()),
        steps_max=int(glsl["steps"].max()),
        t_rel_err_median=float(np.median(rel)) if rel.size else 0.0,
        t_rel_err_max=float(rel.max()) if rel.size else 0.0,
        ms=float(glsl["ms"]),
        examples=examples,
    )
