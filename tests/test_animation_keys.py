"""Keyed values, the animation block and the camera orbit: exact at the keys, the linear and smooth formulas
between them (against values computed by hand in exact rational arithmetic), every frame validated, and
bad keys refused in one line."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from implgen.animation.frames import frames_from_data, parse_range
from implgen.cli import main as cli_main
from implgen.errors import UserError
from implgen.scene.keys import Keyed, parse_keyed
from implgen.scene.load import parse_scene

ROOT = Path(__file__).resolve().parent.parent
SPHERE = str(ROOT / "examples" / "shapes" / "sphere.yaml")  # x^2 + y^2 + z^2 - r^2
TORUS = str(ROOT / "examples" / "shapes" / "torus_y.yaml")


def scene(**over) -> dict:
    data = {
        "animation": {"frames": 48, "fps": 24},
        "image": {"width": 48, "height": 36},
        "camera": {"position": [0, 1, 6], "look_at": [0, 0, 0], "fov": 40},
        "lights": [{"position": [0, 10, 0]}],
        "objects": [{"shape": TORUS, "params": {"a": 1.0, "b": 0.25}}],
    }
    data.update(over)
    return data


# ------------------------------------------------------------------------------------------- the formulas


def test_a_keyed_value_is_exactly_its_key_at_each_key_frame():
    # values whose linear interpolation would not round-trip: the key must be returned, not recomputed
    k = parse_keyed("s", "v", {"keys": {0: 0.1, 7: 0.7, 47: 1e-300}, "ease": "smooth"}, 48)
    assert k.at(0) == 0.1 and k.at(7) == 0.7 and k.at(47) == 1e-300
    assert parse_keyed("s", "v", {"keys": {3: 0.3, 9: 1 / 3}}, 48).at(9) == 1 / 3


def test_holds_before_the_first_key_and_after_the_last():
    k = Keyed(frames=(10, 20), values=(2.0, 5.0))
    assert [k.at(f) for f in (0, 9, 10, 20, 21, 47)] == [2.0, 2.0, 2.0, 5.0, 5.0, 5.0]


def _exact_linear(f0, v0, f1, v1, f):
    s = Fraction(f - f0, f1 - f0)
    return Fraction(v0) + (Fraction(v1) - Fraction(v0)) * s


def _exact_smooth(f0, v0, f1, v1, f):
    s = Fraction(f - f0, f1 - f0)
    return Fraction(v0) + (Fraction(v1) - Fraction(v0)) * (3 * s**2 - 2 * s**3)


@pytest.mark.parametrize("ease, exact", [("linear", _exact_linear), ("smooth", _exact_smooth)])
def test_between_keys_the_ease_formula_holds(ease, exact):
    keys = {0: 0.5, 12: 2.0, 47: -1.25}  # dyadic values: the exact answer is a rational
    k = parse_keyed("s", "v", {"keys": keys, "ease": ease}, 48)
    pairs = [(0, 12), (12, 47)]
    for f in range(48):
        f0, f1 = next((a, b) for a, b in pairs if a <= f <= b)
        want = exact(f0, keys[f0], f1, keys[f1], f)
        # a few roundings of numbers the size of the keys
        assert abs(Fraction(k.at(f)) - want) <= 4 * Fraction(1, 2**53) * (abs(keys[f0]) + abs(keys[f1])), f


def test_hand_computed_values():
    lin = Keyed(frames=(0, 4), values=(1.0, 3.0))
    smooth = Keyed(frames=(0, 4), values=(1.0, 3.0), ease="smooth")
    assert lin.at(1) == 1.5 and lin.at(2) == 2.0 and lin.at(3) == 2.5
    # s = 1/4: 3/16 - 2/64 = 5/32 -> 1 + 2 * 5/32 = 1.3125; s = 1/2: 1/2 -> 2.0; s = 3/4: 27/32 -> 2.6875
    assert smooth.at(1) == 1.3125 and smooth.at(2) == 2.0 and smooth.at(3) == 2.6875


def test_keys_in_any_order_and_integer_values():
    k = parse_keyed("s", "v", {"keys": {40: 4, 0: 0}}, 48)
    assert k.frames == (0, 40) and k.at(10) == 1.0


# ------------------------------------------------------------------------------------------ in a scene


def test_every_kind_of_number_may_be_keyed():
    data = scene(
        camera={"position": [0, 1, {"keys": {0: 6, 47: 8}}], "look_at": [0, 0, 0], "fov": {"keys": {0: 30, 47: 60}}},
        lights=[
            {"position": [0, 10, 0], "intensity": {"keys": {0: 1, 47: 2}}, "color": [1, {"keys": {0: 1, 47: 0}}, 1]}
        ],
        background=[{"keys": {0: 0, 47: 1}}, 0, 0],
        materials={"m": {"color": [1, 1, 1], "reflectivity": {"keys": {0: 0, 47: 1}}}},
        objects=[
            {
                "shape": TORUS,
                "params": {"a": 1.0, "b": {"keys": {0: 0.1, 47: 0.5}}},
                "material": "m",
                "transform": {"rotate": [{"keys": {0: 0, 47: 90}}, 0, 0], "translate": [0, {"keys": {0: 0, 47: 1}}, 0]},
            },
            {"equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": {"keys": {0: 0.5, 47: 1.0}}}},
        ],
    )
    fr = frames_from_data(data, "anim.yaml")
    assert fr.count == 48 and fr.fps == 24 and fr.animated and fr.params_vary
    mid = fr.scene(47)
    assert mid.camera.position == (0.0, 1.0, 8.0) and mid.camera.fov == 60.0
    assert mid.lights[0].color == (2.0, 0.0, 2.0)
    assert mid.background == (1.0, 0.0, 0.0)
    torus, ball = mid.leaves()
    assert torus.params == {"a": 1.0, "b": 0.5} and torus.material.reflectivity == 1.0
    assert torus.matrix[1, 3] == 1.0 and abs(torus.matrix[1, 1]) < 1e-15  # rotated 90 degrees about x
    assert ball.params == {"r": 1.0}
    assert fr.scene(0).leaves()[1].params == {"r": 0.5}
    # the shapes are the same objects on every frame: one library for the whole animation
    assert [leaf.spec for leaf in fr.scene(30).leaves()] == [leaf.spec for leaf in fr.first.leaves()]
    assert fr.scene(30).leaves()[0].spec is fr.first.leaves()[0].spec


def test_a_still_scene_is_one_frame_and_unchanged():
    data = scene()
    del data["animation"]
    fr = frames_from_data(data, "still.yaml")
    assert fr.count == 1 and not fr.animated and fr.scene(0) is fr.first
    assert fr.first.keyed == () and fr.first.leaves()[0].params == parse_scene(data).leaves()[0].params


def test_orbit_follows_the_circle_and_looks_at_its_centre():
    data = scene(camera={"orbit": {"center": [1, 2, 3], "radius": 5, "height": 0.5, "turns": 2}, "fov": 30})
    fr = frames_from_data(data, "orbit.yaml")
    assert fr.animated and fr.first.keyed == ("camera.orbit",)
    for f in (0, 5, 12, 30, 47):
        cam = fr.scene(f).camera
        angle = 2 * math.pi * 2 * f / 48
        want = (1 + 5 * math.sin(angle), 2.5, 3 + 5 * math.cos(angle))
        assert cam.position == pytest.approx(want, abs=1e-12) and cam.look_at == (1.0, 2.0, 3.0)
        assert math.dist(cam.position[::2], (1, 3)) == pytest.approx(5.0, rel=1e-14)
    assert fr.scene(0).camera.position == (1.0, 2.5, 8.0)


def test_frame_ranges():
    assert parse_range("3:7", 48) == range(3, 8)
    assert parse_range("5", 48) == range(5, 6)
    assert parse_range(":2", 48) == range(0, 3) and parse_range("45:", 48) == range(45, 48)
    for bad in ("7:3", "48", "a:b", "1:2:3", ":", "-1:4", "", "9" * 5000, "²:3"):
        with pytest.raises(UserError, match="--frames"):
            parse_range(bad, 48)


# ---------------------------------------------------------------------------------------- bad keys


@pytest.mark.parametrize(
    "patch, fragment",
    [
        (
            {"camera": {"position": [0, 1, 6], "fov": {"keys": {0: 30, 47: 200}}}},
            "camera.fov.keys.47: 200 is outside (0, 179]",
        ),
        ({"camera": {"position": [0, 1, 6], "fov": {"keys": {0: 30, 48: 50}}}}, "camera.fov.keys: frame 48 is outside"),
        ({"camera": {"position": [0, 1, 6], "fov": {"keys": {"x": 30}}}}, "camera.fov.keys: a key is a frame number"),
        ({"camera": {"position": [0, 1, 6], "fov": {"keys": {}}}}, "camera.fov.keys: expected a mapping"),
        ({"camera": {"position": [0, 1, 6], "fov": {"keys": {0: 30}, "ease": "cubic"}}}, "camera.fov.ease: 'cubic'"),
        ({"camera": {"position": [0, 1, 6], "fov": {"keys": {0: 30}, "speed": 1}}}, "camera.fov.speed: unknown key"),
        (
            {"camera": {"position": [0, 1, 6], "fov": {"keys": {0: {"keys": {0: 1}}}}}},
            "camera.fov.keys.0: a key's value",
        ),
        (
            {"camera": {"position": [0, 1, 6], "fov": {"keys": {0: "wide"}}}},
            "camera.fov.keys.0: expected a finite number",
        ),
        (
            {"camera": {"position": [0, 1, 6], "fov": {"keys": {0: float("nan")}}}},
            "camera.fov.keys.0: expected a finite",
        ),
        ({"camera": {"position": {"keys": {0: [0, 1, 6]}}}}, "camera.position: key each of the three numbers"),
        ({"image": {"width": {"keys": {0: 48, 47: 96}}}}, "image.width: cannot be keyed"),
        ({"animation": {"frames": 0}}, "animation.frames: 0 is outside [1, 10000]"),
        ({"animation": {"frames": 10001}}, "animation.frames: 10001 is outside [1, 10000]"),
        ({"animation": {"frames": 4, "fps": 0}}, "animation.fps: 0 is outside (0, 1000]"),
        ({"animation": {"frames": 4, "speed": 2}}, "animation.speed: unknown key"),
        ({"animation": {"fps": 2}}, "animation: missing key 'frames'"),
        ({"animation": [48]}, "animation: expected a mapping"),
        ({"camera": {"orbit": {"radius": 0}}}, "camera.orbit.radius: 0 is outside (0, 1e+09]"),
        ({"camera": {"orbit": {"center": [0, 0, 0]}}}, "camera.orbit: missing key 'radius'"),
        ({"camera": {"orbit": {"radius": 5}, "position": [0, 1, 6]}}, "camera.position: not with camera.orbit"),
        ({"camera": {"orbit": {"radius": 5, "turns": 1e6}}}, "camera.orbit.turns: 1e+06 is outside [-1000, 1000]"),
        # composed checks hold between keys too, and say at which frame they fail
        (
            {"objects": [{"shape": SPHERE, "transform": {"scale": {"keys": {0: -1, 46: 1}}}}]},
            "objects[0].transform.scale: a scale must be at least 1e-06 in size",
        ),
        (
            {"camera": {"position": [{"keys": {0: -2, 20: 2}}, 0, 0], "look_at": [0, 0, 0]}},
            "camera.look_at: must differ from camera.position (at frame 10)",
        ),
        ({"camera": {"position": [0, {"keys": {0: 1, 47: 3}}, 0]}}, "camera.up: must not be zero or parallel"),
    ],
)
def test_bad_keys_are_one_line_naming_the_key(tmp_path, capsys, patch, fragment):
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(scene(**patch)))
    out = tmp_path / "f_%04d.png"
    assert cli_main(["render", str(path), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(f"implgen: error: {path}: "), err
    assert fragment in err, err
    assert list(tmp_path.iterdir()) == [path]  # nothing rendered, nothing written


def test_a_keyed_value_needs_an_animation_block(tmp_path, capsys):
    data = scene(camera={"position": [0, 1, 6], "fov": {"keys": {0: 30}}})
    del data["animation"]
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    assert cli_main(["render", str(path), "-o", str(tmp_path / "o.png")]) == 2
    assert "camera.fov: a keyed value needs an 'animation' block" in capsys.readouterr().err


def test_a_scale_through_zero_is_caught_at_the_frame_it_reaches_zero():
    data = scene(objects=[{"shape": SPHERE, "transform": {"scale": {"keys": {0: -1, 46: 1}}}}])
    with pytest.raises(UserError, match=r"\(at frame 23\)$"):
        frames_from_data(data, "s.yaml")


@pytest.mark.parametrize(
    "args, fragment",
    [
        (["-o", "{d}/f.png"], "-o {d}/f.png: 48 frames to write"),
        (["-o", "{d}/f_%04d_%d.png"], "exactly one %d field"),
        (["-o", "{d}/f_%s.png"], "exactly one %d field"),
        (["-o", "{d}/f_%04d.jpg"], "must end in .png"),
        (["-o", "{d}/x%d/f.png"], "must be in the file name"),
        (["-o", "{d}/a.avi"], "must end in .png or .mp4 or .webm or .gif"),
        (["-o", "{d}/a.mp4", "--width", "47"], "a video needs an even width and height (the image is 47x36)"),
        (["-o", "{d}/f_%d.png", "--frames", "40:50"], "--frames: 40:50: frames must satisfy"),
        (["-o", "{d}/f_%d.png", "--tiles", "37"], "--tiles: 37 is outside [1, 36]"),
        (["-o", "{d}/f_%d.png", "--cluster", "not an address"], "--cluster: 'not an address' is not a scheduler"),
        (["-o", "{d}/f_%d.png", "--local-workers", "2", "--cluster", "tcp://a:1"], "not allowed with argument"),
        (["-o", "{d}/f_%d.png", "--retries", "-1"], "--retries: -1 is outside [0, 100]"),
        (["-o", "{d}/f_%d.png", "--fold"], "--fold: the scene's shape params change"),
    ],
)
def test_bad_render_options_for_animations(tmp_path, capsys, args, fragment):
    data = scene(objects=[{"shape": TORUS, "params": {"b": {"keys": {0: 0.1, 47: 0.3}}}}])
    path = tmp_path / "anim.yaml"
    path.write_text(yaml.safe_dump(data))
    args = [a.replace("{d}", str(tmp_path)) for a in args]
    assert cli_main(["render", str(path), *args, "-q"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and fragment.replace("{d}", str(tmp_path)) in err, err
    assert list(tmp_path.iterdir()) == [path]


# ------------------------------------------------------------------------------ any input: a scene or one line

_leaf = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(10**30), max_value=10**30),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=6),
)
_value = st.recursive(
    _leaf,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.dictionaries(st.one_of(st.sampled_from(["keys", "ease", "0", "axis"]), _leaf), inner, max_size=4),
        st.fixed_dictionaries(
            {"keys": st.dictionaries(st.one_of(st.integers(-3, 60), _leaf), inner, max_size=4)},
            optional={"ease": st.one_of(st.sampled_from(["linear", "smooth"]), _leaf)},
        ),
    ),
    max_leaves=12,
)
_where = st.sampled_from(["fov", "position", "b", "transform", "rotate", "intensity", "frames", "orbit"])


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(where=_where, value=_value, frames=st.one_of(st.integers(-2, 6), _leaf))
def test_any_keyed_input_is_a_scene_or_a_user_error(where, value, frames):
    data = scene(animation={"frames": frames})
    if where == "fov":
        data["camera"]["fov"] = value
    elif where == "position":
        data["camera"]["position"] = [0, value, 6]
    elif where == "b":
        data["objects"][0]["params"]["b"] = value
    elif where == "transform":
        data["objects"][0]["transform"] = value
    elif where == "rotate":
        data["objects"][0]["transform"] = {"rotate": [value, 0, value]}
    elif where == "intensity":
        data["lights"][0]["intensity"] = value
    elif where == "orbit":
        data["camera"] = {"orbit": {"radius": value, "turns": value}}
    else:
        data["animation"] = value
    try:
        fr = frames_from_data(data, "fuzz.yaml")
    except UserError as err:
        assert "\n" not in str(err)
        return
    for f in range(fr.count):
        sc = fr.scene(f)
        assert all(math.isfinite(v) for leaf in sc.leaves() for v in leaf.params.values())
        assert 0 < sc.camera.fov <= 179


def test_objects_without_keys_are_parsed_once_and_shared_by_every_frame():
    data = scene(
        camera={"position": [0, 1, {"keys": {0: 6, 47: 8}}]},
        objects=[
            {"equation": "x^2 + y^2 + z^2 - 1", "transform": {"translate": [2, 0, 0]}},
            {"equation": "x^2 + y^2 + z^2 - r^2", "params": {"r": {"keys": {0: 0.5, 47: 1}}}},
            {"shape": SPHERE, "transform": {"translate": [-2, 0, 0]}},
        ],
    )
    fr = frames_from_data(data, "s.yaml")
    a, b = fr.scene(0), fr.scene(30)
    assert b.objects[0] is a.objects[0] and b.objects[2] is a.objects[2]  # no keyed value: shared
    assert b.objects[1] is not a.objects[1] and b.objects[1].params["r"] > a.objects[1].params["r"]
    # the inline shapes keep their names and identity on every frame
    assert [leaf.spec.name for leaf in b.leaves()] == ["inline1", "inline2", "sphere"]
    assert all(x.spec is y.spec for x, y in zip(a.leaves(), b.leaves()))
    # a keyed named material makes every object depend on the frame
    data["materials"] = {"m": {"reflectivity": {"keys": {0: 0, 47: 1}}}}
    data["objects"][0]["material"] = "m"
    fr = frames_from_data(data, "s.yaml")
    assert fr.scene(30).objects[0].material.reflectivity == pytest.approx(30 / 47)


def test_the_frames_times_keyed_objects_limit_is_checked_before_the_frames():
    keyed = {"shape": SPHERE, "transform": {"translate": [0, {"keys": {0: 0, 1: 1}}, 0]}}
    data = scene(animation={"frames": 1000}, objects=[keyed] * 101)
    with pytest.raises(UserError, match=r"1000 frames of 101 keyed objects is more than 100,000 keyed object-frames"):
        frames_from_data(data, "s.yaml")
    data = scene(animation={"frames": 1000}, objects=[keyed] * 2)  # 2,000 keyed object-frames: fine
    assert frames_from_data(data, "s.yaml").count == 1000
