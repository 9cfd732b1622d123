"""Certified primary rays (docs/certify.md): the error-bounded coefficients against exact ones, the polynomial
certificate on polynomials with known roots, certified pixels of the example and POV-Ray comparison scenes against
the exact judge (implgen.roots.exactray), rays undecidable in double never certified, and `implgen render
--certify` / `render(certify=True)`. bench/certify.py samples 2,000 pixels a scene; here a few hundred."""

from __future__ import annotations

import ctypes
import json
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from PIL import Image

from implgen.cli import main as cli_main
from implgen.measure.cases.extreme import far_torus_rays
from implgen.measure.cases.polys import hard_set
from implgen.measure.cases.reference import exact_roots, reference
from implgen.measure.certcheck import check_pixels, sample_pixels
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene, parse_scene
from implgen.scene.render import render
from implgen.scene.tracer import CScene
from implgen.spec.parse import X, Y, Z, param_symbol

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "examples" / "shapes"
MISS, HIT, TANGENT, SINGULAR, NOISE = 0, 1, 2, 3, 4
NOBOUND, WRONG = 8, 10

_pd = ctypes.POINTER(ctypes.c_double)
ERRFN = ctypes.CFUNCTYPE(ctypes.c_int, _pd, _pd, _pd, _pd, _pd, _pd, _pd)


class IgShape(ctypes.Structure):  # runtime_c/shape.h's ig_shape
    _fields_ = [
        ("name", ctypes.c_char_p),
        ("degree", ctypes.c_int),
        ("nparams", ctypes.c_int),
        ("coeffs", ctypes.c_void_p),
        ("value", ctypes.c_void_p),
        ("gradient", ctypes.c_void_p),
        ("bounds", ctypes.c_void_p),
        ("coeffs_err", ctypes.c_void_p),
    ]


def one_object(obj: dict, **camera) -> dict:
    cam = {"position": [0, 0, 6], "look_at": [0, 0, 0], "fov": 40, **camera}
    return {
        "image": {"width": 40, "height": 30, "spp": 1, "max_depth": 0},
        "camera": cam,
        "objects": [{**obj, "material": {"color": [1, 1, 1]}}],
    }


def cscene(data: dict) -> tuple:
    sc = parse_scene(data, str(ROOT / "tests" / "s.yaml"))
    return sc, CScene(sc, build_scene(sc))


def darr(v):
    return (ctypes.c_double * len(v))(*[float(x) for x in v])


# ------------------------------------------------------------------------------------- coefficient bounds


def exact_coeffs(spec, params, o, d) -> list[Fraction]:
    t = sp.Symbol("t")
    subs = {param_symbol(k): sp.Rational(Fraction(v)) for k, v in params.items()}
    ray = {X: sp.Rational(Fraction(o[0])) + t * sp.Rational(Fraction(d[0]))}
    ray[Y] = sp.Rational(Fraction(o[1])) + t * sp.Rational(Fraction(d[1]))
    ray[Z] = sp.Rational(Fraction(o[2])) + t * sp.Rational(Fraction(d[2]))
    poly = sp.Poly(sp.expand(spec.f.xreplace(subs).xreplace(ray)), t)
    out = [Fraction(0)] * (spec.degree + 1)
    for (k,), c in poly.terms():
        out[k] = Fraction(int(c.p), int(c.q))
    return out


@pytest.mark.parametrize("shape", ["torus_y", "cayley", "heart", "chmutov6"])
def test_error_bounded_coefficients_hold_the_exact_ones(shape):
    """<name>_coeffs_err's balls hold the exact coefficients of f(o + t d), and are not loose beyond reason."""
    sc, cs = cscene(one_object({"shape": str(SHAPES / f"{shape}.yaml")}))
    ig = ctypes.cast(cs.lib.rt_scene_shape(0), ctypes.POINTER(IgShape)).contents
    fn = ERRFN(ig.coeffs_err)
    leaf = sc.objects[0]
    params = darr(list(leaf.params.values()) or [0.0])
    rng = np.random.default_rng(7)
    zero = darr([0, 0, 0])
    for _ in range(20):
        o, d = rng.normal(size=3) * 3, rng.normal(size=3)
        c, e = darr([0] * 25), darr([0] * 25)
        assert fn(darr(o), zero, darr(d), zero, params, c, e) == 1
        for k, exact in enumerate(exact_coeffs(leaf.spec, leaf.params, o, d)):
            assert abs(Fraction(c[k]) - exact) <= Fraction(e[k]), (shape, k)
            assert e[k] <= 1e-12 * max(1.0, abs(c[k]) * 1e3) or e[k] < 1e3 * 2.0**-52 * max(map(abs, c[:25]))


# ------------------------------------------------------------------------------------- the polynomial certificate


@pytest.fixture(scope="module")
def lib():
    return cscene(one_object({"equation": "x^2 + y^2 + z^2 - 1"}))[1].lib


def first_root(lib, coeffs, errs, a, b):
    lo, hi = ctypes.c_double(), ctypes.c_double()
    f = lib.rt_certify_first_root
    f.restype = ctypes.c_int
    f.argtypes = [_pd, _pd, ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_double, _pd, _pd]
    k = f(darr(coeffs), darr(errs), len(coeffs) - 1, a, b, 0.0, 1e-12, ctypes.byref(lo), ctypes.byref(hi))
    return k, lo.value, hi.value


def test_the_first_simple_root_is_isolated(lib):
    """(s - 1)(s - 2)(s + 3) on [0, 5]: the root 1, in an interval that excludes 2; none on [1.5, 1.9]."""
    c = [6.0, -7.0, 0.0, 1.0]  # (s - 1)(s - 2)(s + 3) = s^3 - 7 s + 6
    k, lo, hi = first_root(lib, c, [0.0] * 4, 0.0, 5.0)
    assert k == 1 and lo <= 1.0 <= hi < 2.0 and hi - lo < 1e-6
    assert first_root(lib, c, [0.0] * 4, 1.5, 1.9)[0] == 0


def test_a_double_root_is_never_certified(lib):
    """(s - 1)^2 and (s - 1)^2 (s - 3): no interval holds exactly one simple root at 1."""
    assert first_root(lib, [1.0, -2.0, 1.0], [0.0] * 3, 0.0, 4.0)[0] == -TANGENT
    assert first_root(lib, [-3.0, 7.0, -5.0, 1.0], [0.0] * 4, 0.0, 4.0)[0] == -TANGENT


def test_a_root_hidden_in_the_coefficients_noise_is_not_certified(lib):
    """s^2 - 1 + c0 with |c0| <= 1: the balls hold polynomials with and without a root near 0: undecided."""
    k, _, _ = first_root(lib, [0.0, 0.0, 1.0], [1e-12, 0.0, 0.0], -1.0, 1.0)
    assert k < 0
    assert first_root(lib, [2.0, 0.0, 1.0], [1.0, 0.0, 0.0], -1.0, 1.0)[0] == 0  # s^2 + [1, 3]: no root


# ------------------------------------------------------------------------------------- scenes against the judge

SCENES = [ROOT / "bench" / "scenes" / f"{n}.yaml" for n in ("torus", "torus_far", "heart", "chmutov", "piriform")]
SCENES += [ROOT / "examples" / "scenes" / f"{n}.yaml" for n in ("torus_shadow", "glass_sphere", "piriform_basis")]


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_certified_pixels_agree_with_the_exact_judge(path):
    sc = load_scene(path)
    cs = CScene(sc, build_scene(sc))
    w, h = 160, 120
    got = check_pixels(sc, cs, w, h, sample_pixels(w, h, 150, seed=3))
    assert got.wrong == [] and got.judged >= 140, (got.counts, got.wrong)
    assert WRONG not in got.counts


def test_csg_objects_are_not_certified_where_the_ray_reaches_them():
    sc = load_scene(ROOT / "examples" / "scenes" / "csg_trio.yaml")
    cs = CScene(sc, build_scene(sc))
    got = check_pixels(sc, cs, 80, 60, sample_pixels(80, 60, 120, seed=5))
    assert got.counts.get(NOBOUND, 0) > 0  # the CSG objects' pixels
    for degree, (pixels, uncertified) in got.per_degree.items():
        if degree == 4:  # only CSG objects have degree 4 there
            assert uncertified == pixels


# ------------------------------------------------------------------------------------- undecidable rays


def test_a_ray_tangent_to_a_sphere_is_never_certified():
    """y = 1 touches the unit sphere at (0, 1, 0): (t - 5)^2 exactly, a double root."""
    box = {"x": [-2, 2], "y": [-2, 2], "z": [-2, 2]}
    _, cs = cscene(one_object({"equation": "x^2 + y^2 + z^2 - 1", "bounds": box}))
    code, _ = cs.certify([-5.0, 1.0, 0.0], [1.0, 0.0, 0.0])
    assert code == TANGENT
    code, _ = cs.certify([-5.0, 0.5, 0.0], [1.0, 0.0, 0.0])  # through it: certified
    assert code == HIT
    code, _ = cs.certify([-5.0, 1.5, 0.0], [1.0, 0.0, 0.0])  # beside it: certified miss
    assert code == MISS


def test_a_ray_through_a_node_of_cayleys_cubic_is_never_certified():
    """The node (1, 1, -1) is the first point of the cubic on this ray (f = t'^2 (..) at t = 3, exactly)."""
    _, cs = cscene(one_object({"shape": str(SHAPES / "cayley.yaml")}))
    o, d = [1.0 - 3 * 0.25, 1.0 - 3 * 0.5, -1.0 - 3 * 1.0], [0.25, 0.5, 1.0]
    hit = cs.intersect(o, d)
    code, _ = cs.certify(o, d)
    assert code in (TANGENT, SINGULAR)
    assert hit is None or hit.t > 2.9  # the node is the first point on the ray, as the test means


# ------------------------------------------------------------------------------------- the command and the API


def test_render_certify_writes_the_map_and_the_report(tmp_path, capsys):
    scene = ROOT / "examples" / "scenes" / "torus_shadow.yaml"
    out, cmap, rep = tmp_path / "a.png", tmp_path / "m.png", tmp_path / "r.json"
    args = ["render", str(scene), "-o", str(out), "--width", "64", "--height", "48", "--spp", "2", "-q"]
    assert cli_main([*args, "--certify", str(cmap), "--report", str(rep)]) == 0
    with Image.open(cmap) as im:
        assert im.mode == "L" and im.size == (64, 48)
        codes = np.asarray(im)
    report = json.loads(rep.read_text())
    assert report["reasons"]["0"] == "miss" and report["reasons"]["1"] == "hit"
    counts = np.bincount(codes.ravel(), minlength=len(report["reasons"]))
    assert {report["reasons"][str(k)]: int(n) for k, n in enumerate(counts)} == report["counts"]
    assert sum(sum(v.values()) for v in report["per_object"].values()) == report["pixels"] - report["counts"]["miss"]
    assert report["certified"] > 0.9 * report["pixels"]
    img, cert = render(scene, width=64, height=48, spp=2, certify=True)
    assert np.array_equal(cert.codes, codes) and img.shape == (48, 64, 3)


@pytest.mark.parametrize(
    "extra, word",
    [
        (["--report", "r.json"], "--report"),
        (["--certify", "m.jpg"], "--certify"),
        (["--certify", "m.png", "--report", "r.txt"], "--report"),
        (["--certify", "m.png", "--tiles", "2"], "--certify"),
    ],
)
def test_bad_certify_options_are_one_line_and_exit_2(tmp_path, capsys, monkeypatch, extra, word):
    monkeypatch.chdir(tmp_path)
    scene = ROOT / "examples" / "scenes" / "torus_shadow.yaml"
    assert cli_main(["render", str(scene), "-o", "a.png", "-q", *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and word in err
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------------------------- far rays and hard cases


def certify_roots(lib, c, a, b):
    """rt_certify_roots on the double polynomial c (exact: no error balls) over [a, b]: the count or -code, and
    the intervals."""
    f = lib.rt_certify_roots
    f.restype = ctypes.c_int
    f.argtypes = [_pd, _pd, ctypes.c_int, ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_double]
    f.argtypes += [_pd, _pd, ctypes.POINTER(ctypes.c_int)]
    lo, hi, sign = (ctypes.c_double * 26)(), (ctypes.c_double * 26)(), ctypes.c_int()
    k = f(darr(c), darr([0.0] * len(c)), len(c) - 1, a, b, 0.0, 1e-12, lo, hi, ctypes.byref(sign))
    return k, list(zip(lo[: max(k, 0)], hi[: max(k, 0)]))


def agrees(k, got, want) -> bool:
    """A certified answer lists exactly the reference's real roots on the interval, each simple, in order (the
    exact root where the reference has it: a root next to an end of the interval is on one side of it)."""
    exact = [r.exact if r.exact is not None else r.value for r in want]
    return k == len(want) and all(r.mult == 1 and lo <= x <= hi for (lo, hi), r, x in zip(got, want, exact))


@pytest.mark.parametrize("dist", [1e3, 1e4])
def test_far_torus_rays_without_the_shift_are_certified_by_the_compensated_shift(lib, dist):
    """Torus ray polynomials written at the far origin (no shift): at 1e4 the plain Taylor shift's noise (~u
    |a|^4 |c_4|, about 1) hides every sign, so every one of these was undecided before the compensated shift;
    now each is certified, and every certified answer is exactly the double polynomial's real roots."""
    c, lo, hi = far_torus_rays(60, np.random.default_rng(2), dist)
    ref = reference(c)
    certified = 0
    for i in range(len(c)):
        k, got = certify_roots(lib, c[i], lo[i], hi[i])
        if k >= 0:
            certified += 1
            assert agrees(k, got, [r for r in ref[i] if lo[i] <= r.value <= hi[i]]), (i, k, got)
    assert certified == len(c)


def test_the_hard_set_is_certified_only_where_exactly_right(lib):
    """The solver report's hard polynomials (near-double and quadruple roots once rounded to doubles, clusters,
    spread roots, roots at an end, a tiny minimum) on a finite window: every certified answer is exact."""
    c, lo, hi = hard_set(64, np.random.default_rng(4), n=12)
    certified = 0
    for i in range(len(c)):
        a, b = max(lo[i], -8.0), min(hi[i], 8.0)
        want = [r for r in exact_roots(c[i]) if a <= r.exact <= b]
        k, got = certify_roots(lib, c[i], a, b)
        if k >= 0:
            certified += 1
            assert agrees(k, got, want), (i, k, got, [(r.value, r.mult) for r in want])
    assert certified >= len(c) // 3


def test_a_degree_20_surface_seen_through_its_box_centre_is_certified():
    """The spiky degree-20 surface: expanded about its box's centre, f's terms near the hit are a million times f,
    and pieces cut by de Casteljau alone keep that noise; pieces formed afresh (and the expansion about the
    tracer's root) certify the hit. This ray was `tangent` (not certified) before."""
    sc = load_scene(ROOT / "bench" / "scenes" / "spiky20.yaml")
    cs = CScene(sc, build_scene(sc))
    got = check_pixels(sc, cs, sc.width, sc.height, [(342, 207), (335, 214), (342, 214)])
    assert got.counts == {HIT: 3} and got.wrong == []
