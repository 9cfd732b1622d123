"""Bad scenes and `implgen render` options, run as the user runs them (tests/bad_input_harness.py): each exits
with status 2 and one line naming the file (and key) or the option as typed, writes nothing, compiles and runs
nothing, within 5 s and 300 MB.

Classes: numbers (huge integers, NaN, inf, ranges), combined overflow (light colour x intensity, composed
scales and translations), material ranges, alias bombs, CSG list size and nesting, object and shape counts,
structure, inline equations (injection, reserved names), files given as `shape:` that are not specs, the scene
path itself (a folder, a fifo, a device), the output path, and options named as typed.
"""

from __future__ import annotations

import pytest

from bad_input_harness import FIFO, FOLDER, SPHERE, Case, Link, check, run_batch

BIG = "9" * 400
TORUS = SPHERE.replace("sphere.yaml", "torus_y.yaml")
OBJ = f"objects: [{{shape: {SPHERE}}}]\n"
LEAF = f"{{shape: {SPHERE}}}"


def scene(case_id: str, text: str | bytes, fragment: str, files: dict | None = None) -> Case:
    return Case(case_id, ["render", "s.yaml", "-o", "out.png", "-q"], fragment, {"s.yaml": text, **(files or {})})


def top(case_id: str, yaml_line: str, fragment: str) -> Case:
    """A good scene with one more top-level line."""
    return scene(case_id, yaml_line + "\n" + OBJ, fragment)


def leaf(case_id: str, extra: str, fragment: str) -> Case:
    """One sphere with `extra` keys on it."""
    return scene(case_id, f"objects: [{{shape: {SPHERE}, {extra}}}]\n", fragment)


def material(case_id: str, body: str, fragment: str) -> Case:
    return scene(case_id, f"materials: {{m: {{{body}}}}}\n" + OBJ, fragment)


def objects(case_id: str, body: str, fragment: str) -> Case:
    return scene(case_id, f"objects: {body}\n", fragment)


def render(case_id: str, options: list[str], fragment: str, names: str) -> Case:
    return Case(case_id, ["render", "s.yaml", "-o", "out.png", "-q", *options], fragment, {"s.yaml": OBJ}, names=names)


def union(n: int) -> str:
    return "[" + ", ".join([LEAF] * n) + "]"


def nested(levels: int) -> str:
    node = LEAF
    for _ in range(levels):
        node = f"{{union: [{node}, {LEAF}]}}"
    return node


CASES: list[Case] = []

# ---------------------------------------------------------------------------------- image and camera
CASES += [
    top("width-huge", f"image: {{width: {BIG}}}", "image.width: a number of about 1e400 is outside [1, 16384]"),
    top("width-zero", "image: {width: 0}", "image.width: 0 is outside [1, 16384]"),
    top("width-above", "image: {width: 16385}", "image.width: 16385 is outside"),
    top("width-float", "image: {width: 64.5}", "image.width: expected a whole number"),
    top("width-text", "image: {width: '64'}", "image.width: expected a whole number, not '64'"),
    top("width-bool", "image: {width: true}", "image.width: expected a whole number, not true"),
    top("height-negative", f"image: {{height: -{BIG}}}", "image.height: a negative number of about 1e400"),
    top("spp-zero", "image: {spp: 0}", "image.spp: 0 is outside"),
    top("spp-huge", "image: {spp: 100000000}", "image.spp"),
    top("max-depth-negative", "image: {max_depth: -1}", "image.max_depth: -1 is outside"),
    top("max-depth-above", "image: {max_depth: 65}", "image.max_depth: 65 is outside"),
    top("image-unknown-key", "image: {widht: 10}", "image.widht: unknown key"),
    top("image-list", "image: [64, 48]", "image: expected a mapping"),
    top("image-empty-list", "image: []", "image: expected a mapping"),
    top("camera-zero", "camera: 0", "camera: expected a mapping"),
    top("lights-zero", "lights: 0", "lights: expected a list"),
    top("lights-false", "lights: false", "lights: expected a list"),
    top("materials-empty-text", "materials: ''", "materials: expected a mapping"),
    top("width-over-4300-digits", "image: {width: " + "9" * 5000 + "}", "a number is written with more than 4300"),
    top("fov-zero", "camera: {fov: 0}", "camera.fov: 0 is outside (0, 179]"),
    top("fov-180", "camera: {fov: 180}", "camera.fov: 180 is outside"),
    top("fov-huge", f"camera: {{fov: {BIG}}}", "camera.fov: a number of about 1e400"),
    top("fov-nan", "camera: {fov: .nan}", "camera.fov: expected a finite number, not nan"),
    top("fov-inf-text", "camera: {fov: '1e999'}", "camera.fov: expected a finite number"),
    top("camera-same-point", "camera: {position: [1, 2, 3], look_at: [1, 2, 3]}", "camera.look_at: must differ"),
    top("camera-up-parallel", "camera: {position: [0, 5, 0], look_at: [0, 0, 0], up: [0, 1, 0]}", "camera.up"),
    top("camera-up-zero", "camera: {up: [0, 0, 0]}", "camera.up: must not be zero"),
    top("camera-position-far", "camera: {position: [2e9, 0, 0]}", "camera.position[0]: 2e+09 is outside"),
    top("camera-position-two", "camera: {position: [0, 1]}", "camera.position: expected a list of three numbers"),
    top("camera-position-inf", "camera: {position: [.inf, 0, 0]}", "camera.position[0]: expected a finite number"),
    top("camera-position-1e400", "camera: {position: [1e400, 0, 0]}", "camera.position[0]: expected a finite"),
    top("background-negative", "background: [-0.1, 0, 0]", "background[0]: -0.1 is outside [0, 100]"),
    top("background-huge", f"background: [{BIG}, 0, 0]", "background[0]: a number of about 1e400"),
    top("background-text", "background: blue", "background: expected a list of three numbers"),
]

# ------------------------------------------------------------------------------ lights (combined overflow)
CASES += [
    top("light-colour-above", "lights: [{position: [0, 5, 0], color: [101, 1, 1]}]", "lights[0].color[0]: 101"),
    top("light-intensity-above", "lights: [{position: [0, 5, 0], intensity: 1e5}]", "lights[0].intensity: 100000"),
    top(
        "light-colour-times-intensity",
        "lights: [{position: [0, 5, 0], color: [1e308, 1e308, 1e308], intensity: 1e308}]",
        "lights[0].color[0]: 1e+308 is outside [0, 100]",
    ),
    top("light-intensity-negative", "lights: [{position: [0, 5, 0], intensity: -1}]", "lights[0].intensity: -1"),
    top("light-intensity-nan", "lights: [{position: [0, 5, 0], intensity: .nan}]", "lights[0].intensity"),
    top("light-no-position", "lights: [{intensity: 1}]", "lights[0]: missing key 'position'"),
    top("light-position-huge", f"lights: [{{position: [0, {BIG}, 0]}}]", "lights[0].position[1]"),
    top("light-unknown-key", "lights: [{position: [0, 5, 0], colour: [1, 1, 1]}]", "lights[0].colour: unknown key"),
    top("lights-mapping", "lights: {a: 1}", "lights: expected a list"),
    top("light-not-mapping", "lights: [[0, 5, 0]]", "lights[0]: expected a mapping"),
]

# ---------------------------------------------------------------------------------------- materials
CASES += [
    material("ambient-negative", "ambient: -0.1", "materials.m.ambient: -0.1 is outside [0, 100]"),
    material("diffuse-above", "diffuse: 101", "materials.m.diffuse: 101 is outside"),
    material("specular-1e308", "specular: 1e308", "materials.m.specular: 1e+308 is outside"),
    material("shininess-above", "shininess: 1e5", "materials.m.shininess: 100000 is outside [0, 10000]"),
    material("reflectivity-above", "reflectivity: 1.5", "materials.m.reflectivity: 1.5 is outside [0, 1]"),
    material("transparency-negative", "transparency: -0.5", "materials.m.transparency"),
    material("ior-zero", "ior: 0", "materials.m.ior: 0 is outside (0, 10]"),
    material("ior-above", "ior: 11", "materials.m.ior: 11 is outside"),
    material("ior-huge", f"ior: {BIG}", "materials.m.ior: a number of about 1e400"),
    material("absorption-above", "absorption: [1e7, 0, 0]", "materials.m.absorption[0]: 1e+07 is outside"),
    material("absorption-nan", "absorption: [0, .nan, 0]", "materials.m.absorption[1]: expected a finite"),
    material("colour-above", "color: [1, 1, 101]", "materials.m.color[2]: 101 is outside"),
    material("colour-text", "color: red", "materials.m.color: expected a list of three numbers"),
    material("checker-one-colour", "checker: {colors: [[1, 1, 1]]}", "materials.m.checker.colors: expected two"),
    material("checker-scale-zero", "checker: {colors: [[1, 1, 1], [0, 0, 0]], scale: 0}", "checker.scale: 0 is"),
    material("checker-unknown", "checker: {colors: [[1, 1, 1], [0, 0, 0]], size: 2}", "checker.size: unknown key"),
    material("material-unknown-key", "gloss: 1", "materials.m.gloss: unknown key"),
    scene("material-name-long", f"materials: {{{'m' * 65}: {{}}}}\n" + OBJ, "is not a material name"),
    scene("material-name-number", "materials: {1: {}}\n" + OBJ, "materials: 1 is not a material name"),
    scene("material-name-control", 'materials: {"a\\x1b[2J": {}}\n' + OBJ, "is not a material name"),
    scene("materials-list", "materials: [a, b]\n" + OBJ, "materials: expected a mapping"),
    leaf("material-missing", "material: nope", "objects[0].material: no material named 'nope'"),
    leaf("material-number", "material: 12", "objects[0].material: expected a mapping"),
]

# ------------------------------------------------------------------------------------------- transforms
CASES += [
    leaf("scale-zero", "transform: {scale: 0}", "objects[0].transform.scale: a scale must be at least 1e-06"),
    leaf("scale-above", "transform: {scale: 2e6}", "objects[0].transform.scale: 2e+06 is outside"),
    leaf("scale-huge", f"transform: {{scale: {BIG}}}", "objects[0].transform.scale: a number of about 1e400"),
    leaf("scale-nan", "transform: {scale: .nan}", "objects[0].transform.scale: expected a finite number"),
    leaf(
        "scale-cubed",
        "transform: [{scale: 1e6}, {scale: 1e6}, {scale: 1e6}]",
        "objects[0].transform: the transform stretches by 1e+12",
    ),
    leaf("scale-shrink-composed", "transform: [{scale: 1e-4}, {scale: 1e-4}]", "shrinks to 1e-08"),
    leaf("translate-composed", "transform: [{translate: [9e8, 0, 0]}, {translate: [9e8, 0, 0]}]", "beyond 1e+09"),
    leaf("translate-huge", f"transform: {{translate: [{BIG}, 0, 0]}}", "objects[0].transform.translate[0]"),
    leaf("rotate-huge", f"transform: {{rotate: [{BIG}, 0, 0]}}", "objects[0].transform.rotate[0]"),
    leaf("rotate-two", "transform: {rotate: [0, 0]}", "objects[0].transform.rotate: expected a list of three"),
    leaf("rotate-axis-zero", "transform: {rotate: {axis: [0, 0, 0], angle: 10}}", "rotate.axis: must not be zero"),
    leaf("rotate-axis-no-angle", "transform: {rotate: {axis: [0, 0, 1]}}", "rotate: expected {axis"),
    leaf("axes-singular", "transform: {axes: [[1, 0, 0], [0, 1, 0], [1, 1, 0]]}", "the transform is singular"),
    leaf("axes-two", "transform: {axes: [[1, 0, 0], [0, 1, 0]]}", "transform.axes: expected three vectors"),
    leaf("position-without-axes", "transform: {position: [0, 0, 0]}", "'position' needs 'axes'"),
    leaf("axes-with-scale", "transform: {axes: [[1, 0, 0], [0, 1, 0], [0, 0, 1]], scale: 2}", "transform.scale"),
    leaf("transform-unknown", "transform: {shear: 1}", "transform.shear: unknown key"),
    leaf("transform-text", "transform: big", "objects[0].transform: expected a mapping"),
    leaf("transform-nested-list", "transform: [[{scale: 2}]]", "objects[0].transform[0]: expected a mapping"),
    objects(
        "csg-transform-composed",
        f"[{{union: [{{shape: {SPHERE}, transform: {{scale: 1e3}}}}, {LEAF}], transform: {{scale: 1e4}}}}]",
        "objects[0].union[0].transform: the transform stretches",
    ),
]

# ------------------------------------------------------------------------------- alias and size bombs
_BOMB = "".join(f"  - &n{i} {{union: [*n{i - 1}, *n{i - 1}]}}\n" for i in range(1, 41))
_TBOMB = "".join(f"t{i}: &t{i} [*t{i - 1}, *t{i - 1}]\n" for i in range(1, 41))
CASES += [
    scene("alias-bomb-csg", f"objects:\n  - &n0 {LEAF}\n" + _BOMB, "more than 100000 values once its aliases"),
    scene(
        "alias-bomb-transform",
        "x:\n  t0: &t0 {scale: 1}\n" + "".join(f"  t{i}: &t{i} [*t{i - 1}, *t{i - 1}]\n" for i in range(1, 41)) + OBJ,
        "more than 100000 values",
    ),
    scene(
        "alias-bomb-materials",
        "materials: {m0: &m0 {color: [1, 1, 1]}"
        + "".join(f", m{i}: &m{i} {{checker: {{colors: [*m{i - 1}, *m{i - 1}]}}}}" for i in range(1, 30))
        + "}\n"
        + OBJ,
        "more than 100000 values",
    ),
    scene("alias-cycle", "objects: &a [*a]\n", "cycle"),
    scene("alias-cycle-mapping", "materials: &m {m: *m}\n" + OBJ, "cycle"),
    scene(
        "merge-key-bomb",
        "m0: &m0 {a: 1, b: 2}\n"
        + "".join(f"m{i}: &m{i} {{<<: *m{i - 1}, l{i}: [*m{i - 1}, *m{i - 1}]}}\n" for i in range(1, 30))
        + OBJ,
        "more than 100000 values",
    ),
    scene(
        "objects-over-10000-counted",
        "objects: [" + ", ".join(["&a " + LEAF] + ["*a"] * 10000) + "]\n",
        "objects[10000]: more than 10000 objects in one scene",
    ),
    scene(
        "shapes-over-256",
        "objects: [" + ", ".join(f"{{equation: 'x^2 + y^2 + z^2 - {i}'}}" for i in range(1, 258)) + "]\n",
        "objects[256].equation: more than 256 distinct shapes",
    ),
    scene("deep-flow-nesting", "objects: " + "[" * 2000 + "]" * 2000 + "\n", "invalid YAML"),
    scene("huge-file", OBJ + "# " + "x" * (1 << 20) + "\n", "larger than 1048576 bytes"),
]

# Keyed values: 1,000 keys shared by eight transforms, checked on each of 2,000 frames; the last frame takes the
# composed translation past 1e9. Each key used to be parsed and checked again on every frame (minutes).
_KEYS = ", ".join([f"{i}: 0" for i in range(0, 1999, 2)] + ["1999: 9.0e8"])
_KEYED_LEAF = f"{{shape: {SPHERE}, transform: [{{translate: [*k, 0, 0]}}, {{translate: [*k, 0, 0]}}]}}"
CASES += [
    scene(
        "animation-many-keys-many-frames",
        "animation: {frames: 2000}\nobjects: ["
        + ", ".join([_KEYED_LEAF.replace("*k", f"&k {{keys: {{{_KEYS}}}}}", 1)] + [_KEYED_LEAF] * 3)
        + "]\n",
        "objects[0].transform: the transform moves the object beyond 1e+09 (at frame 1999)",
    ),
    top("animation-keyed-without-block", "camera: {fov: {keys: {0: 30, 5: 40}}}", "needs an 'animation' block"),
    top("animation-frames-zero", "animation: {frames: 0}", "animation.frames: 0 is outside [1, 10000]"),
    top("animation-frames-huge", f"animation: {{frames: {BIG}}}", "animation.frames: a number of about 1e400"),
    top("animation-key-outside", "animation: {frames: 4}\ncamera: {fov: {keys: {9: 30}}}", "frame 9 is outside"),
    top("animation-key-range", "animation: {frames: 4}\ncamera: {fov: {keys: {0: 30, 3: 200}}}", "fov.keys.3: 200"),
    top("animation-ease", "animation: {frames: 4}\ncamera: {fov: {keys: {0: 30}, ease: bounce}}", "is not one of"),
    top("animation-nested-keys", "animation: {frames: 4}\ncamera: {fov: {keys: {0: {keys: {0: 1}}}}}", "not another"),
    top("animation-keyed-width", "animation: {frames: 4}\nimage: {width: {keys: {0: 8}}}", "cannot be keyed"),
    scene(
        "animation-scale-through-zero",
        f"animation: {{frames: 5}}\nobjects: [{{shape: {SPHERE}, transform: {{scale: {{keys: {{0: -1, 4: 1}}}}}}}}]\n",
        "(at frame 2)",
    ),
]

# ----------------------------------------------------------------------------------------------- CSG
CASES += [
    objects("union-one-child", f"[{{union: [{LEAF}]}}]", "objects[0].union: expected a list of 2 to 1024 objects"),
    objects("union-empty", "[{union: []}]", "objects[0].union: expected a list of 2 to 1024"),
    objects("union-1025", f"[{{union: {union(1025)}}}]", "objects[0].union: expected a list of 2 to 1024"),
    objects("union-not-list", f"[{{union: {LEAF}}}]", "objects[0].union: expected a list"),
    objects("nesting-33", f"[{nested(33)}]", "CSG operations nested more than 32 deep as written"),
    objects("two-operations", f"[{{union: [{LEAF}, {LEAF}], intersection: [{LEAF}, {LEAF}]}}]", "one CSG operation"),
    objects("csg-unknown-key", f"[{{difference: [{LEAF}, {LEAF}], params: {{r: 1}}}}]", "objects[0].params"),
    objects("csg-child-text", f"[{{intersection: [{LEAF}, sphere]}}]", "intersection[1]: expected a mapping"),
    objects("csg-child-bad", f"[{{difference: [{LEAF}, {{shape: nope.yaml}}]}}]", "objects[0].difference[1].shape"),
]

# ------------------------------------------------------------------------------------------- leaves
CASES += [
    objects("objects-empty", "[]", "objects: expected a non-empty list"),
    scene("objects-missing", "camera: {fov: 40}\n", "objects: expected a non-empty list"),
    objects("objects-mapping", "{a: 1}", "objects: expected a non-empty list"),
    objects("leaf-nothing", "[{material: {color: [1, 0, 0]}}]", "objects[0]: give exactly one of 'shape'"),
    objects("leaf-both", f"[{{shape: {SPHERE}, equation: x}}]", "objects[0]: give exactly one of"),
    leaf("leaf-name-with-shape", "name: ball", "objects[0].name: only for an inline 'equation'"),
    leaf("leaf-bounds-with-shape", "bounds: {x: [0, 1]}", "objects[0].bounds: only for an inline"),
    leaf("param-unknown", "params: {q: 1}", "objects[0].params.q: shape 'sphere' has no param 'q'"),
    leaf("param-huge", f"params: {{r: {BIG}}}", "objects[0].params.r: a number of about 1e400"),
    leaf("param-nan", "params: {r: .nan}", "objects[0].params.r: expected a finite number"),
    leaf(
        "param-bounds-empty",
        "params: {r: -1}",
        "objects[0].params: with these params the bounds of shape 'sphere' are empty",
    ),
    objects(
        "param-bounds-beyond",
        f"[{{shape: {TORUS}, params: {{a: 1e9, b: 1e9}}}}]",
        "objects[0].params: with these params the bounds of shape 'torus_y' leave",
    ),
    scene(
        "param-power-overflow",
        "objects: [{shape: p.yaml, params: {a: 1e9}}]\n",
        "objects[0].params: with these params a coefficient of shape 'p' reaches 2^1196",
        {"p.yaml": "name: p\nequation: x^2 + y^2 + z^2 - a^40 + 1\nparams: {a: 1}\n"},
    ),
    leaf("params-empty-list", "params: []", "objects[0].params: expected a mapping"),
    leaf("params-list", "params: [1]", "objects[0].params: expected a mapping"),
    leaf("leaf-unknown-key", "colour: red", "objects[0].colour: unknown key"),
    objects("inline-injection", "[{equation: 'y # */ int pwned; /*'}]", "objects[0]: equation: character '#'"),
    objects("inline-import", "[{equation: \"__import__('os').system('touch PWNED')\"}]", "objects[0]: equation"),
    objects("inline-call", "[{equation: 'exec(y)'}]", "objects[0]: equation: function calls are not allowed"),
    objects("inline-docstring", '[{equation: \'y """\'}]', "objects[0]: equation: character '\"'"),
    objects("inline-nul", '[{equation: "y\\0"}]', "objects[0]: equation: character U+0000"),
    objects("inline-non-ascii", "[{equation: 'y\u00b2'}]", "objects[0]: equation: character U+00B2"),
    objects("inline-degree-bomb", "[{equation: '(x+y+z)^10000'}]", "degree would exceed 24"),
    objects("inline-name-reserved", "[{equation: y, name: rt_scene}]", "objects[0]: name: 'rt_scene' is reserved"),
    objects("inline-name-header", "[{equation: y, name: stdlib}]", "objects[0]: name: 'stdlib'"),
    objects("inline-name-keyword", "[{equation: y, name: while}]", "objects[0]: name: 'while' is a reserved word"),
    objects("inline-name-path", "[{equation: y, name: ../../x}]", "objects[0]: name: '../../x' is not an identifier"),
    objects("inline-param-huge", f"[{{equation: y - a, params: {{a: {BIG}}}}}]", "objects[0]: params.a"),
    objects("inline-bounds-nan", "[{equation: y, bounds: {x: [.nan, 1]}}]", "objects[0]: bounds.x: must be finite"),
    objects("inline-constant", "[{equation: '3'}]", "objects[0]: equation: has no x, y or z"),
    objects("inline-equation-list", "[{equation: [y]}]", "objects[0]: equation: must be text"),
]

# ------------------------------------------------------------------------------ shape: that is not a spec
CASES += [
    objects("shape-missing", "[{shape: nope.yaml}]", "objects[0].shape: spec file not found"),
    objects("shape-empty", "[{shape: ''}]", "objects[0].shape: expected the path of a spec file"),
    objects("shape-number", "[{shape: 12}]", "objects[0].shape: expected the path of a spec file"),
    objects("shape-nul", '[{shape: "a\\0b"}]', "objects[0].shape: expected the path of a spec file"),
    objects("shape-etc-passwd", "[{shape: /etc/passwd}]", "objects[0].shape: /etc/passwd: not a shape spec"),
    objects("shape-proc", "[{shape: /proc/self/status}]", "not a shape spec"),
    objects("shape-dev-null", "[{shape: /dev/null}]", "objects[0].shape: /dev/null: is a device"),
    objects("shape-dev-zero", "[{shape: /dev/zero}]", "is a device"),
    objects("shape-folder", "[{shape: /etc}]", "objects[0].shape: /etc: is a folder, not a shape spec file"),
    scene("shape-fifo", "objects: [{shape: p.yaml}]\n", "p.yaml: is a fifo, not a shape spec file", {"p.yaml": FIFO}),
    scene("shape-png", "objects: [{shape: a.png}]\n", "is not a text file", {"a.png": b"\x89PNG\r\n\x1a\n\0\0"}),
    scene("shape-a-scene", "objects: [{shape: s.yaml}]\n", "s.yaml: not a shape spec"),
    scene(
        "shape-bad-spec",
        "objects: [{shape: b.yaml}]\n",
        "b.yaml: equation: function calls are not allowed",
        {"b.yaml": "name: b\nequation: __import__(os)\n"},
    ),
    scene("shape-link-loop", "objects: [{shape: l.yaml}]\n", "l.yaml is a link to nothing", {"l.yaml": Link("l.yaml")}),
    objects("shape-name-too-long", "[{shape: " + "a" * 300 + ".yaml}]", "objects[0].shape: cannot use this path"),
    objects("shape-path-too-long", "[{shape: " + "/".join(["d" * 200] * 25) + "}]", "objects[0].shape"),
]

# --------------------------------------------------------------------------------- the scene file itself
CASES += [
    Case("scene-missing", ["render", "nope.yaml", "-o", "out.png"], "not found (expected a scene file)"),
    Case("scene-folder", ["render", "d", "-o", "out.png"], "d: is a folder, not a scene file", {"d": FOLDER}),
    Case("scene-fifo", ["render", "p", "-o", "out.png"], "p: is a fifo, not a scene file", {"p": FIFO}),
    Case("scene-dev-zero", ["render", "/dev/zero", "-o", "out.png"], "/dev/zero: is a device, not a scene file"),
    Case("scene-passwd", ["render", "/etc/passwd", "-o", "out.png"], "a scene must be a mapping"),
    Case("scene-link-loop", ["render", "l", "-o", "out.png"], "cannot read", {"l": Link("l")}),
    scene("scene-binary", b"\x89PNG\r\n\x1a\n\0\0", "is not a text file (expected a scene"),
    scene("scene-latin1", b"objects: []\n# caf\xe9\n", "is not a text file"),
    scene("scene-empty", "", "a scene must be a mapping"),
    scene("scene-list", "- objects\n", "a scene must be a mapping"),
    scene("scene-python-tag", "objects: !!python/object/apply:os.system ['touch PWNED']\n", "invalid YAML"),
    scene("scene-duplicate-key", OBJ + OBJ, "duplicate key 'objects'"),
    scene("scene-unknown-top", "lamps: []\n" + OBJ, "lamps: unknown key"),
    scene("scene-spec-given", "name: s\nequation: x\n", "name: unknown key"),
    scene("scene-merge-unknown", "base: &b {width: 8}\nimage: {<<: *b, heigth: 4}\n" + OBJ, "base: unknown key"),
    scene("scene-merge-override-bad", "d: &d {width: 8}\n" + OBJ, "d: unknown key"),
]

# --------------------------------------------------------------------------------- output and options
CASES += [
    render("out-jpg", ["-o", "o.jpg"], "the output must end in .png", "-o o.jpg"),
    Case("out-folder", ["render", "s.yaml", "-o", "d"], "is a folder", {"s.yaml": OBJ, "d": FOLDER}, names="-o d"),
    Case("out-fifo", ["render", "s.yaml", "-o", "p.png"], "is a fifo", {"s.yaml": OBJ, "p.png": FIFO}, names="-o"),
    render("out-missing-folder", ["-o", "no/o.png"], "the folder no does not exist", "-o no/o.png"),
    Case(
        "out-under-file", ["render", "s.yaml", "-o", "f/o.png"], "f is not", {"s.yaml": OBJ, "f": "x"}, names="-o f/o"
    ),
    render("out-in-proc", ["-o", "/proc/o.png"], "cannot write in /proc", "-o /proc/o.png"),
    render("out-name-too-long", ["-o", "o" * 300 + ".png"], "long", "-o ooo"),
    render("out-path-too-long", ["-o", "/".join(["d" * 200] * 25) + ".png"], "long", "-o ddd"),
    Case(
        "out-link-loop",
        ["render", "s.yaml", "-o", "l/o.png"],
        "is a link to nothing",
        {"s.yaml": OBJ, "l": Link("l")},
        names="-o l/o.png",
    ),
    render("option-max-depth-above", ["--max-depth", "999"], "--max-depth: 999 is outside [0, 64]", "--max-depth"),
    render("option-max-depth-negative", ["--max-depth", "-1"], "--max-depth: -1 is outside", "--max-depth"),
    render("max-depth-text", ["--max-depth", "deep"], "argument --max-depth: invalid int value", "--max-depth"),
    render("width-zero-option", ["--width", "0"], "argument --width: 0 must be at least 1", "--width"),
    render("width-text-option", ["--width", "1e3"], "argument --width: '1e3' is not a whole number", "--width"),
    render("width-huge-option", ["--width", BIG], "--width", "--width"),
    render("height-above-option", ["--height", "16385"], "--height: 16385 is outside [1, 16384]", "--height"),
    render("spp-option", ["--spp", "0"], "argument --spp: 0 must be at least 1", "--spp"),
    render("spp-above-option", ["--spp", "100000000"], "--spp", "--spp"),
    render("threads-option", ["--threads", "-2"], "argument --threads", "--threads"),
    render("threads-above-option", ["--threads", "100000"], "--threads", "--threads"),
    render("unknown-option", ["--colour", "red"], "unrecognized arguments: --colour", "--colour"),
    *(
        Case(
            f"out-pattern-{i}",
            ["render", "a.yaml", "-o", pattern],
            "a frame pattern needs exactly one %d field",
            {"a.yaml": "animation: {frames: 3}\n" + OBJ},
            names=f"-o {pattern}",
        )
        for i, pattern in enumerate(["f_%n.png", "f_%099999999d.png", "f_%d_%d.png", "f_%s.png", "f_%%d.png"])
    ),
    Case(
        "out-video-odd-size",
        ["render", "a.yaml", "-o", "v.mp4", "--width", "5"],
        "a video needs an even width and height",
        {"a.yaml": "animation: {frames: 3}\n" + OBJ},
        names="-o v.mp4",
    ),
    Case("no-output", ["render", "s.yaml"], "arguments are required: -o/--output", {"s.yaml": OBJ}, names="render"),
    render("certify-jpg", ["--certify", "m.jpg"], "the output must end in .png", "--certify m.jpg"),
    render("certify-same-as-out", ["--certify", "out.png"], "is the same file as -o", "--certify out.png"),
    render("certify-in-proc", ["--certify", "/proc/m.png"], "cannot write in /proc", "--certify /proc/m.png"),
    render("report-alone", ["--report", "r.json"], "needs --certify MAP.png", "--report r.json"),
    render("report-txt", ["--certify", "m.png", "--report", "r.txt"], "must end in .json", "--report r.txt"),
    render("certify-tiles", ["--certify", "m.png", "--tiles", "2"], "only a still image", "--certify"),
    Case(
        "certify-animation",
        ["render", "a.yaml", "-o", "f_%d.png", "--certify", "m.png"],
        "only a still image",
        {"a.yaml": "animation: {frames: 3}\n" + OBJ},
        names="--certify",
    ),
    Case(
        "certify-folder",
        ["render", "s.yaml", "-o", "o.png", "--certify", "d"],
        "is a folder",
        {"s.yaml": OBJ, "d": FOLDER},
        names="--certify d",
    ),
]


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    return run_batch(CASES, tmp_path_factory.mktemp("bad-scenes"))


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_scene(case, results):
    check(case, results[0][case.id])


def test_bad_scenes_fit_in_300_mb(results):
    assert results[1] < 300 << 20
