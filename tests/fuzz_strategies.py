"""Hypothesis strategies for fuzzing the readers of user text: equations, specs and scenes that are valid by
construction, then one thing broken; and raw byte mutations of the example files.

`broken(documents)` takes a valid document and breaks exactly one thing in it: a value replaced by a hostile
one (wrong type, out-of-range or huge number, NaN/inf as text, a bad or reserved name, deep nesting, an
equation with a bad token), a key deleted, added or renamed, a list item repeated, or the same node shared
many times (an alias bomb once dumped as YAML). A plain dump of a shared object is a YAML alias, so aliases
come for free.
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parent.parent
SHAPES = ROOT / "examples" / "shapes"
SCENES = ROOT / "examples" / "scenes"
# Params of the example specs (for scene leaves that override them).
EXAMPLE_PARAMS = {
    "sphere": ["r"],
    "cylinder": ["r"],
    "cone": [],
    "torus_y": ["a", "b"],
    "torus_z": ["R", "r"],
    "piriform": [],
    "heart": [],
}

PARAM_NAMES = ["a", "b", "r", "R", "k2", "big_r", "c", "d", "o", "t", "params", "w0"]

# Text that breaks an equation somewhere: comments, quotes, escapes, control and non-ASCII characters,
# Python syntax beyond the grammar, numbers past every range, degree and nesting bombs.
BAD_TOKENS = [
    "#",
    "# */ int pwned; /*",
    "*/",
    "/*",
    '"""',
    "'''",
    "'",
    '"',
    "\\",
    "\\\n",
    "\x00",
    "\x1b[31m",
    "\r",
    "\t",
    "\n",
    "\u00e9",
    "\u2212",
    "\u00b2",
    "\u200b",
    "\U0001f600",
    "\ufeff",
    "sin(",
    "__import__('os')",
    "x.real",
    "lambda q: q",
    "[x for x in y]",
    "x if y else z",
    "1and ",
    "1if ",
    "not ",
    " or ",
    "==",
    "=",
    "==1",
    ";",
    "@",
    "%",
    "//",
    "<<",
    "~",
    "&",
    "|",
    ":=",
    "**-1",
    "^0.5",
    "^-2",
    "^(10^10)",
    "^99999999999",
    "**(2**64)",
    "/0",
    "/x",
    "/(1-1)",
    "(",
    ")",
    "((((((((((",
    "1e999",
    "1e-999",
    "1e308",
    "9" * 81,
    "9" * 79,
    "0x1f",
    "0b101",
    "1_000",
    "1j",
    "nan",
    "inf",
    "..",
    "1.2.3",
    "x^24",
    "(x+y+z)^10000",
    "((x^2)^2)^2)^2",
    "^",
    "**",
    "",
    " ",
]

HOSTILE_TEXT = [
    "",
    " ",
    "*/ int pwned = 1; /*",
    '"""\nimport os\n"""',
    "a\x00b",
    "\x1b[2J",
    "line\nbreak",
    "x\u00b2 \u2212 \u00bd",
    "../../etc/passwd",
    "/etc/passwd",
    "/dev/zero",
    "/proc/self/status",
    "/",
    ".",
    "~",
    "rt_scene",
    "ig_shape",
    "int",
    "math",
    "stdio",
    "lambda",
    "x",
    "a" * 65,
    "a" * 3000,
    "nan",
    "inf",
    "-inf",
    "1e999",
    "1e-999",
    "0x10",
    "12",
    "!!python/object",
]


def _deep_list(n: int) -> Any:
    value: Any = 1
    for _ in range(n):
        value = [value]
    return value


def _deep_map(n: int) -> Any:
    value: Any = 1
    for _ in range(n):
        value = {"union": value}
    return value


def _deep_csg(n: int, bottom: Any = None) -> Any:
    """CSG nested n levels as written, two containers a level: {union: [{union: [bottom, y], ...}, y]}."""
    node = {"equation": "x^2 + y^2 + z^2 - 1"} if bottom is None else bottom
    for _ in range(n):
        node = {"union": [node, {"equation": "y"}]}
    return node


# How deep hostile nesting goes, in containers (lists and mappings): past every walk's bound (scene/keys.py
# MAX_NESTING = 100) and into the band where an unbounded walk of two Python frames per container overflows
# Python's recursion limit while the YAML reader (which refuses ~500 levels by itself) still takes the file:
# about 320-460 containers, whether the reader runs from the command line or under pytest and Hypothesis.
# Hypothesis favours the first of a sampled list: the band comes first.
DEEP_LEVELS = [400, 340, 440, 380, 460, 200, 120, 60]


HOSTILE_VALUES = [
    10**400,
    None,
    True,
    False,
    0,
    -1,
    1,
    2,
    3,
    10**400,
    -(10**400),
    2**63,
    2**1024,
    float("nan"),
    float("inf"),
    float("-inf"),
    1e308,
    -1e308,
    5e-324,
    1e-320,
    0.5,
    179.99,
    1e9,
    1e9 + 1,
    16384,
    16385,
    1024,
    [],
    {},
    [1],
    [1, 2],
    [1, 2, 3],
    [1, 2, 3, 4],
    [1e308, 1e308, 1e308],
    [100, 100, 100],
    [[1, 0, 0], [0, 1, 0], [1, 1, 0]],
    [float("nan"), 0, 0],
    [10**400, 0, 0],
    {"a": 1},
    {"x": [-1, 1]},
    _deep_list(60),
    _deep_list(400),
    _deep_map(60),
    _deep_map(300),
    _deep_csg(40),
    _deep_csg(190),
    *HOSTILE_TEXT,
]

numbers_text = st.one_of(
    st.integers(0, 99).map(str),
    st.tuples(st.integers(0, 9), st.integers(0, 999)).map(lambda t: f"{t[0]}.{t[1]}"),
    st.sampled_from(["1e-3", "2.5e2", "0.5", ".25", "3.", "1E2"]),
)
nonzero_text = st.one_of(st.integers(1, 99).map(str), st.sampled_from(["0.5", "2.5", "1e2", "4"]))


def expressions(names: list[str], max_leaves: int = 10) -> st.SearchStrategy[str]:
    """Equation text in the documented grammar, from x, y, z, the given params and numbers."""
    leaf = st.sampled_from(["x", "y", "z", *names]) | numbers_text

    def extend(children: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        return st.one_of(
            st.tuples(children, st.sampled_from(["+", "-", "*", " + ", " - ", " * "]), children).map(
                lambda t: f"({t[0]}{t[1]}{t[2]})"
            ),
            st.tuples(children, nonzero_text).map(lambda t: f"{t[0]}/{t[1]}"),
            st.tuples(children, st.sampled_from(["^", "**", " ^ "]), st.integers(0, 4)).map(
                lambda t: f"({t[0]}){t[1]}{t[2]}"
            ),
            children.map(lambda s: f"-{s}"),
        )

    return st.recursive(leaf, extend, max_leaves=max_leaves)


@st.composite
def equations(draw: st.DrawFn, names: list[str], max_leaves: int = 10) -> str:
    """A whole equation: mostly a surface (a sphere plus a random term), sometimes `lhs = rhs`."""
    body = draw(expressions(names, max_leaves))
    form = draw(st.sampled_from(["sphere", "sphere", "plain", "equals"]))
    if form == "sphere":
        return f"x^2 + y^2 + z^2 - 1 + 0.01*{body}"
    term = draw(st.sampled_from(["x", "y^2", "x*y*z", "z^3"]))
    if form == "equals":
        return f"{body} + {term} = {draw(expressions(names, 4))}"
    return f"{term} + {body}" if draw(st.booleans()) else f"{body} - {term}"


def insert_token(text: str, token: str, where: float) -> str:
    i = int(where * len(text))
    return text[:i] + token + text[i:]


@st.composite
def bad_equations(draw: st.DrawFn, names: list[str]) -> str:
    """A valid equation with one hostile token inserted somewhere."""
    text = draw(equations(names, 6))
    return insert_token(text, draw(st.sampled_from(BAD_TOKENS)), draw(st.floats(0, 1)))


small = st.floats(-10, 10, allow_nan=False, allow_infinity=False)
positive = st.floats(0.1, 3, allow_nan=False)
unit = st.floats(0, 1, allow_nan=False)


def vec(elements: st.SearchStrategy[float] = small) -> st.SearchStrategy[list[float]]:
    return st.lists(elements, min_size=3, max_size=3)


@st.composite
def specs(draw: st.DrawFn) -> dict:
    """A valid-looking spec document (a few may still be refused: an equation that cancels to zero, or of
    too high a degree)."""
    names = draw(st.lists(st.sampled_from(PARAM_NAMES), unique=True, max_size=3))
    doc: dict[str, Any] = {
        "name": draw(st.from_regex(r"s[a-z0-9_]{0,10}", fullmatch=True)),
        "equation": draw(equations(names)),
    }
    if names or draw(st.booleans()):
        doc["params"] = {n: draw(positive) for n in names}
    if draw(st.booleans()):
        axes = draw(st.lists(st.sampled_from("xyz"), unique=True, min_size=1))
        doc["bounds"] = {a: [-draw(positive), draw(positive)] for a in axes}
        if names and draw(st.booleans()):
            doc["bounds"][axes[0]] = [f"-2*{names[0]}", f"{names[0]} + 1"]
    if draw(st.booleans()):
        doc["description"] = draw(st.text(max_size=30) | st.sampled_from(HOSTILE_TEXT))
    return doc


def _paths(doc: Any, prefix: tuple = ()) -> list[tuple]:
    """Every (container path, key) in a document."""
    out = []
    if isinstance(doc, dict):
        for k, v in doc.items():
            out.append((*prefix, k))
            out += _paths(v, (*prefix, k))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            out.append((*prefix, i))
            out += _paths(v, (*prefix, i))
    return out


def _container(doc: Any, path: tuple) -> Any:
    for k in path[:-1]:
        doc = doc[k]
    return doc


BREAKS = [
    "keep",
    "replace",
    "replace",
    "replace",
    "equation",
    "delete",
    "add_key",
    "rename",
    "repeat",
    "share",
    "wrap",
    "nest",
]


@st.composite
def broken(draw: st.DrawFn, documents: st.SearchStrategy[Any]) -> tuple[str, Any]:
    """(what was broken, the document) from a valid document with exactly one thing broken."""
    doc = copy.deepcopy(draw(documents))
    how = draw(st.sampled_from(BREAKS))
    if how == "keep":  # valid as built: the loaders must take it
        return how, doc
    paths = _paths(doc)[::-1]  # Hypothesis favours the first: let that be a leaf deep down
    if how == "wrap" or not paths:
        return how, draw(st.sampled_from([[doc], {"spec": doc}, _deep_list(50), "text", 12, None]))
    path = draw(st.sampled_from(paths))
    box = _container(doc, path)
    key = path[-1]
    if how == "replace":
        box[key] = copy.deepcopy(draw(st.sampled_from(HOSTILE_VALUES)))
    elif how == "equation":
        names = list(doc.get("params") or {}) if isinstance(doc.get("params"), dict) else []
        box[key] = draw(bad_equations(names))
    elif how == "delete":
        del box[key]
    elif how == "add_key":
        target = box[key] if isinstance(box[key], dict) else box if isinstance(box, dict) else doc
        if isinstance(target, dict):
            target[draw(st.sampled_from(["colour", "x", "<<", "Name", "1", "objects", "name"]))] = 1
    elif how == "rename" and isinstance(box, dict):
        box[draw(st.sampled_from(["Equation", "nmae", "param", "bound", " name", "name\x00"]))] = box.pop(key)
    elif how == "repeat" and isinstance(box[key], list) and box[key]:
        box[key] = box[key] * draw(st.sampled_from([2, 300, 1100, 12000]))
    elif how == "nest":
        # the value itself, nested hundreds of levels deep: in lists, in mappings, or as CSG around it
        box[key] = draw(nested(st.just(box[key])))
    elif how == "share":
        # the same node reused twice per level, n levels: an alias bomb once dumped as YAML
        node = box[key]
        for _ in range(draw(st.integers(1, 40))):
            node = {"union": [node, node]} if draw(st.booleans()) else [node, node]
        box[key] = node
    return how, doc


@st.composite
def nested(draw: st.DrawFn, values: st.SearchStrategy[Any]) -> Any:
    """A value wrapped DEEP_LEVELS deep: in lists, in mappings, in CSG operations (the value as their leaves)."""
    value = copy.deepcopy(draw(values))
    n = draw(st.sampled_from(DEEP_LEVELS))
    how = draw(st.sampled_from(["csg", "list", "mixed", "map"]))
    for i in range(n if how != "csg" else 0):
        if how == "list" or (how == "mixed" and i % 2):
            value = [value]
        else:
            value = {draw(st.sampled_from(["union", "transform", "keys", "a"])) if how == "mixed" else "union": value}
    return _deep_csg(n // 2, value) if how == "csg" else value


@st.composite
def deep_scenes(draw: st.DrawFn) -> dict:
    """A valid scene (animated or not) with one object nested deep: hundreds of levels of CSG, lists or
    mappings around the object, or in its transform (after a keyed param, so the transform is resolved); or
    valid CSG up to the reader's limit of 32 levels."""
    doc = copy.deepcopy(draw(scenes()))
    objects = doc["objects"]
    i = draw(st.integers(0, len(objects) - 1))
    how = draw(st.sampled_from(["object", "transform", "valid"]))
    if how == "object":
        objects[i] = draw(nested(st.sampled_from([objects[i], {"keys": {0: 1.0}}, [1.0, 2.0, 3.0]])))
    elif how == "transform":
        frames = doc.get("animation", {}).get("frames", 2)
        keyed = {"keys": {0: 1.0, frames - 1: 0.5}} if "animation" in doc else 1.0
        transform = draw(nested(st.sampled_from([{"scale": 1.0}, [1.0, 1.0, 1.0], 1.0])))
        objects[i] = {"shape": str(SHAPES / "sphere.yaml"), "params": {"r": keyed}, "transform": transform}
    else:
        objects[i] = _deep_csg(draw(st.integers(1, 31)), objects[i])  # deep, and valid
    return doc


# Values no key of a spec or scene accepts, wherever they are put: a document holding one must be refused.
NEVER_VALID = [10**400, -(10**400), float("nan"), float("inf"), _deep_list(60), {"zq": []}, [[[]]]]


@st.composite
def poisoned(draw: st.DrawFn, documents: st.SearchStrategy[Any]) -> tuple[tuple, Any]:
    """(the path, the document) from a valid document with one value replaced by one no key accepts."""
    doc = copy.deepcopy(draw(documents))
    path = draw(st.sampled_from(_paths(doc)[::-1]))
    _container(doc, path)[path[-1]] = copy.deepcopy(draw(st.sampled_from(NEVER_VALID)))
    return path, doc


# ------------------------------------------------------------------------------------------------ scenes

colours = vec(unit)
materials = st.fixed_dictionaries(
    {},
    optional={
        "color": colours,
        "ambient": unit,
        "diffuse": unit,
        "specular": unit,
        "shininess": st.floats(0, 200),
        "reflectivity": unit,
        "transparency": unit,
        "ior": st.floats(1, 3),
        "absorption": vec(st.floats(0, 2)),
        "checker": st.fixed_dictionaries(
            {"colors": st.lists(colours, min_size=2, max_size=2)}, optional={"scale": positive}
        ),
    },
)
_srt = st.fixed_dictionaries(
    {},
    optional={
        "scale": positive | vec(positive),
        "rotate": vec(st.floats(-360, 360)) | st.fixed_dictionaries({"axis": st.just([0, 1, 1]), "angle": small}),
        "translate": vec(),
    },
)
_axes = st.fixed_dictionaries({"axes": st.just([[0, 1.5, 0], [1.2, 0, 0], [0, 0, 1]])}, optional={"position": vec()})
transforms = _srt | _axes | st.lists(_srt | _axes, min_size=1, max_size=3)


@st.composite
def leaves(draw: st.DrawFn, material_names: list[str]) -> dict:
    if draw(st.booleans()):
        shape = draw(st.sampled_from(sorted(EXAMPLE_PARAMS)))
        where = draw(st.sampled_from(["relative", "absolute"]))
        file = f"../shapes/{shape}.yaml" if where == "relative" else str(SHAPES / f"{shape}.yaml")
        leaf: dict[str, Any] = {"shape": file}
        names = EXAMPLE_PARAMS[shape]
        overrides = draw(st.lists(st.sampled_from(names), unique=True)) if names else []
        if overrides:
            leaf["params"] = {p: draw(positive) for p in overrides}
    else:
        leaf = {"equation": draw(st.sampled_from(["y", "x^2 + y^2 + z^2 - 1", "x^2 + z^2 - 0.25"]) | equations([], 4))}
        if draw(st.booleans()):
            leaf["name"] = draw(st.from_regex(r"q[a-z0-9]{0,6}", fullmatch=True))
    if draw(st.booleans()):
        leaf["transform"] = draw(transforms)
    if material_names and draw(st.booleans()):
        leaf["material"] = draw(st.sampled_from(material_names))
    elif draw(st.booleans()):
        leaf["material"] = draw(materials)
    return leaf


def nodes(material_names: list[str]) -> st.SearchStrategy[dict]:
    def extend(children: st.SearchStrategy[dict]) -> st.SearchStrategy[dict]:
        return st.tuples(
            st.sampled_from(["union", "intersection", "difference"]),
            st.lists(children, min_size=2, max_size=3),
            st.none() | transforms,
        ).map(lambda t: {t[0]: t[1], **({"transform": t[2]} if t[2] is not None else {})})

    return st.recursive(leaves(material_names), extend, max_leaves=5)


@st.composite
def scenes(draw: st.DrawFn) -> dict:
    names = draw(st.lists(st.sampled_from(["floor", "glass", "m1", "red one"]), unique=True, max_size=3))
    doc: dict[str, Any] = {}
    if draw(st.booleans()):
        doc["image"] = draw(
            st.fixed_dictionaries(
                {},
                optional={
                    "width": st.integers(1, 64),
                    "height": st.integers(1, 64),
                    "spp": st.integers(1, 4),
                    "max_depth": st.integers(0, 8),
                },
            )
        )
    if draw(st.booleans()):
        doc["camera"] = {
            "position": [draw(st.floats(-1, 1)), draw(st.floats(1, 3)), draw(st.floats(5, 8))],
            "look_at": [0, draw(st.floats(-0.5, 0.5)), 0],
            "up": [0, 1, 0],
            "fov": draw(st.floats(10, 90)),
        }
    if draw(st.booleans()):
        doc["background"] = draw(colours)
    doc["lights"] = draw(
        st.lists(
            st.fixed_dictionaries({"position": vec()}, optional={"color": colours, "intensity": st.floats(0, 5)}),
            max_size=2,
        )
    )
    doc["materials"] = {n: draw(materials) for n in names}
    doc["objects"] = draw(st.lists(nodes(names), min_size=1, max_size=3))
    if draw(st.booleans()):
        frames = draw(st.integers(1, 6))
        doc = {"animation": {"frames": frames}, **copy.deepcopy(doc)}  # st.just values are shared: copy first
        _animate(draw, doc, frames)
    return doc


_NOT_KEYABLE = ("image", "animation", "bounds")


def _animate(draw: st.DrawFn, doc: Any, frames: int, top: bool = True) -> None:
    """Some of the scene's numbers keyed to frames: the key at frame 0 the number itself, the last key a
    number between half and all of it (in range wherever the number was)."""
    items = list(doc.items()) if isinstance(doc, dict) else list(enumerate(doc)) if isinstance(doc, list) else []
    for k, v in items:
        if top and k in _NOT_KEYABLE:
            continue
        if isinstance(v, float) and draw(st.integers(0, 3)) == 0:
            last = v * draw(st.floats(0.5, 1.0))
            doc[k] = {"keys": {0: v, frames - 1: last}, "ease": draw(st.sampled_from(["linear", "smooth"]))}
        elif isinstance(v, (dict, list)) and k != "bounds":
            _animate(draw, v, frames, top=False)


# --------------------------------------------------------------------------------------- raw mutations

SNIPPETS = [s.encode("utf-8") for s in BAD_TOKENS if s] + [
    b"*/",
    b'"""',
    b"#",
    b"\\",
    b"\xff",
    b"\xc3",
    b"\x00",
    b"\t",
    b"&a ",
    b"*a",
    b"<<: *a\n",
    b"!!python/object/apply:os.system ['true']",
    b"!!binary ",
    b"!!float ",
    b"!!int ",
    b"!!str ",
    b"? ",
    b"---\n",
    b"...\n",
    b"%YAML 1.1\n",
    b"{",
    b"}",
    b"[",
    b"]",
    b": ",
    b"- ",
    b"\n  ",
    b"1" * 400,
    b"1e400",
    b"-1e400",
    b".nan",
    b".inf",
    b"9" * 5000,
]


@st.composite
def mutated(draw: st.DrawFn, data: bytes) -> bytes:
    """`data` with one to three byte-level changes: a bit flipped, a snippet inserted, a slice deleted, a slice
    repeated."""
    for _ in range(draw(st.integers(1, 3))):
        n = len(data)
        i = draw(st.integers(0, max(n - 1, 0)))
        how = draw(st.sampled_from(["flip", "insert", "insert", "delete", "repeat", "replace_number"]))
        if how == "flip" and n:
            data = data[:i] + bytes([data[i] ^ (1 << draw(st.integers(0, 7)))]) + data[i + 1 :]
        elif how == "insert":
            data = data[:i] + draw(st.sampled_from(SNIPPETS)) + data[i:]
        elif how == "delete":
            data = data[:i] + data[i + draw(st.integers(1, 20)) :]
        elif how == "repeat":
            j = min(n, i + draw(st.integers(1, 60)))
            data = data[:j] + data[i:j] * draw(st.sampled_from([2, 50, 2000])) + data[j:]
        elif how == "replace_number":
            digits = [k for k in range(n) if chr(data[k]).isdigit()]
            if digits:
                k = draw(st.sampled_from(digits))
                number = draw(st.sampled_from([b"9" * 400, b"1e999", b"0", b"-0", b"1e-400", b".nan"]))
                data = data[:k] + number + data[k + 1 :]
    return data


def example_files(folder: Path) -> list[tuple[str, bytes]]:
    return [(p.name, p.read_bytes()) for p in sorted(folder.glob("*.yaml"))]
