"""The public API is `from implgen import ...`: every name resolves to the object its module defines, and
importing the package itself loads none of the heavy dependencies."""

from __future__ import annotations

import importlib
import subprocess
import sys

import implgen


def test_every_public_name_resolves_to_its_module_object():
    for name in implgen.__all__:
        module = importlib.import_module(implgen._API[name])
        assert getattr(implgen, name) is getattr(module, name), name
    assert set(dir(implgen)) >= set(implgen.__all__)


def test_the_api_works_end_to_end(tmp_path):
    spec = implgen.parse_spec({"name": "ball", "equation": "x^2 + y^2 + z^2 - 4"}, "<t>")
    assert set(implgen.generate(spec, ("c",))) == {"ball.h", "ball.c"}
    assert list(implgen.real_roots([-4.0, 0.0, 1.0])) == [-2.0, 2.0]


def test_importing_the_package_is_cheap():
    code = "import sys, implgen; print(sorted(m for m in ('sympy', 'numpy', 'jinja2', 'yaml') if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
