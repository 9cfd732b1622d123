"""The one `Spec` type: a validated shape, without SymPy.

A spec has two parts. What a scene's build and render read -- the name, the params and their defaults, the
degree, the printed equation, the box and the checks of param values (from plain data: spec/paramvalues.py),
and the key of its generated code -- is held as plain values. Its expression (`f`, the symbolic `bounds`,
`specialise`) is the symbolic part, built by spec/parse.py: at once when the spec was parsed, or on first use
when it was read back from the spec cache (spec/cache.py). So a scene whose shapes were built before
renders without importing SymPy, and every caller holds the same type either way.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from implgen.spec import paramvalues


class Symbolic(Protocol):
    """The SymPy side of a spec (spec/parse.py's SymbolicForm)."""

    f: Any  # lhs - rhs as a SymPy expression in x, y, z and the k_* param symbols
    bounds: dict[str, tuple[Any, Any]] | None  # axis -> (lo, hi) in the k_* symbols
    param_symbols: list[Any]  # the k_* symbols, in the params' order

    def specialise(self, spec: Spec, values: Mapping[str, float], name: str | None) -> Spec: ...


class _Once:
    """A value built on first use by `make`, at most once even when threads ask together. Pickles when `make`
    does (a cached spec's is a module-level callable holding the cached content)."""

    def __init__(self, make: Callable[[], Symbolic] | None = None, value: Symbolic | None = None):
        self._make, self._value, self._lock = make, value, threading.Lock()
        self.deferred = value is None  # built on first use rather than given

    def __getstate__(self) -> tuple:  # a spec travels to Dask workers; the lock is made anew there
        return (self._make, self._value, self.deferred)

    def __setstate__(self, state: tuple) -> None:
        self._make, self._value, self.deferred = state
        self._lock = threading.Lock()

    @property
    def ready(self) -> bool:
        return self._value is not None

    def get(self) -> Symbolic:
        if self._value is None:
            with self._lock:
                if self._value is None:
                    assert self._make is not None
                    self._value, self._make = self._make(), None
        return self._value


@dataclass(frozen=True, eq=False)
class Spec:
    name: str
    equation: str  # f printed back from the parsed tree (never the raw text)
    params: dict[str, float]  # ordered: the order the generated code takes them in
    degree: int  # exact total degree in x, y, z
    param_terms: paramvalues.Terms  # (log2 |coefficient|, param exponents) of every term of f
    bounds_trees: paramvalues.Trees | None  # the bounds as trees in the param names, None when unbounded
    spec_key: str  # the key of the generated code (speccache.spec_key)
    symbolic_part: _Once = field(repr=False)
    description: str = ""
    source: str = "<spec>"
    folded: dict[str, float] = field(default_factory=dict)  # params folded into constants by specialise()
    default_box: list[float] | None = field(default=None, repr=False)
    title: str = ""  # shown, never generated: the title, the literature reference, a slider's range per param
    reference: str = ""
    ranges: dict[str, tuple[float, float]] = field(default_factory=dict)
    # the equation as the user wrote it (`lhs = rhs` or `expr`): the parsed tree printed back in the user's order
    # (spec/written.py), for what people read; "" where there is none (params folded): `equation` then
    written: str = ""

    @property
    def as_written(self) -> str:
        """The equation to show a person: as written, else the canonical `equation` (meaning `= 0`)."""
        return self.written or self.equation

    @staticmethod
    def parsed(symbolic: Symbolic) -> _Once:
        """The symbolic part of a spec parsed just now."""
        return _Once(value=symbolic)

    @staticmethod
    def deferred(make: Callable[[], Symbolic]) -> _Once:
        """The symbolic part of a cached spec: parsed from the cached content when first asked for."""
        return _Once(make=make)

    @property
    def symbolic(self) -> Symbolic:
        return self.symbolic_part.get()

    @property
    def f(self) -> Any:
        return self.symbolic.f

    @property
    def bounds(self) -> dict[str, tuple[Any, Any]] | None:
        return self.symbolic.bounds

    @property
    def param_symbols(self) -> list[Any]:
        return self.symbolic.param_symbols

    def box(self, values: Mapping[str, float] | None = None) -> list[float] | None:
        """The numeric box {xmin, ymin, zmin, xmax, ymax, zmax} for these param values (defaults else); an end
        too large for a double is an infinity."""
        if self.bounds_trees is None:
            return None
        if self.default_box is not None and (
            not values or all(k in self.params and self.params[k] == v for k, v in values.items())
        ):
            return list(self.default_box)
        return paramvalues.box(self.params, self.bounds_trees, values)

    def check_values(self, values: Mapping[str, float], source: str, key: str) -> None:
        """With these param values every coefficient stays a finite double and the bounds an ordered box
        (paramvalues.check)."""
        paramvalues.check(self.name, self.params, self.param_terms, self.bounds_trees, values, source, key)

    def specialise(self, values: Mapping[str, float], name: str | None = None) -> Spec:
        """The same shape with the given params folded into the equation as constants."""
        return self.symbolic.specialise(self, values, name)

    @property
    def symbolic_loaded(self) -> bool:
        """Whether the symbolic part is at hand (a cached spec's is parsed only when something asks for it)."""
        return self.symbolic_part.ready

    def __repr__(self) -> str:
        return f"Spec(name={self.name!r}, degree={self.degree}, params={self.params!r})"
