"""The Blender add-on (blender/implgen_blender/, docs/blender.md): its plain-Python half (params, the spec it writes,
`implgen mesh`'s one line, the OBJ read back) here without Blender, its zip as `make blender-addon` builds it, and
the add-on itself in Debian's Blender, headless (tests/blender_addon_check.py): installed and enabled as a user
does, a torus added through the operator, closed, with Euler characteristic 0, the same mesh `implgen mesh`
writes; bad input one line in Blender's report, no traceback, no object."""

from __future__ import annotations

import ast
import importlib.util
import json
import os
import subprocess
import tomllib
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from hypothesis import given, settings
from hypothesis import strategies as st

import implgen
from conftest import ROOT
from implgen_proc import IMPLGEN

ADDON = ROOT / "blender" / "implgen_blender"
TORUS = "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)"


def _module(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


surface = _module("implgen_blender_surface", ADDON / "surface.py")
build_addon = _module("implgen_blender_build", ROOT / "blender" / "build_addon.py")


@pytest.mark.parametrize(
    ("text", "values"),
    [("", {}), ("a=1, b=0.3", {"a": 1.0, "b": 0.3}), (" r = -2e-1 ,", {"r": -0.2}), ("_k=3", {"_k": 3.0})],
)
def test_params_as_on_the_command_line(text, values):
    assert surface.parse_params(text) == values


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("a", "params: 'a' is not NAME=VALUE"),
        ("1a=2", "params: '1a=2' is not NAME=VALUE"),
        ("a=__import__('os')", "params: a: \"__import__('os')\" is not a number"),
        ("a=nan", "params: a: 'nan' is not a finite number"),
        ("a=1, a=2", "params: a is given twice"),
        ("a=1" + " " * 5000, "params: longer than 4096 characters"),
    ],
)
def test_bad_params_are_one_line(text, message):
    with pytest.raises(surface.SurfaceError) as err:
        surface.parse_params(text)
    assert str(err.value) == message


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.text(alphabet=st.sampled_from("ab_1.=, -+e\tnaifx\u00e9\u2028\"'"), max_size=40) | st.text(max_size=40))
def test_any_params_text_is_numbers_or_one_line(text):
    """Whatever is typed into the Params field: finite numbers under identifiers, or one line saying what is
    wrong -- never another exception."""
    try:
        values = surface.parse_params(text)
    except surface.SurfaceError as err:
        assert str(err).startswith("params: ") and "\n" not in str(err).replace("\\n", "")
        return
    assert all(surface.NAME.match(k) and np.isfinite(v) for k, v in values.items())


def test_the_mesh_is_what_implgen_mesh_writes(tmp_path):
    verts, faces = surface.mesh(IMPLGEN, TORUS, "R=1, r=0.35", 24, "sphere:3")
    spec = tmp_path / "ring.yaml"
    spec.write_text(json.dumps({"name": "ring", "equation": TORUS, "params": {"R": 1, "r": 0.35}}))
    subprocess.run([IMPLGEN, "mesh", spec, "--cells", "24", "--clip", "sphere:3", "-o", tmp_path / "r.ply"], check=True)
    reference = trimesh.load(tmp_path / "r.ply")
    assert len(verts) == len(reference.vertices) and len(faces) == len(reference.faces)
    assert np.allclose(np.array(verts), reference.vertices) and np.array_equal(np.array(faces), reference.faces)


@pytest.mark.parametrize(
    ("equation", "clip", "message"),
    [
        ("x^2 + w", "sphere:3", "equation: unknown symbol 'w' at column 7 (known: x, y, z)"),
        ('x"}, "bounds": {"x": [0, 1]}, "z": {"y', "sphere:3", "equation:"),  # text stays text in the spec
        ("x^2 + y^2 - 1", "", "the shape is unbounded along some axis"),
        ("x^2 + y^2 + z^2 - 1", "cube:2", "--clip cube:2: expected sphere:R or box:H"),
        ("  ", "sphere:3", "equation: empty"),
    ],
)
def test_refusals_are_implgens_one_line_without_the_temporary_file(equation, clip, message):
    with pytest.raises(surface.SurfaceError) as err:
        surface.mesh(IMPLGEN, equation, "", 16, clip)
    text = str(err.value)
    assert text.startswith(message) and "\n" not in text and "implgen-blender-" not in text, text


def test_the_program_is_found_or_named(tmp_path, monkeypatch):
    assert surface.find_implgen(IMPLGEN) == IMPLGEN
    with pytest.raises(surface.SurfaceError, match="is not a program"):
        surface.find_implgen(str(tmp_path / "implgen"))
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(surface.SurfaceError, match="^implgen not found on PATH: pip install implgen"):
        surface.find_implgen("")


def test_the_zip_is_an_addon_and_an_extension(tmp_path):
    """One folder holding the add-on, the manifest and the license; bl_info for Blender 3.4, the manifest for
    4.2+, both with implgen's version."""
    target = build_addon.build(tmp_path / "implgen_blender.zip")
    with zipfile.ZipFile(target) as zf:
        assert sorted(zf.namelist()) == [
            f"implgen_blender/{n}" for n in ("LICENSE", "__init__.py", "blender_manifest.toml", "surface.py")
        ]
        manifest = tomllib.loads(zf.read("implgen_blender/blender_manifest.toml").decode())
        init = ast.parse(zf.read("implgen_blender/__init__.py").decode())
    assert target.read_bytes() == build_addon.build(tmp_path / "again.zip").read_bytes()
    bl_info = next(
        ast.literal_eval(node.value)
        for node in init.body
        if isinstance(node, ast.Assign) and getattr(node.targets[0], "id", "") == "bl_info"
    )
    assert bl_info["blender"] == (3, 4, 0) and bl_info["location"] == "View3D > Add > Mesh > Implicit surface"
    version = tuple(int(p) for p in implgen.__version__.split("."))
    assert bl_info["version"] == version and manifest["version"] == implgen.__version__
    assert manifest["id"] == "implgen_blender" and manifest["type"] == "add-on"
    assert manifest["license"] == ["SPDX:MIT"] and manifest["blender_version_min"] == "4.2.0"
    assert len(manifest["tagline"]) <= 64


@pytest.mark.needs_program("blender")
def test_in_blender_headless(tmp_path):
    zip_path = build_addon.build(tmp_path / "implgen_blender.zip")
    result = tmp_path / "result.json"
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "scripts"), BLENDER_USER_CONFIG=str(tmp_path / "cfg"))
    cmd = ["blender", "-b", "--factory-startup", "--python", ROOT / "tests" / "blender_addon_check.py"]
    cmd += ["--", zip_path, IMPLGEN, result]
    proc = subprocess.run(list(map(str, cmd)), capture_output=True, text=True, env=env, timeout=600)
    assert proc.returncode == 0 and result.is_file(), proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "Traceback" not in proc.stdout + proc.stderr, proc.stdout[-3000:] + proc.stderr[-3000:]
    out = json.loads(result.read_text())
    assert out["menu"] and out["status"] == ["FINISHED"]
    (torus,) = out["added"]
    assert torus["in_scene"] and torus["triangles"] and torus["manifold"] and torus["contiguous"]
    assert torus["vertices"] - torus["edges"] + torus["faces"] == 0  # closed, genus 1
    assert torus["volume"] == pytest.approx(2 * np.pi**2 * 0.35**2, rel=0.06)  # > 0: normals outward
    errors = out["errors"]
    assert errors["equation"] == "Error: equation: unknown symbol 'w' at column 7 (known: x, y, z)\n"
    assert errors["params"] == "Error: params: a: 'one' is not a number\n"
    assert errors["clip"].startswith("Error: --clip cube:2: expected sphere:R or box:H")
    assert errors["unbounded"].startswith("Error: the shape is unbounded along some axis")
    assert errors["program"] == "Error: implgen: '/nonexistent/implgen' (the add-on's preferences) is not a program\n"
    assert all(e.count("\n") == 1 for e in errors.values()) and out["objects_after_errors"] == 0
