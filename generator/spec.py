"""Shape spec files: YAML (safe_load) -> validated `Spec`.

    name: piriform                      # identifier; names the generated files and functions
    equation: x^4 - x^3 + y^2 + z^2     # `expr` (meaning expr = 0) or `lhs = rhs`
    params: {a: 1.0}                    # optional ordered mapping name -> default number
    bounds: {x: [0, 1], y: [-0.5, 0.5]} # optional object-space box; numbers or expressions in params;
                                        # an axis left out is unbounded
    description: a peg top              # optional

Inside is f < 0 with f = lhs - rhs; the outward normal is grad f / |grad f|.
"""

from __future__ import annotations

import keyword
import math
import re
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping

import sympy
import yaml
from sympy.polys.domains import QQ
from sympy.polys.rings import ring

from .errors import UserError
from .parse import ParseError, parse_expression, split_equation

MAX_DEGREE = 24          # must match IG_MAX_DEGREE in runtime_c/roots.h
MAX_FILE_BYTES = 1 << 20
MAX_PARAMS = 64
AXES = ("x", "y", "z")
KEYS = ("name", "equation", "params", "bounds", "description")
X, Y, Z = sympy.symbols("x y z", real=True)
VARIABLES = {"x": X, "y": Y, "z": Z}

_IDENT = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,63}\Z")
# Words that cannot be names in the generated C or Python.
_C_KEYWORDS = frozenset(
    "auto break case char const continue default do double else enum extern float for goto if inline int long "
    "register restrict return short signed sizeof static struct switch typedef union unsigned void volatile "
    "while _Bool _Complex _Imaginary".split()
)
_RESERVED_SHAPE_NAMES = frozenset({"implgen", "roots", "shape", "raycast", "numpy", "math"})


def param_symbol(name: str) -> sympy.Symbol:
    """Internal symbol for a user param: prefixed, so a param called `c`, `d`, `o` or `t` cannot collide
    with the names the generated code uses itself."""
    return sympy.Symbol(f"k_{name}", real=True)


@dataclass(frozen=True)
class Spec:
    name: str
    equation: str
    params: dict[str, float]                     # ordered: the order the generated code takes them in
    f: sympy.Expr                                # lhs - rhs, structure as written; x, y, z and k_* symbols
    degree: int                                  # exact total degree in x, y, z
    bounds: dict[str, tuple[sympy.Expr, sympy.Expr]] | None = None   # axis -> (lo, hi) in k_* symbols
    description: str = ""
    source: str = "<spec>"
    folded: dict[str, float] = field(default_factory=dict)  # params folded into constants by specialise()

    @property
    def param_symbols(self) -> list[sympy.Symbol]:
        return [param_symbol(p) for p in self.params]

    def box(self, values: Mapping[str, float] | None = None) -> list[float] | None:
        """The numeric box {xmin, ymin, zmin, xmax, ymax, zmax} for these param values (defaults else)."""
        if self.bounds is None:
            return None
        subs = {param_symbol(k): v for k, v in {**self.params, **(values or {})}.items()}
        lo = [float(self.bounds[a][0].subs(subs)) if a in self.bounds else -math.inf for a in AXES]
        hi = [float(self.bounds[a][1].subs(subs)) if a in self.bounds else math.inf for a in AXES]
        return lo + hi

    def specialise(self, values: Mapping[str, float], name: str | None = None) -> "Spec":
        """The same shape with the given params folded into the equation as constants."""
        unknown = set(values) - set(self.params)
        if unknown:
            raise UserError(self.source, f"unknown params {sorted(unknown)} for shape {self.name!r}")
        new_name = name or self.name
        _check_identifier(self.source, "name", new_name)
        subs = {param_symbol(k): sympy.nsimplify(_finite(self.source, f"params.{k}", v), rational=True)
                for k, v in values.items()}
        bounds = None
        if self.bounds is not None:
            bounds = {a: (lo.subs(subs), hi.subs(subs)) for a, (lo, hi) in self.bounds.items()}
        return replace(self, name=new_name, f=self.f.subs(subs),
                       params={k: v for k, v in self.params.items() if k not in values},
                       bounds=bounds, folded={**self.folded, **{k: float(v) for k, v in values.items()}})


class _UniqueKeyLoader(yaml.SafeLoader):
    """safe_load, but a key given twice is an error rather than silently the last one."""


def _construct_mapping(loader: _UniqueKeyLoader, node: yaml.MappingNode, deep: bool = False) -> dict:
    seen = set()
    for key_node, _ in node.value:
        key = loader.construct_object(key_node, deep=deep)
        if isinstance(key, (str, int, float)) and key in seen:
            raise yaml.constructor.ConstructorError(None, None, f"duplicate key {key!r}", key_node.start_mark)
        if isinstance(key, (str, int, float)):
            seen.add(key)
    return yaml.SafeLoader.construct_mapping(loader, node, deep=deep)


_UniqueKeyLoader.add_constructor(yaml.resolver.BaseResolver.DEFAULT_MAPPING_TAG, _construct_mapping)


def read_yaml(path: Path) -> Any:
    """Read a small YAML file safely; any failure is a one-line UserError naming the file."""
    try:
        size = path.stat().st_size
    except OSError as err:
        raise UserError(path, f"cannot read: {err.strerror or err}") from None
    if not path.is_file():
        raise UserError(path, "not a file")
    if size > MAX_FILE_BYTES:
        raise UserError(path, f"file larger than {MAX_FILE_BYTES} bytes")
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        raise UserError(path, f"cannot read: {err}") from None
    try:
        return yaml.load(text, Loader=_UniqueKeyLoader)  # noqa: S506 -- a SafeLoader subclass
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise UserError(path, f"invalid YAML{where}: {problem}") from None
    except RecursionError:
        raise UserError(path, "invalid YAML: nested too deeply") from None


def load_spec(path: str | Path) -> Spec:
    """Load and validate a spec file."""
    path = Path(path)
    return parse_spec(read_yaml(path), str(path))


def _check_identifier(source: str, key: str, name: Any) -> str:
    if not isinstance(name, str) or not _IDENT.match(name):
        raise UserError(source, f"{key}: {str(name)[:40]!r} is not an identifier "
                                "(a letter, then letters, digits or _, at most 64)")
    if keyword.iskeyword(name) or name in _C_KEYWORDS:
        raise UserError(source, f"{key}: {name!r} is a reserved word in C or Python")
    return name


def _finite(source: str, key: str, value: Any) -> float:
    if isinstance(value, bool):
        raise UserError(source, f"{key}: must be a finite number, not {value!r}")
    if isinstance(value, str):
        try:
            value = float(value)
        except ValueError:
            raise UserError(source, f"{key}: must be a finite number, not {value[:40]!r}") from None
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(source, f"{key}: must be a finite number, not {str(value)[:40]!r}")
    return float(value) if isinstance(value, float) else int(value)


def _parse_params(source: str, raw: Any) -> dict[str, float]:
    if raw is None:
        return {}
    if not isinstance(raw, dict):
        raise UserError(source, "params: must be a mapping of name to default number")
    if len(raw) > MAX_PARAMS:
        raise UserError(source, f"params: more than {MAX_PARAMS}")
    params: dict[str, float] = {}
    for name, value in raw.items():
        _check_identifier(source, "params", name)
        if name in AXES:
            raise UserError(source, f"params: {name!r} shadows the coordinate {name}")
        params[name] = _finite(source, f"params.{name}", value)
    return params


def _parse_equation(source: str, text: Any, params: dict[str, float]) -> tuple[sympy.Expr, int]:
    if not isinstance(text, (str, int, float)) or isinstance(text, bool):
        raise UserError(source, "equation: must be text such as 'x^2 + y^2 + z^2 - 1'")
    symbols = {p: param_symbol(p) for p in params}
    try:
        lhs_text, rhs_text = split_equation(str(text))
        lhs = parse_expression(lhs_text, VARIABLES, symbols, MAX_DEGREE)
        rhs = parse_expression(rhs_text, VARIABLES, symbols, MAX_DEGREE)
    except ParseError as err:
        raise UserError(source, f"equation: {err}") from None
    f = lhs.expr - rhs.expr
    poly = exact_polynomial(f, list(symbols.values()))
    if poly == 0:
        raise UserError(source, "equation: is identically zero (every point would be on the surface)")
    degree = max(sum(m[:3]) for m in poly.monoms())
    if degree == 0:
        raise UserError(source, "equation: has no x, y or z (a constant, not a surface)")
    if degree > MAX_DEGREE:
        raise UserError(source, f"equation: degree {degree} is above the highest supported, {MAX_DEGREE}")
    return f, degree


def exact_polynomial(f: sympy.Expr, params: list[sympy.Symbol]):
    """f as an element of the polynomial ring QQ[x, y, z, params] (exact rational arithmetic)."""
    R, *_ = ring([X, Y, Z, *params], QQ)
    return R.from_expr(f) if f != 0 else R.zero


def _parse_bounds(source: str, raw: Any, params: dict[str, float]) -> dict[str, tuple[sympy.Expr, sympy.Expr]] | None:
    if raw is None:
        return None
    if not isinstance(raw, dict) or not raw:
        raise UserError(source, "bounds: must be a mapping such as {x: [-1, 1], y: [-1, 1], z: [-1, 1]}")
    symbols = {p: param_symbol(p) for p in params}
    defaults = {param_symbol(k): v for k, v in params.items()}
    bounds: dict[str, tuple[sympy.Expr, sympy.Expr]] = {}
    for axis, pair in raw.items():
        if axis not in AXES:
            raise UserError(source, f"bounds: unknown axis {str(axis)[:20]!r} (use x, y, z)")
        if not isinstance(pair, list) or len(pair) != 2:
            raise UserError(source, f"bounds.{axis}: must be a pair [low, high]")
        ends = []
        for item in pair:
            if isinstance(item, bool) or not isinstance(item, (int, float, str)):
                raise UserError(source, f"bounds.{axis}: {str(item)[:40]!r} is not a number or expression")
            if isinstance(item, float) and not math.isfinite(item):
                raise UserError(source, f"bounds.{axis}: must be finite (leave the axis out to leave it open)")
            try:
                ends.append(parse_expression(str(item), {}, symbols, 0).expr)
            except ParseError as err:
                raise UserError(source, f"bounds.{axis}: {err}") from None
        lo, hi = ends
        if not float(lo.subs(defaults)) < float(hi.subs(defaults)):
            raise UserError(source, f"bounds.{axis}: low must be below high (with the default params)")
        bounds[axis] = (lo, hi)
    return bounds


def parse_spec(data: Any, source: str = "<spec>") -> Spec:
    """Validate an already-loaded mapping (a spec file, or an inline shape in a scene)."""
    if not isinstance(data, dict):
        raise UserError(source, "a spec must be a mapping with at least 'name' and 'equation'")
    unknown = [str(k) for k in data if k not in KEYS]
    if unknown:
        raise UserError(source, f"unknown key {unknown[0][:40]!r} (allowed: {', '.join(KEYS)})")
    for key in ("name", "equation"):
        if key not in data:
            raise UserError(source, f"missing key {key!r}")
    name = _check_identifier(source, "name", data["name"])
    if name.lower() in _RESERVED_SHAPE_NAMES:
        raise UserError(source, f"name: {name!r} is reserved by implgen")
    params = _parse_params(source, data.get("params"))
    f, degree = _parse_equation(source, data["equation"], params)
    bounds = _parse_bounds(source, data.get("bounds"), params)
    description = data.get("description", "")
    if not isinstance(description, str):
        raise UserError(source, "description: must be text")
    return Spec(name=name, equation=str(data["equation"]).strip(), params=params, f=f, degree=degree,
                bounds=bounds, description=" ".join(description.split()), source=source)
