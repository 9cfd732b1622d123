"""A param's slider range (spec/paramrange.py), the one the viewer, its exported page and `implgen share` use: the
spec's own `ranges`, else where the surface stays the same kind, each end passing the spec's checks."""

from __future__ import annotations

import re

import pytest

from conftest import ROOT
from implgen.share.command import main as share_main
from implgen.spec.entry import load_spec, parse_spec
from implgen.spec.paramrange import param_ranges, plain_range
from implgen.view.document import STARTER

SHAPES = sorted((ROOT / "examples" / "shapes").glob("*.yaml"))


def test_the_torus_radii_stay_a_ring_torus() -> None:
    """(a^2 - b^2)^2 vanishes at b = a (the hole closes) and f holds b only squared: b runs from just above 0 (the
    box [-b, b] is empty at 0) to 1; a from b = 0.35 to its mirror 1.65 (it was -0.65..1.35 and 0..2)."""
    ranges = param_ranges(parse_spec(STARTER, "starter"))
    assert ranges == {"a": (0.35, 1.65), "b": (0.004, 1.0)}


@pytest.mark.parametrize(
    "equation, params, expected",
    [
        ("x^2 + y^2 + z^2 - a", {"a": 1}, (0.0, 2.0)),  # a = 0: the ball is gone; a side with none mirrors the other
        ("x^2 + y^2 + z^2 - 1 + k*x", {"k": 0}, plain_range(0)),  # no coefficient vanishes but at k = 0 itself
        ("x^4 - 5*x^2 + y^4 - 5*y^2 + z^4 - 5*z^2 + c", {"c": 11.8}, (0.0, 23.6)),
    ],
)
def test_ranges_run_between_the_values_where_a_coefficient_vanishes(equation, params, expected) -> None:
    spec = parse_spec({"name": "s", "equation": equation, "params": params}, "s")
    assert param_ranges(spec)[next(iter(params))] == pytest.approx(expected)


@pytest.mark.parametrize("path", SHAPES, ids=[p.stem for p in SHAPES])
def test_every_example_range_holds_its_default_and_passes_the_checks_at_both_ends(path) -> None:
    spec = load_spec(path)
    for name, (lo, hi) in param_ranges(spec).items():
        assert lo < hi and lo <= spec.params[name] <= hi
        if name in spec.ranges:
            assert (lo, hi) == spec.ranges[name]  # the spec's own, as declared
        for end in (lo, hi):
            spec.check_values({name: end}, "t", name)


def test_implgen_share_uses_the_same_ranges(tmp_path) -> None:
    out = tmp_path / "torus.html"
    spec_path = tmp_path / "torus.yaml"
    import yaml

    spec_path.write_text(yaml.safe_dump(STARTER))
    assert share_main([str(spec_path), "-o", str(out), "-q"]) == 0
    found = re.findall(r'min="([^"]+)" max="([^"]+)"[^>]*aria-label="(\w+)"', out.read_text())
    assert {n: (float(lo), float(hi)) for lo, hi, n in found} == {"a": (0.35, 1.65), "b": (0.004, 1.0)}
