"""Every example shape against exact rational arithmetic; C against Python; gradients against finite
differences; the checked-in generated/ folder against a fresh generation."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy

from conftest import GENERATED, SHAPE_FILES, SHAPE_NAMES, CShapes, load_python_shape, random_rays
from implgen.codegen.emit import generate
from implgen.spec.entry import load_spec
from implgen.spec.parse import X, Y, Z, param_symbol

EXACT_RAYS = 12


def exact_coefficients(spec, o, d, params) -> list[Fraction]:
    """c_k of f(o + t d) with o, d, params the exact rational values of the doubles (SymPy, no rounding)."""
    t = sympy.Symbol("t")
    q = lambda v: sympy.Rational(Fraction(float(v)))  # noqa: E731
    subs = {param_symbol(k): q(v) for k, v in params.items()}
    ray = {X: q(o[0]) + t * q(d[0]), Y: q(o[1]) + t * q(d[1]), Z: q(o[2]) + t * q(d[2])}
    poly = sympy.Poly(sympy.expand(spec.f.xreplace({**subs, **ray})), t)
    coeffs = [Fraction(int(c.p), int(c.q)) for c in reversed(poly.all_coeffs())]
    return coeffs + [Fraction(0)] * (spec.degree + 1 - len(coeffs))


@pytest.fixture(scope="module")
def all_c() -> CShapes:
    return CShapes(SHAPE_NAMES)


@pytest.mark.parametrize("path", SHAPE_FILES, ids=SHAPE_NAMES)
def test_coefficients_equal_exact_rational_arithmetic(path, rng, all_c):
    spec = load_spec(path)
    module = load_python_shape(spec.name)
    o, d = random_rays(rng, EXACT_RAYS, spread=1.5)
    for i in range(EXACT_RAYS):
        exact = exact_coefficients(spec, o[i], d[i], spec.params)
        scale = max(abs(c) for c in exact)
        py = module.coeffs(o[i], d[i])
        cc = all_c.coeffs(spec.name, spec.degree, o[i], d[i], list(spec.params.values()))
        for got in (py, cc):
            err = max(abs(Fraction(float(g)) - e) for g, e in zip(got, exact)) / scale
            assert err < 1e-12, f"{spec.name} ray {i}: relative error {float(err):.2e}"


@pytest.mark.parametrize("path", SHAPE_FILES, ids=SHAPE_NAMES)
def test_c_and_python_agree(path, rng, all_c):
    spec = load_spec(path)
    module = load_python_shape(spec.name)
    params = list(spec.params.values())
    o, d = random_rays(rng, 200)
    py_c = module.coeffs(o, d)
    c_c = np.array([all_c.coeffs(spec.name, spec.degree, o[i], d[i], params) for i in range(len(o))])
    scale = np.max(np.abs(py_c), axis=-1, keepdims=True)
    assert np.max(np.abs(py_c - c_c) / scale) < 1e-13
    p = o
    values = module.value(p)  # the two sum f's terms in different orders: the difference is relative to them
    assert np.allclose(
        values, [all_c.value(spec.name, q, params) for q in p], rtol=1e-13, atol=1e-13 * np.max(np.abs(values))
    )
    assert np.allclose(
        module.gradient(p),
        [all_c.gradient(spec.name, q, params) for q in p],
        rtol=1e-12,
        atol=1e-12 * np.max(np.abs(module.gradient(p))),
    )
    flag, box = all_c.bounds(spec.name, params)
    if spec.bounds is None:
        assert flag == 0 and module.bounds() is None and np.all(np.isinf(box))
    else:
        assert flag == 1 and np.array_equal(box, module.bounds()) and np.allclose(box, spec.box())


@pytest.mark.parametrize("path", SHAPE_FILES, ids=SHAPE_NAMES)
def test_gradient_matches_exact_central_differences(path, rng):
    """(f(p + h e_i) - f(p - h e_i)) / 2h in exact rational arithmetic, h = 1e-20: off by O(h^2) only."""
    spec = load_spec(path)
    module = load_python_shape(spec.name)
    q = lambda v: sympy.Rational(Fraction(float(v)))  # noqa: E731
    f = spec.f.xreplace({param_symbol(k): q(v) for k, v in spec.params.items()})
    h = sympy.Rational(1, 10**20)
    for p in rng.uniform(-1.2, 1.2, (20, 3)):
        point = [q(v) for v in p]
        want = []
        for axis in range(3):
            hi, lo = list(point), list(point)
            hi[axis] += h
            lo[axis] -= h
            fh = f.xreplace(dict(zip((X, Y, Z), hi)))
            fl = f.xreplace(dict(zip((X, Y, Z), lo)))
            want.append(float((fh - fl) / (2 * h)))
        got = module.gradient(p)
        assert np.allclose(got, want, rtol=1e-12, atol=1e-12 * max(1.0, np.max(np.abs(want))))


@pytest.mark.parametrize("path", SHAPE_FILES, ids=SHAPE_NAMES)
def test_generated_folder_is_up_to_date(path):
    # If this fails, run `make regen` (implgen examples/shapes/*.yaml --lang all -o generated).
    spec = load_spec(path)
    for fname, text in generate(spec).items():
        on_disk = (GENERATED / fname).read_text(encoding="utf-8")
        assert on_disk == text, f"generated/{fname} is stale: run `make regen`"


def test_generation_is_byte_identical_on_rerun(tmp_path):
    """Two runs in processes with different hash seeds (set order differs) write the same bytes."""
    import os
    import subprocess
    import sys

    outs = []
    for seed in ("1", "2"):
        out = tmp_path / seed
        env = {**os.environ, "PYTHONHASHSEED": seed}
        subprocess.run(
            [sys.executable, "-m", "implgen.cli", *map(str, SHAPE_FILES), "-q", "-o", str(out)], check=True, env=env
        )
        outs.append({p.name: p.read_bytes() for p in out.iterdir()})
    assert outs[0] == outs[1]


def runs_to_infinity(spec, rng) -> bool:
    """Whether f's highest-degree part takes both signs on the unit sphere: then the surface has real points at
    infinity, and its box is a window onto it (the gallery's Cayley, Clebsch, Kummer, Barth decic, ...)."""
    f = spec.f.subs({param_symbol(k): sympy.nsimplify(v, rational=True) for k, v in spec.params.items()})
    poly = sympy.Poly(sympy.expand(f), X, Y, Z)
    top = sum(c * X**i * Y**j * Z**k for (i, j, k), c in poly.terms() if i + j + k == poly.total_degree())
    u = rng.normal(size=(3, 20000))
    values = sympy.lambdify((X, Y, Z), top, "numpy")(*(u / np.linalg.norm(u, axis=0)))
    return bool(np.min(values) < 0 < np.max(values))


def test_bounding_boxes_enclose_the_surfaces(rng):
    """Every root found along axis-parallel lines through a big region lies inside the spec's box (for a surface
    that does not run off to infinity)."""
    windows = []
    for path in SHAPE_FILES:
        spec = load_spec(path)
        if spec.bounds is None:
            continue
        if runs_to_infinity(spec, rng):
            windows.append(spec.name)
            continue
        module = load_python_shape(spec.name)
        box = np.array(spec.box())
        for axis in range(3):
            o = rng.uniform(-3, 3, (400, 3))
            o[:, axis] = 0.0
            d = np.zeros_like(o)
            d[:, axis] = 1.0
            for oi, ci in zip(o, module.coeffs(o, d)):
                roots = np.roots(ci[::-1]) if np.any(ci[1:]) else []
                for r in roots:
                    if abs(r.imag) < 1e-7:
                        p = oi + r.real * np.eye(3)[axis]
                        assert np.all(p >= box[:3] - 1e-6) and np.all(p <= box[3:] + 1e-6), (spec.name, p)
    assert {"cayley", "kummer", "barth10", "whitney"} <= set(windows) and "heart" not in windows
