"""The package as a user gets it: `python -m build` makes an sdist and a wheel (the wheel built from the unpacked
sdist, in a folder that is gone afterwards) that pass `twine check`; the wheel goes into a new venv outside the
repository, and from an empty folder the tour runs: generate C, Python and GLSL for a spec the user wrote, render
a scene, mesh, share, and `implgen view --no-browser` answers on a free port. Anything that reads the source tree
instead of the installed package fails here: the folder the wheel was built in no longer exists and the working
folder is empty. The tour shares the suite's build cache (its keys are the sources' bytes, read from the installed
package), so it compiles only what the rest of the suite has not; the test without a compiler starts from none.

The new venv gets the wheel (pip, without its dependencies) and, linked in, exactly the installed distributions
its Requires-Dist names and theirs in turn -- nothing the tests alone install -- so it takes seconds, not the
minute a download of every dependency would, and a module the wheel imports without declaring it fails.

Without a C compiler (PATH holds only the venv's bin/, CC unset or a name that is not there) what needs none
still works -- Python and GLSL output, share pages -- and what needs one says so in one line naming the package
to install.
"""

from __future__ import annotations

import email.parser
import importlib.metadata
import os
import signal
import subprocess
import sys
import urllib.request
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh
from PIL import Image

from conftest import ROOT

TORUS = """\
name: ring
description: a torus about the z-axis, radii R and r
equation: (x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)
params: {R: 1.0, r: 0.35}
bounds: {x: [-R - r, R + r], y: [-R - r, R + r], z: [-r, r]}
"""
SCENE = """\
image: {width: 64, height: 48, spp: 1, max_depth: 2}
camera: {position: [0, -4, 3], look_at: [0, 0, 0], up: [0, 0, 1], fov: 40}
lights:
  - {position: [3, -5, 6], color: [1, 1, 1]}
objects:
  - {equation: z + 0.5, name: floor}
  - {shape: ring.yaml, params: {r: 0.3}}
"""


def run(cmd, *, cwd: Path | None = None, env: dict | None = None, timeout: float = 300) -> subprocess.CompletedProcess:
    return subprocess.run(list(map(str, cmd)), cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)


def ok(proc: subprocess.CompletedProcess) -> str:
    assert proc.returncode == 0, (proc.args, proc.stdout[-2000:], proc.stderr[-3000:])
    assert "Traceback" not in proc.stderr, proc.stderr[-3000:]
    assert str(ROOT) not in proc.stdout + proc.stderr, "the source tree was read"
    return proc.stdout


@pytest.fixture(scope="module")
def dist(tmp_path_factory) -> Path:
    """sdist + wheel, with the dev venv's setuptools (no download): the wheel is built from the unpacked sdist."""
    out = tmp_path_factory.mktemp("dist")
    ok(run([sys.executable, "-m", "build", "--no-isolation", "--outdir", out, ROOT], timeout=600))
    return out


def wheel_of(dist: Path) -> Path:
    (wheel,) = dist.glob("implgen-*-py3-none-any.whl")
    return wheel


def requirements(wheel: Path) -> list[str]:
    """The Requires-Dist lines of the wheel's METADATA."""
    with zipfile.ZipFile(wheel) as zf:
        (name,) = [n for n in zf.namelist() if n.endswith(".dist-info/METADATA")]
        meta = email.parser.Parser().parsestr(zf.read(name).decode())
    return meta.get_all("Requires-Dist") or []


def closure(requires: list[str]) -> dict[str, importlib.metadata.Distribution]:
    """The installed distributions these requirements name (extras and markers evaluated, no extra asked for
    the top level), and theirs, transitively: what `pip install` of the wheel would bring."""
    from packaging.requirements import Requirement
    from packaging.utils import canonicalize_name

    found: dict[str, importlib.metadata.Distribution] = {}
    todo = [(Requirement(r), "") for r in requires]
    while todo:
        req, extra = todo.pop()
        if req.marker is not None and not req.marker.evaluate({"extra": extra}):
            continue
        dist = importlib.metadata.distribution(req.name)
        key = canonicalize_name(req.name)
        asked = (key, *sorted(req.extras))
        if asked in found:
            continue
        found[asked] = dist
        for line in dist.requires or []:
            todo += [(Requirement(line), e) for e in ("", *req.extras)]
    return {canonicalize_name(d.metadata["Name"]): d for d in found.values()}


def link_distributions(dists, site: Path) -> None:
    """Each distribution's top-level files and folders (its RECORD's first path parts), linked into `site`."""
    for dist in dists:
        assert dist.files is not None, f"{dist.metadata['Name']} has no RECORD"
        tops = {f.parts[0] for f in dist.files if f.parts[0] != ".." and not f.parts[0].endswith(".pth")}
        for top in tops:
            target = Path(dist.locate_file(top))
            if target.exists() and not (site / top).exists():
                (site / top).symlink_to(target)


@pytest.fixture(scope="module")
def venv(dist, tmp_path_factory) -> Path:
    """A new venv (no pip of its own) holding the wheel and the distributions it requires."""
    home = tmp_path_factory.mktemp("venv") / "v"
    ok(run([sys.executable, "-m", "venv", "--without-pip", home]))
    site = home / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}" / "site-packages"
    assert site.is_dir()
    wheel = wheel_of(dist)
    link_distributions(closure(requirements(wheel)).values(), site)
    ok(run([sys.executable, "-m", "pip", "--python", home / "bin" / "python", "install", "-q", "--no-deps", wheel]))
    return home


def user_env(venv: Path, **extra: str) -> dict[str, str]:
    """A user's environment: the venv's bin/ first, no PYTHONPATH, the suite's build cache unless told."""
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PYTHON", "VIRTUAL_ENV", "CC"))}
    env.update(PATH=f"{venv / 'bin'}{os.pathsep}{os.environ['PATH']}", OPENBLAS_NUM_THREADS="1")
    return env | extra


@pytest.fixture(scope="module")
def tour(venv, tmp_path_factory) -> tuple[Path, dict]:
    """An empty folder holding only the spec and the scene a user wrote, and the user's environment."""
    work = tmp_path_factory.mktemp("empty")
    (work / "ring.yaml").write_text(TORUS)
    (work / "scene.yaml").write_text(SCENE)
    return work, user_env(venv)


def test_sdist_and_wheel_pass_twine_check_and_carry_the_license(dist):
    ok(run([sys.executable, "-m", "twine", "check", "--strict", *sorted(dist.iterdir())]))
    (sdist,) = dist.glob("implgen-*.tar.gz")
    with zipfile.ZipFile(wheel_of(dist)) as zf:
        names = zf.namelist()
        meta = zf.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
        licence = zf.read(next(n for n in names if n.endswith(".dist-info/licenses/LICENSE"))).decode()
    assert licence == (ROOT / "LICENSE").read_text()
    assert "\nLicense-Expression: MIT\n" in meta and "\nRequires-Python: >=3.11\n" in meta
    assert "implgen/runtime_c/roots.h" in names and "implgen/templates/c/shape.c.j2" in names
    assert "implgen/notebook/static/widget.js" in names and "implgen/share/static/surface.js" in names
    assert not any(n.startswith("tests/") for n in names)
    assert sdist.stat().st_size > 0


def test_the_venv_runs_the_installed_package_not_the_tree(venv, tour):
    work, env = tour
    where = ok(
        run([venv / "bin" / "python", "-c", "import implgen, numpy; print(implgen.__file__)"], cwd=work, env=env)
    )
    assert Path(where.strip()).is_relative_to(venv), where
    # what the tests alone install is not there; the notebook widget says which extra brings it
    gone = run([venv / "bin" / "python", "-c", "import pytest"], cwd=work, env=env)
    assert gone.returncode != 0
    show = "import implgen\ntry:\n    implgen.show('x')\nexcept implgen.UserError as err:\n    print(err)"
    assert ok(run([venv / "bin" / "python", "-c", show], cwd=work, env=env)).strip() == (
        "implgen.show: needs anywidget: pip install 'implgen[notebook]'"
    )


def test_generate_c_python_glsl_and_use_the_python(venv, tour):
    work, env = tour
    ok(run(["implgen", "ring.yaml", "--lang", "all", "-o", "gen"], cwd=work, env=env))
    assert sorted(p.name for p in (work / "gen").iterdir()) == ["ring.c", "ring.glsl", "ring.h", "ring.py"]
    hit = "import numpy as np, ring; print(ring.intersect([0, 0, -5], [0, 0, 1], 0.0, np.inf, R=0.0))"
    # R = 0: a ball of radius r; the ray from z = -5 meets it at t = 5 - r
    assert float(ok(run([venv / "bin" / "python", "-c", hit], cwd=work / "gen", env=env))) == pytest.approx(4.65)


def test_render_a_scene(tour):
    work, env = tour
    ok(run(["implgen", "render", "scene.yaml", "-o", "pic.png"], cwd=work, env=env))
    pixels = np.asarray(Image.open(work / "pic.png").convert("RGB"))
    assert pixels.shape == (48, 64, 3)
    assert len(np.unique(pixels.reshape(-1, 3), axis=0)) > 20  # a shaded torus on a floor, not one colour


def test_mesh_is_a_closed_torus(tour):
    work, env = tour
    ok(run(["implgen", "mesh", "ring.yaml", "--cells", "24", "-o", "ring.stl"], cwd=work, env=env))
    mesh = trimesh.load(work / "ring.stl")
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.euler_number == 0  # genus 1
    assert mesh.volume == pytest.approx(2 * np.pi**2 * 1.0 * 0.35**2, rel=0.05)


def test_share_page(tour):
    work, env = tour
    ok(run(["implgen", "share", "ring.yaml", "-o", "ring.html"], cwd=work, env=env))
    page = (work / "ring.html").read_text()
    assert page.startswith("<!DOCTYPE html>") and "ring" in page and str(ROOT) not in page


def test_view_answers_on_a_free_port(tour):
    work, env = tour
    cmd = ["implgen", "view", "ring.yaml", "--no-browser", "--port", "0"]
    proc = subprocess.Popen(cmd, cwd=work, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        assert "http://127.0.0.1:" in line, (line, proc.stderr.read() if proc.poll() is not None else "")
        url = "http://" + line.split("http://", 1)[1].split()[0]
        with urllib.request.urlopen(url, timeout=30) as reply:
            assert reply.status == 200 and b"<html" in reply.read().lower()
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(30)


def test_without_a_compiler(venv, tmp_path):
    """PATH holds only the venv's bin/ (no cc, no gcc) and the build cache starts empty. What needs no compiler
    works; rendering and meshing say in one line which package to install, and leave nothing behind; so does a
    CC that names no program."""
    (tmp_path / "ring.yaml").write_text(TORUS)
    (tmp_path / "scene.yaml").write_text(SCENE)
    env = user_env(venv, PATH=str(venv / "bin"), IMPLGEN_CACHE=str(tmp_path / "cache"))
    ok(run(["implgen", "ring.yaml", "--lang", "all", "-o", "gen"], cwd=tmp_path, env=env))
    assert {p.suffix for p in (tmp_path / "gen").iterdir()} == {".c", ".h", ".py", ".glsl"}
    ok(run(["implgen", "share", "ring.yaml", "-o", "ring.html"], cwd=tmp_path, env=env))
    for cmd, cc in (
        ("render scene.yaml -o pic.png", None),
        ("mesh ring.yaml -o r.stl", None),
        ("mesh ring.yaml -o r.stl", "gcc-none"),
    ):
        proc = run(["implgen", *cmd.split()], cwd=tmp_path, env=env | ({"CC": cc} if cc else {}))
        assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr[-3000:]
        assert f"no C compiler found (tried '{cc or 'cc'}')" in proc.stderr, proc.stderr
        assert "apt-get install gcc" in proc.stderr, proc.stderr
        assert not (tmp_path / cmd.split()[-1]).exists()


def test_example_shapes_are_found_away_from_a_clone(tmp_path, monkeypatch):
    """`implgen bench solvers` and `implgen demo` started where there is no examples/shapes/ take the same specs
    installed with the package."""
    from implgen import demo
    from implgen.measure.cases.polys import find_shapes_dir
    from implgen.resources import gallery_dir

    monkeypatch.chdir(tmp_path)
    assert find_shapes_dir() == gallery_dir()
    names = sorted(p.name for p in gallery_dir().glob("*.yaml"))
    assert names == sorted(p.name for p in (ROOT / "examples" / "shapes").glob("*.yaml"))
    (tmp_path / "shapes").mkdir()
    (tmp_path / "shapes" / "ring.yaml").write_text(TORUS)
    monkeypatch.setattr(demo, "gallery_dir", lambda: tmp_path / "shapes")  # one shape, not all of them
    assert demo.main(["-o", "out"]) == 0
    assert (tmp_path / "out" / "generated" / "ring.py").is_file()
