"""Scene limits that keep bad input cheap, and the mechanisms behind them: CSG lists as balanced trees (checked
against analytic sphere hits), YAML aliases counted as expanded, numbers compared exactly, output written
with the umask's mode."""

from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np
import pytest

from implgen import validate
from implgen.cli import main as cli_main
from implgen.errors import UserError
from implgen.scene.build import build_scene
from implgen.scene.load import load_scene, parse_scene
from implgen.scene.model import Csg
from implgen.scene.objects import MAX_CSG_NESTING
from implgen.scene.tracer import CScene
from implgen.yamlfile import MAX_YAML_NODES, read_yaml

ROOT = Path(__file__).resolve().parent.parent
SPHERE = str(ROOT / "examples" / "shapes" / "sphere.yaml")  # x^2 + y^2 + z^2 - r^2, r = 1


def _spheres(n: int, spacing: float = 3.0) -> list[dict]:
    return [{"shape": SPHERE, "transform": {"translate": [spacing * i, 0, 0]}} for i in range(n)]


def _sphere_hit(o, d, centre, r=1.0) -> float:
    """Nearest t > 0 of |o + t d - c| = r (textbook quadratic), inf if none."""
    oc = np.subtract(o, centre)
    a, b, c = np.dot(d, d), 2 * np.dot(oc, d), np.dot(oc, oc) - r * r
    disc = b * b - 4 * a * c
    if disc < 0:
        return math.inf
    roots = sorted(((-b - math.sqrt(disc)) / (2 * a), (-b + math.sqrt(disc)) / (2 * a)))
    return next((t for t in roots if t > 1e-9), math.inf)


# ---------------------------------------------------------------------------------------------- CSG


def test_a_sixty_object_union_is_one_level_and_shallow():
    scene = parse_scene({"objects": [{"union": _spheres(60)}]}, "<t>")
    root = scene.objects[0]
    assert isinstance(root, Csg) and root.depth == 6 and len(scene.leaves()) == 60  # ceil(log2 60)


def test_balanced_union_hits_where_the_nearest_sphere_is():
    scene = parse_scene({"objects": [{"union": _spheres(60)}]}, "<t>")
    cs = CScene(scene, build_scene(scene))
    try:
        rng = np.random.default_rng(7)
        for _ in range(200):
            o = np.array([rng.uniform(-5, 185), rng.uniform(-3, 3), 10.0])
            d = np.array([rng.uniform(-0.5, 0.5), rng.uniform(-0.3, 0.3), -1.0])
            want = min(_sphere_hit(o, d, (3.0 * i, 0, 0)) for i in range(60))
            hit = cs.intersect(o, d)
            if math.isinf(want):
                assert hit is None
            else:
                assert hit is not None and hit.t == pytest.approx(want, rel=1e-12)
    finally:
        cs.close()


def test_difference_list_subtracts_every_later_object():
    """difference [A, B, C] = A - B - C: a ray along x through three overlapping unit spheres enters A, is cut
    by B and C, and comes out of A where the last subtracted sphere ends."""
    scene = parse_scene(
        {
            "objects": [
                {
                    "difference": [
                        {"shape": SPHERE, "transform": {"scale": 2}},
                        {"shape": SPHERE, "transform": {"translate": [-1.5, 0, 0]}},
                        {"shape": SPHERE, "transform": {"translate": [1.5, 0, 0]}},
                    ]
                }
            ]
        },
        "<t>",
    )
    cs = CScene(scene, build_scene(scene))
    try:
        hit = cs.intersect([-10.0, 0, 0], [1.0, 0, 0])  # A from -2, B covers [-2.5, -0.5]: enter at -0.5
        assert hit is not None and hit.t == pytest.approx(9.5, rel=1e-12)
        hit = cs.intersect([-10.0, 0.5, 0], [1.0, 0, 0])  # off axis: B's chord ends at -1.5 + sqrt(0.75)
        assert hit.t == pytest.approx(10 - 1.5 + math.sqrt(0.75), rel=1e-12)
    finally:
        cs.close()


def test_nesting_limit_is_about_nesting_as_written():
    node: dict = {"shape": SPHERE}
    for _ in range(MAX_CSG_NESTING):
        node = {"union": [node, {"shape": SPHERE}]}
    parse_scene({"objects": [node]}, "<t>")  # exactly the limit: fine
    with pytest.raises(UserError, match=f"nested more than {MAX_CSG_NESTING} deep as written"):
        parse_scene({"objects": [{"union": [node, {"shape": SPHERE}]}]}, "<t>")


# --------------------------------------------------------------------------------------- YAML expansion


def _bomb(levels: int) -> str:
    lines = ["objects:", "  - &n0 {equation: 'x^2 + y^2 + z^2 - 1', name: ball}"]
    lines += [f"  - &n{i} {{union: [*n{i - 1}, *n{i - 1}]}}" for i in range(1, levels + 1)]
    return "\n".join(lines) + "\n"


def test_alias_bomb_is_refused_at_once(tmp_path):
    path = tmp_path / "bomb.yaml"
    path.write_text(_bomb(40))
    start = time.perf_counter()
    with pytest.raises(UserError, match=f"more than {MAX_YAML_NODES} values once its aliases are expanded"):
        load_scene(path)
    # a hang guard, not a timing: expanding the 2^40 values would take hours and all the memory there is
    assert time.perf_counter() - start < 10.0


def test_recursive_alias_is_refused(tmp_path):
    path = tmp_path / "loop.yaml"
    path.write_text("objects: &a [*a]\n")
    with pytest.raises(UserError, match="cycle"):
        load_scene(path)


def test_modest_aliases_still_work(tmp_path):
    path = tmp_path / "ok.yaml"
    path.write_text(
        "materials: {m: &m {color: [1, 0, 0]}}\n"
        "objects: [{shape: " + SPHERE + ", material: *m}, {shape: " + SPHERE + ", material: *m}]\n"
    )
    assert len(load_scene(path).leaves()) == 2
    assert read_yaml(path, "scene")["objects"][0]["material"] == {"color": [1, 0, 0]}


def test_yaml_12_floats_are_numbers(tmp_path):
    path = tmp_path / "f.yaml"
    path.write_text("a: [1e-3, 2E6, -.5e1, 1.0e+3, x1e3]\n")
    assert read_yaml(path)["a"] == [0.001, 2e6, -5.0, 1000.0, "x1e3"]


# --------------------------------------------------------------------------------------------- numbers


@pytest.mark.parametrize(
    "value, ok",
    [
        (16384, True),
        (16385, False),
        (10**400, False),
        (-(10**400), False),
        (16384.0, False),
        (True, False),
        ("12", False),
        (float("nan"), False),
    ],
)
def test_whole_numbers_compare_exactly(value, ok):
    if ok:
        assert validate.whole("f", "image.width", value, 1, 16384) == value
    else:
        with pytest.raises(UserError, match="image.width"):
            validate.whole("f", "image.width", value, 1, 16384)


def test_huge_integers_are_refused_without_converting_them():
    with pytest.raises(UserError, match=r"camera.fov: a number of about 1e400 is outside \(0, 179\]"):
        validate.number("f", "camera.fov", 10**400, 0.0, 179.0, lo_open=True)
    assert validate.number("f", "k", 10**9) == 1e9
    with pytest.raises(UserError, match="outside"):
        validate.number("f", "k", 10**9 + 1)


@pytest.mark.parametrize(
    "transform, fragment",
    [
        ({"scale": 1e-7}, "at least 1e-06"),
        ({"scale": 2e6}, "outside"),
        ([{"scale": 1e3}, {"scale": 1e3}, {"scale": 10}], r"stretches by 1e\+07"),
        ({"translate": [2e9, 0, 0]}, "outside"),
        ([{"translate": [9e8, 0, 0]}, {"translate": [9e8, 0, 0]}], r"beyond 1e\+09"),
        ({"axes": [[1, 0, 0], [0, 1, 0], [1, 1, 0]]}, "singular"),
    ],
)
def test_transforms_stay_in_range_once_composed(transform, fragment):
    with pytest.raises(UserError, match=fragment):
        parse_scene({"objects": [{"shape": SPHERE, "transform": transform}]}, "<t>")


def test_csg_node_transform_is_checked_on_the_composed_matrix():
    inner = {"union": [{"shape": SPHERE, "transform": {"scale": 1e3}}, {"shape": SPHERE}], "transform": {"scale": 1e4}}
    with pytest.raises(UserError, match=r"objects\[0\]\.union\[0\]\.transform: the transform stretches"):
        parse_scene({"objects": [inner]}, "<t>")


# ---------------------------------------------------------------------------------------------- output


def test_png_and_generated_files_get_the_umask_mode(tmp_path):
    scene = tmp_path / "s.yaml"
    scene.write_text(f"image: {{width: 8, height: 6}}\nobjects: [{{shape: {SPHERE}}}]\n")
    old = os.umask(0o027)
    try:
        assert cli_main(["render", str(scene), "-o", str(tmp_path / "out.png"), "-q"]) == 0
        assert cli_main([SPHERE, "--lang", "all", "-o", str(tmp_path / "gen"), "-q"]) == 0
    finally:
        os.umask(old)
    assert (tmp_path / "out.png").stat().st_mode & 0o777 == 0o640
    assert {p.stat().st_mode & 0o777 for p in (tmp_path / "gen").iterdir()} == {0o640}
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gen", "out.png", "s.yaml"]  # no temporaries left


def test_output_is_checked_before_any_work(tmp_path, capsys, monkeypatch):
    """The scene is never read when the output cannot be written: a scene that would take long to load
    (a missing file, here) is not even looked at."""
    called = []
    monkeypatch.setattr("implgen.animation.command.load_frames", lambda p: called.append(p))
    (tmp_path / "afile").write_text("")
    for out, fragment in [
        (tmp_path, "is a folder"),
        (tmp_path / "nope" / "o.png", "does not exist"),
        (tmp_path / "afile" / "o.png", "is not a folder"),
        (tmp_path / "o.jpg", "end in .png"),
    ]:
        assert cli_main(["render", str(tmp_path / "missing.yaml"), "-o", str(out)]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and fragment in err and err.startswith("implgen: error: -o "), err
    assert not called


def test_render_option_errors_name_the_option_as_typed(tmp_path, capsys):
    scene = tmp_path / "s.yaml"
    scene.write_text(f"objects: [{{shape: {SPHERE}}}]\n")
    assert cli_main(["render", str(scene), "-o", str(tmp_path / "o.png"), "--max-depth", "999"]) == 2
    assert "--max-depth: 999 is outside [0, 64]" in capsys.readouterr().err


def test_output_folder_is_tried_for_real(tmp_path):
    """Whether a folder takes a new file is decided by creating one, not by its mode bits (root writes into a
    0500 folder; anyone else cannot): the check agrees with what actually happens, and leaves nothing."""
    from implgen.outputs import check_output_file, check_output_folder

    locked = tmp_path / "locked"
    locked.mkdir()
    locked.chmod(0o500)
    try:
        try:
            (locked / "probe").write_text("")
            (locked / "probe").unlink()
            writable = True
        except PermissionError:
            writable = False
        for check in (
            lambda: check_output_folder(locked / "gen", "-o"),
            lambda: check_output_file(locked / "o.png", "-o", (".png",)),
        ):
            if writable:
                check()
            else:
                with pytest.raises(UserError, match="cannot write in"):
                    check()
        assert list(locked.iterdir()) == []
    finally:
        locked.chmod(0o700)


@pytest.mark.parametrize("argv", [["render", "SCENE", "-o", "OUT/o.png"], ["SPEC", "-o", "OUT/gen"]])
def test_output_under_a_link_loop_is_refused_before_work(tmp_path, capsys, argv):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    scene = tmp_path / "s.yaml"
    scene.write_text(f"objects: [{{shape: {SPHERE}}}]\n")
    argv = [a.replace("SCENE", str(scene)).replace("SPEC", SPHERE).replace("OUT", str(tmp_path / "loop")) for a in argv]
    assert cli_main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "is a link to nothing" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["loop", "s.yaml"]


def test_a_write_that_fails_anyway_is_one_line(tmp_path, capsys, monkeypatch):
    """A failure after the checks (a full disk, here simulated) is still one line, exit status 2."""
    import errno

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("implgen.outputs.atomic_write", full)
    assert cli_main([SPHERE, "-o", str(tmp_path / "gen"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "No space left on device" in err and err.startswith("implgen: error: -o ")


# ------------------------------------------------------------------------------------------ YAML keys


def test_merge_keys_are_overridden_by_the_mappings_own_keys(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text(
        "materials:\n"
        "  base: &base {color: [1, 0, 0], diffuse: 0.9, specular: 0.1}\n"
        "  shiny: {<<: *base, specular: 0.8}\n"
        f"objects: [{{shape: {SPHERE}, material: shiny}}, {{shape: {SPHERE}, material: base}}]\n"
    )
    scene = load_scene(path)
    shiny, base = (leaf.material for leaf in scene.leaves())
    assert (shiny.specular, shiny.diffuse, shiny.color) == (0.8, 0.9, (1.0, 0.0, 0.0))
    assert (base.specular, base.diffuse) == (0.1, 0.9)


def test_a_key_given_twice_is_still_refused_next_to_a_merge(tmp_path):
    path = tmp_path / "m.yaml"
    path.write_text("materials:\n  b: &b {diffuse: 0.5}\n  m: {<<: *b, specular: 0.1, specular: 0.2}\n")
    with pytest.raises(UserError, match="duplicate key 'specular'"):
        load_scene(path)


# --------------------------------------------------------------------------------------- counts


def test_ten_thousand_objects_load_and_one_more_is_refused(tmp_path):
    """MAX_OBJECTS leaves (CSG operands count) load, one more is refused naming the object; a spec file used
    by every one of them is looked up once."""
    from implgen.scene import objects

    calls = []
    real = objects._find_spec_file
    path = tmp_path / "many.yaml"
    path.write_text(
        "objects: [" + ", ".join(["&a {shape: " + SPHERE + "}"] + ["*a"] * (objects.MAX_OBJECTS - 1)) + "]\n"
    )
    try:
        objects._find_spec_file = lambda *a: calls.append(a) or real(*a)
        assert len(load_scene(path).leaves()) == objects.MAX_OBJECTS
    finally:
        objects._find_spec_file = real
    assert len(calls) == 1
    path.write_text("objects: [" + ", ".join(["&a {shape: " + SPHERE + "}"] + ["*a"] * objects.MAX_OBJECTS) + "]\n")
    with pytest.raises(UserError, match=rf"objects\[{objects.MAX_OBJECTS}\]: more than {objects.MAX_OBJECTS} objects"):
        load_scene(path)


def test_union_operands_count_as_objects():
    from implgen.scene import objects

    per = 1000
    objs = [{"union": _spheres(per)} for _ in range(objects.MAX_OBJECTS // per)]
    assert len(parse_scene({"objects": objs}, "<t>").leaves()) == objects.MAX_OBJECTS
    with pytest.raises(UserError, match=r"objects\[10\]: more than 10000 objects"):
        parse_scene({"objects": [*objs, {"shape": SPHERE}]}, "<t>")


# ------------------------------------------------------------------------------------------ equations


@pytest.mark.parametrize("text", ["1and y", "1if x else y", "0x1for x", "1or x"])
def test_python_syntax_warnings_are_syntax_errors_and_print_nothing(text, recwarn):
    """Python warns about `1and` (a number run into a keyword); the warning is the syntax error it is, one
    message, and nothing else is printed or warned."""
    from implgen.spec.entry import parse_spec

    with pytest.raises(UserError, match="equation: syntax error|not a polynomial"):
        parse_spec({"name": "s", "equation": text}, "<t>")
    assert not [w for w in recwarn if issubclass(w.category, SyntaxWarning)]


# ------------------------------------------------------------------------------------ param values


def test_param_values_that_overflow_a_coefficient_are_refused():
    """Each param is within range, but a^40 with a = 1e9 is 1e360: refused with the key named. The test is on
    the exact terms (log2 |c| + sum e log2 |p|), so a = 1e9 to the 30th power (2^897) passes, and a zero param
    makes its terms vanish."""
    from implgen.spec.entry import parse_spec

    spec = parse_spec({"name": "p", "equation": "x^2 + y^2 + z^2 - a^30 - b^40", "params": {"a": 1, "b": 1}}, "<t>")
    spec.check_values({"a": 1e9, "b": 0.0}, "<t>", "objects[0].params")
    with pytest.raises(UserError, match=r"objects\[0\].params: with these params a coefficient of shape 'p' reaches"):
        spec.check_values({"a": 1.0, "b": 1e9}, "<t>", "objects[0].params")
    with pytest.raises(UserError, match="params: with these params"):
        parse_spec({"name": "p", "equation": "x - a^40", "params": {"a": 1e9}}, "<t>")


def test_param_values_must_keep_the_bounds_a_box():
    from implgen.spec.entry import load_spec

    torus = load_spec(ROOT / "examples" / "shapes" / "torus_y.yaml")
    torus.check_values({"a": 2.0, "b": 0.5}, "<t>", "k")
    assert torus.box({"a": 2.0, "b": 0.5}) == [-2.5, -0.5, -2.5, 2.5, 0.5, 2.5]
    with pytest.raises(UserError, match="k: with these params the bounds of shape 'torus_y' are empty along y"):
        torus.check_values({"b": -0.5}, "<t>", "k")
    with pytest.raises(UserError, match="leave"):
        torus.check_values({"a": 1e9, "b": 1e9}, "<t>", "k")
