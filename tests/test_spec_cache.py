"""The parsed-spec cache (spec/cache.py): a cached scene loads and renders without SymPy, gives the same
values and pictures as a full parse, refuses bad specs exactly as before, and survives any damaged entry."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from implgen.errors import UserError
from implgen.scene import build
from implgen.scene.load import parse_scene
from implgen.scene.render import render
from implgen.spec import cache as speccache
from implgen.spec.entry import load_spec
from implgen.spec.entry import parse_spec as parse_full

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "examples" / "shapes"
BENCH_SCENES = ROOT / "bench" / "scenes"
HEAVY = ("sympy", "matplotlib", "tqdm", "dask", "distributed", "imageio", "starlette", "uvicorn", "jinja2")
# A still needs none of the batch or Dask side of `implgen render` (asyncio alone costs a cached still a third
# of its start-up): animation/command.py imports them only for frames, tiles or Dask.
HEAVY += ("asyncio", "implgen.animation.cluster", "implgen.animation.batch")


@pytest.fixture
def cache(tmp_path: Path, monkeypatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("IMPLGEN_CACHE", str(folder))
    return folder


def scene_with(objects: list) -> dict:
    return {
        "image": {"width": 24, "height": 18, "spp": 1, "max_depth": 3},
        "camera": {"position": [0, 2, 6], "look_at": [0, 0.5, 0], "fov": 40},
        "lights": [{"position": [2, 8, 4]}],
        "objects": objects,
    }


TORUS = {"shape": str(SHAPES / "torus_y.yaml"), "params": {"a": 1.1}, "transform": {"translate": [0, 0.5, 0]}}
INLINE = {"equation": "y + 0.25*x", "name": "tilted", "bounds": {"x": [-3, 3], "y": [-2, 2], "z": [-3, "a"]}}
INLINE["params"] = {"a": 2}


def entries(cache: Path) -> list[Path]:
    return sorted((cache / "spec").glob("*.json")) if (cache / "spec").exists() else []


def test_second_load_is_cached_and_equal_to_a_full_parse(cache: Path) -> None:
    first = parse_scene(scene_with([TORUS, INLINE]), "s.yaml")
    assert all(not leaf.spec.symbolic_part.deferred for leaf in first.leaves())
    assert len(entries(cache)) == 2
    second = parse_scene(scene_with([TORUS, INLINE]), "s.yaml")
    for a, b in zip(first.leaves(), second.leaves()):
        assert b.spec.symbolic_part.deferred
        full = a.spec
        assert (b.spec.name, b.spec.equation, b.spec.degree, b.spec.description) == (
            full.name,
            full.equation,
            full.degree,
            full.description,
        )
        assert list(b.spec.params.items()) == list(full.params.items())
        assert [type(v) for v in b.spec.params.values()] == [type(v) for v in full.params.values()]
        assert b.spec.box() == full.box() and b.spec.box(b.params) == full.box(b.params)
        assert b.spec.spec_key == full.spec_key
        assert b.params == a.params and b.spec.source == full.source
        # what the entry does not hold comes from a full parse of the same content
        assert b.spec.f == full.f and b.spec.bounds == full.bounds
        other = {"a": 3.0} if "a" in full.params else None
        assert b.spec.box(other) == full.box(other)
    # folding goes through the full spec too
    folded = build.plan_shapes(second, fold=True)[0]
    reference = build.plan_shapes(first, fold=True)[0]
    assert [e.spec.spec_key for e in folded] == [e.spec.spec_key for e in reference]


def test_a_spec_file_and_the_same_content_share_one_entry(cache: Path) -> None:
    path = SHAPES / "heart.yaml"
    load_spec(path, cache=True)
    cached = load_spec(path, cache=True)
    assert cached.symbolic_part.deferred and cached.source == str(path)
    full = load_spec(path)
    assert cached.spec_key == full.spec_key and cached.equation == full.equation and cached.written == full.written


def test_content_types_are_part_of_the_key(cache: Path) -> None:
    base = {"name": "ball", "equation": "x^2 + y^2 + z^2 - r^2"}
    for value in (1, 1.0, "1"):
        speccache.parse_cached({**base, "params": {"r": value}}, "<a>")
    assert len(entries(cache)) == 3
    for value in (1, 1.0, "1"):
        got = speccache.parse_cached({**base, "params": {"r": value}}, "<a>")
        want = parse_full({**base, "params": {"r": value}}, "<a>")
        assert got.symbolic_part.deferred
        assert got.params == want.params and type(got.params["r"]) is type(want.params["r"])


def test_a_new_implgen_misses(cache: Path, monkeypatch) -> None:
    speccache.parse_cached({"name": "plane", "equation": "y"}, "<a>")
    assert speccache.parse_cached({"name": "plane", "equation": "y"}, "<a>").symbolic_part.deferred
    monkeypatch.setattr(speccache, "implgen_fingerprint", lambda: "another implgen")
    assert not speccache.parse_cached({"name": "plane", "equation": "y"}, "<a>").symbolic_part.deferred


def test_the_fingerprint_is_every_source_and_template_in_path_order() -> None:
    """implgen_fingerprint walks the tree with os.walk (a cached start computes it): the same files, names and
    order as pathlib's rglob and sort, written out independently here."""
    import hashlib

    import implgen
    from implgen.resources import templates_dir
    from implgen.spec.fingerprint import implgen_fingerprint

    h = hashlib.sha256()
    pkg = Path(implgen.__file__).resolve().parent
    files = sorted(pkg.rglob("*.py")) + sorted(templates_dir().rglob("*.j2"))
    assert len(files) > 50 and any(p.suffix == ".j2" for p in files)
    for p in files:
        h.update(f"{p.parent.name}/{p.name}".encode() + b"\0" + p.read_bytes())
    assert implgen_fingerprint() == h.hexdigest()


BAD_SPECS = [
    {"name": "b", "equation": "x^2 +"},
    {"name": "int", "equation": "x"},
    {"name": "b", "equation": "x", "params": {"x": 1}},
    {"name": "b", "equation": "x", "bounds": {"x": [1, 0]}},
    {"name": "b", "equation": "x^30"},
    {"name": "b", "equation": "1"},
    {"name": "b", "equation": "x", "description": ["not text"]},
    {"name": "b", "equation": "x", "params": {1: 2}},
    {"name": "b", "equation": "x", "bounds": {"x": [[[[[[[[[[0]]]]]]]]], 1]}},
]


@pytest.mark.parametrize("bad", BAD_SPECS, ids=range(len(BAD_SPECS)))
def test_bad_specs_are_refused_as_before_and_never_cached(cache: Path, bad: dict) -> None:
    with pytest.raises(UserError) as want:
        parse_full(bad, "<x>")
    for _ in range(2):
        with pytest.raises(UserError) as got:
            speccache.parse_cached(bad, "<x>")
        assert str(got.value) == str(want.value)
    assert entries(cache) == []


def test_a_bad_inline_shape_in_a_scene_says_the_same(cache: Path) -> None:
    bad = scene_with([{"equation": "x^2 + (y", "name": "broken"}])
    messages = []
    for _ in range(2):
        with pytest.raises(UserError) as err:
            parse_scene(bad, "s.yaml")
        messages.append(str(err.value))
    assert messages[0] == messages[1] and "objects[0]" in messages[0] and "equation" in messages[0]


def _damage(entry: Path, how: str) -> None:
    good = json.loads(entry.read_text())
    if how == "garbage":
        entry.write_bytes(os.urandom(300))
    elif how == "empty":
        entry.write_bytes(b"")
    elif how == "truncated":
        entry.write_text(json.dumps(good)[:40])
    elif how == "list":
        entry.write_text("[1, 2, 3]")
    elif how == "nested":
        entry.write_text("[" * 100_000 + "]" * 100_000)
    elif how == "folder":
        entry.unlink()
        entry.mkdir()
    elif how == "fifo":
        entry.unlink()
        os.mkfifo(entry)
    else:
        bad = dict(good)
        if how == "wrong_name":
            bad["name"] = "torus_z"
        elif how == "param_text":
            bad["params"] = [[k, "1.0"] for k, _ in good["params"]]
        elif how == "param_nan":
            bad["params"] = [[k, float("nan")] for k, _ in good["params"]]
        elif how == "missing_param":
            bad["params"] = good["params"][:-1]
        elif how == "degree":
            bad["degree"] = 99
        elif how == "bool_degree":
            bad["degree"] = True
        elif how == "spec_key":
            bad["spec_key"] = "../../etc"
        elif how == "box":
            bad["box"] = [0.0] * 6
        elif how == "extra_key":
            bad["extra"] = 1
        elif how == "other_key":
            bad["key"] = "0" * 64
        elif how == "format":
            bad["format"] = 999
        entry.write_text(json.dumps(bad))


DAMAGE = [
    "garbage",
    "empty",
    "truncated",
    "list",
    "nested",
    "folder",
    "fifo",
    "wrong_name",
    "param_text",
    "param_nan",
    "missing_param",
    "degree",
    "bool_degree",
    "spec_key",
    "box",
    "extra_key",
    "other_key",
    "format",
]


@pytest.mark.parametrize("how", DAMAGE)
def test_a_damaged_entry_is_a_miss_and_the_picture_is_unchanged(cache: Path, how: str) -> None:
    data = scene_with([TORUS])
    reference = render(parse_scene(data, "s.yaml"))  # full parse; writes the entry
    (entry,) = entries(cache)
    assert parse_scene(data, "s.yaml").leaves()[0].spec.symbolic_part.deferred
    _damage(entry, how)
    again = parse_scene(data, "s.yaml")
    assert not again.leaves()[0].spec.symbolic_part.deferred  # not trusted: parsed in full
    assert np.array_equal(render(again), reference)
    if how != "folder":  # written again (a fifo is replaced), and good
        assert parse_scene(data, "s.yaml").leaves()[0].spec.symbolic_part.deferred


def test_a_read_only_cache_still_loads(cache: Path) -> None:
    (cache / "spec").mkdir(parents=True)
    (cache / "spec").chmod(0o500)
    try:
        if os.access(cache / "spec", os.W_OK):  # root ignores the mode
            pytest.skip("cannot make a read-only folder as this user")
        for _ in range(2):
            assert not speccache.parse_cached({"name": "plane", "equation": "y"}, "<a>").symbolic_part.deferred
    finally:
        (cache / "spec").chmod(0o700)


def _run(args: list[str], env: dict, code: str = "") -> subprocess.CompletedProcess:
    script = (
        "import sys\n"
        "from implgen.cli import main\n"
        f"code = main({args!r})\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))\n"
        "sys.exit(code)\n"
    )
    return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=300)


@pytest.mark.parametrize("scene", ["torus.yaml", "heart.yaml"])
def test_a_cached_render_imports_no_sympy(cache: Path, tmp_path: Path, scene: str) -> None:
    env = dict(os.environ, IMPLGEN_CACHE=str(cache))
    outs = [tmp_path / "first.png", tmp_path / "second.png"]
    args = ["render", str(BENCH_SCENES / scene), "-q", "--width", "16", "--height", "12", "--threads", "2"]
    first = _run([*args, "-o", str(outs[0])], env)
    assert first.returncode == 0, first.stderr
    assert "sympy" in first.stdout  # a cold cache parses and generates
    second = _run([*args, "-o", str(outs[1])], env)
    assert second.returncode == 0, second.stderr
    assert second.stdout.strip().splitlines()[-1] == "[]"  # no heavy module at all
    assert outs[0].read_bytes() == outs[1].read_bytes()


POWER = {
    "name": "power",
    "equation": "x^2 + y^2 + z^2 - a^40*b",
    "params": {"a": 1.0, "b": 1.0},
    "bounds": {"x": ["-2*a", "2*a"], "y": [-2, "b^3 - 1 + a"], "z": ["-(a + b)^2", 3]},
}


@pytest.mark.parametrize(
    "values",
    [
        {},
        {"a": 1.5},
        {"a": 1e9},  # a^40 = 1e360: the coefficient check
        {"a": 2.0, "b": 1e-300},
        {"a": 0.0},  # a zero param: its terms vanish
        {"a": -1.0},  # the x bounds become empty
        {"a": 1e8, "b": 1e8},  # the y bound leaves the coordinate range
        {"b": -3.0},
    ],
)
def test_a_cached_spec_checks_overrides_as_the_full_spec_does(cache: Path, values: dict) -> None:
    full = speccache.parse_cached(POWER, "p.yaml")
    cached = speccache.parse_cached(POWER, "p.yaml")
    assert not full.symbolic_part.deferred and cached.symbolic_part.deferred

    def outcome(spec):
        try:
            spec.check_values(values, "s.yaml", "objects[0].params")
        except UserError as err:
            return str(err)
        return spec.box(values)

    assert outcome(cached) == outcome(full)
    assert not cached.symbolic_loaded  # decided from the cached terms and bounds trees, without parsing again


def test_bounds_trees_evaluate_as_sympy_does() -> None:
    spec = parse_full(POWER, "p.yaml")
    for a, b in ((1.0, 1.0), (0.3, -2.5), (7.0, 1e-3)):
        for k, pair in spec.bounds.items():
            exact = [float(e.subs({spec.param_symbols[0]: a, spec.param_symbols[1]: b})) for e in pair]
            box = spec.box({"a": a, "b": b})
            i = "xyz".index(k)
            assert box[i] == pytest.approx(exact[0], rel=1e-15) and box[i + 3] == pytest.approx(exact[1], rel=1e-15)
