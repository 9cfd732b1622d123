"""The build cache is code (it holds the libraries implgen loads), so it is held to the project's rule: nothing
is loaded unless this user owns it, nobody else can write it, and it is the entry built for this source
(generator/implgen/cachedir.py, compile/clib.py, compile/cachesize.py): what a hostile or broken cache folder must
never make us load or run.

Run as the user runs it where the contract is the command's (`implgen render`, `implgen cache`: exit status 2,
one line, no traceback), in process where a test needs to look inside (which library is loaded, eviction).
Each test gets its own copy of one cache warmed once for the module, so the C runtime compiles once.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from implgen_proc import Ran, assert_one_line

ROOT = Path(__file__).resolve().parent.parent
SPHERE = ROOT / "examples" / "shapes" / "sphere.yaml"

SCENE = f"""image: {{width: 8, height: 6, spp: 1, max_depth: 2}}
camera: {{position: [0, 2, 6], look_at: [0, 0, 0], fov: 40}}
lights: [{{position: [2, 8, 4]}}]
objects: [{{shape: {SPHERE}}}]
"""

PAYLOAD = r"""
#include <stdio.h>
__attribute__((constructor)) static void planted(void) {
    FILE *f = fopen(MARKER, "w");
    if (f) { fputs("ran\n", f); fclose(f); }
}
int rt_scene_new(void) { return 0; }
"""


def scene_with_equation(folder: Path, equation: str) -> Path:
    """A scene whose one shape is an inline equation (a new one compiles a new shape and links a library)."""
    path = folder / f"s{abs(hash(equation)) % 10**8}.yaml"
    path.write_text(SCENE.replace(f"{{shape: {SPHERE}}}", f'{{equation: "{equation}", name: "probe"}}'))
    return path


def render(cache: Path, scene: Path, out: Path, **env: str) -> subprocess.CompletedProcess:
    """`implgen render` in a child process, as a user runs it."""
    full = dict(os.environ, IMPLGEN_CACHE=str(cache), **env)
    cmd = [sys.executable, "-m", "implgen.cli", "render", str(scene), "-o", str(out), "-q"]
    return subprocess.run(cmd, capture_output=True, text=True, env=full, timeout=600)


def cache_command(cache: Path, *args: str, **env: str) -> subprocess.CompletedProcess:
    full = dict(os.environ, IMPLGEN_CACHE=str(cache), **env)
    cmd = [sys.executable, "-m", "implgen.cli", "cache", *args]
    return subprocess.run(cmd, capture_output=True, text=True, env=full, timeout=120)


def one_line_error(proc: subprocess.CompletedProcess, *fragments: str) -> str:
    """The bad-input contract (implgen_proc.assert_one_line): exit status 2, one line on stderr saying each
    fragment, no traceback. Returns the line."""
    assert_one_line(Ran(proc.returncode, proc.stdout, proc.stderr, 0.0), *fragments)
    return proc.stderr.strip()


def libraries(cache: Path) -> list[Path]:
    """The cache's scene libraries, wherever the layout keeps them."""
    return sorted(cache.rglob("scene-*.so"))


@pytest.fixture(scope="module")
def warm(tmp_path_factory) -> tuple[Path, Path]:
    """(a cache holding the built sphere scene, the scene file), built once for the module."""
    folder = tmp_path_factory.mktemp("warm")
    scene = folder / "sphere_scene.yaml"
    scene.write_text(SCENE)
    proc = render(folder / "cache", scene, folder / "out.png")
    assert proc.returncode == 0, proc.stderr
    return folder / "cache", scene


@pytest.fixture
def cache(warm, tmp_path: Path, monkeypatch) -> Path:
    """A private copy of the warm cache, also this process's $IMPLGEN_CACHE."""
    copy = tmp_path / "cache"
    shutil.copytree(warm[0], copy, symlinks=True)
    monkeypatch.setenv("IMPLGEN_CACHE", str(copy))
    monkeypatch.delenv("IMPLGEN_CACHE_MAX_MB", raising=False)
    return copy


@pytest.fixture
def scene(warm) -> Path:
    return warm[1]


def payload_library(folder: Path, marker: Path) -> Path:
    """A valid shared library whose constructor writes `marker` when it is loaded."""
    from implgen.compile.clib import compiler

    src = folder / "payload.c"
    src.write_text(PAYLOAD)
    out = folder / "payload.so"
    cmd = [compiler(), "-shared", "-fPIC", f'-DMARKER="{marker}"', "-o", str(out), str(src)]
    subprocess.run(cmd, check=True, capture_output=True)
    return out


# ------------------------------------------------------------------------------------------ the folder


def test_the_folder_and_its_subfolders_are_created_0700_and_entries_0600(tmp_path: Path, scene: Path) -> None:
    cache = tmp_path / "new" / "cache"
    old = os.umask(0)  # the most permissive umask: the modes must not come from it
    try:
        proc = render(cache, scene, tmp_path / "out.png")
    finally:
        os.umask(old)
    assert proc.returncode == 0, proc.stderr
    folders = [cache, *(p for p in cache.rglob("*") if p.is_dir())]
    assert {oct(p.stat().st_mode & 0o777) for p in folders} == {oct(0o700)}
    files = [p for p in cache.rglob("*") if p.is_file()]
    assert files and {oct(p.stat().st_mode & 0o777) for p in files} == {oct(0o600)}


@pytest.mark.parametrize("mode", [0o777, 0o770, 0o702])
def test_a_cache_others_can_write_is_refused(cache: Path, scene: Path, tmp_path: Path, mode: int) -> None:
    cache.chmod(mode)
    line = one_line_error(render(cache, scene, tmp_path / "out.png"), "IMPLGEN_CACHE", "writable", "chmod go-w")
    assert str(cache) in line
    assert not (tmp_path / "out.png").exists()


def test_a_subfolder_others_can_write_is_refused(cache: Path, scene: Path, tmp_path: Path) -> None:
    lib = libraries(cache)[0].parent
    lib.chmod(0o777)
    one_line_error(render(cache, scene, tmp_path / "out.png"), "IMPLGEN_CACHE", str(lib), "writable")


def test_a_link_in_place_of_a_subfolder_is_refused(cache: Path, scene: Path, tmp_path: Path) -> None:
    lib = libraries(cache)[0].parent
    elsewhere = tmp_path / "elsewhere"
    shutil.move(lib, elsewhere)
    lib.symlink_to(elsewhere)
    one_line_error(render(cache, scene, tmp_path / "out.png"), "IMPLGEN_CACHE", "symbolic link")


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() != 0, reason="needs root to give a folder away")
@pytest.mark.parametrize("which", ["root", "lib", "spec"])
def test_a_cache_owned_by_another_user_is_refused(cache: Path, scene: Path, tmp_path: Path, which: str) -> None:
    import pwd

    nobody = pwd.getpwnam("nobody").pw_uid
    folder = {"root": cache, "lib": libraries(cache)[0].parent, "spec": cache / "spec"}[which]
    os.chown(folder, nobody, -1)
    line = one_line_error(render(cache, scene, tmp_path / "out.png"), "IMPLGEN_CACHE", f"user id {nobody}")
    assert str(folder) in line


# ------------------------------------------------------------------------------------------ the entries


def test_a_replaced_library_is_rebuilt_not_loaded(cache: Path, scene: Path, tmp_path: Path) -> None:
    """Another valid library in place of the built one (same name, ours, 0600): its constructor must not run."""
    (lib,) = libraries(cache)
    original = lib.read_bytes()
    marker = tmp_path / "PWNED"
    shutil.copyfile(payload_library(tmp_path, marker), lib)
    proc = render(cache, scene, tmp_path / "out.png")
    assert proc.returncode == 0, proc.stderr
    assert not marker.exists(), "the planted library was loaded"
    assert lib.read_bytes() == original  # linked again from the cached objects


def test_a_library_changed_after_it_was_planned_is_not_loaded(cache: Path, tmp_path: Path) -> None:
    """clib.load checks again right before dlopen: a library swapped after the build is refused, one line."""
    from implgen.compile import clib
    from implgen.errors import UserError

    (lib,) = libraries(cache)
    marker = tmp_path / "PWNED"
    shutil.copyfile(payload_library(tmp_path, marker), lib)
    with pytest.raises(UserError, match="not loaded"):
        clib.load(lib)
    assert not marker.exists()


def test_a_sealed_library_under_another_name_is_not_loaded(cache: Path, tmp_path: Path) -> None:
    """An entry with its own good seal, renamed to another key's name: not the entry built for that source."""
    from implgen.compile import clib
    from implgen.errors import UserError

    (lib,) = libraries(cache)
    other = lib.with_name("scene-" + "0" * 32 + ".so")
    shutil.copyfile(lib, other)
    shutil.copyfile(lib.with_name(lib.name + ".sha256"), other.with_name(other.name + ".sha256"))
    with pytest.raises(UserError, match="not loaded"):
        clib.load(other)


@pytest.mark.parametrize("damage", ["truncated", "empty", "no_seal", "other_owner", "group_writable", "link"])
def test_a_broken_library_is_rebuilt(cache: Path, scene: Path, tmp_path: Path, damage: str) -> None:
    (lib,) = libraries(cache)
    original = lib.read_bytes()
    if damage == "truncated":
        lib.write_bytes(original[: len(original) // 3])
    elif damage == "empty":
        lib.write_bytes(b"")
    elif damage == "no_seal":
        lib.with_name(lib.name + ".sha256").unlink()
    elif damage == "other_owner":
        if os.geteuid() != 0:
            pytest.skip("needs root to give a file away")
        os.chown(lib, 65534, -1)
    elif damage == "group_writable":
        lib.chmod(0o660)
    elif damage == "link":
        kept = tmp_path / "kept.so"
        lib.rename(kept)
        lib.symlink_to(kept)
    proc = render(cache, scene, tmp_path / "out.png")
    assert proc.returncode == 0, proc.stderr
    assert lib.is_file() and not lib.is_symlink() and lib.read_bytes() == original
    assert lib.stat().st_uid == os.geteuid() and lib.stat().st_mode & 0o777 == 0o600


def test_a_broken_object_or_generated_source_is_rebuilt(cache: Path, scene: Path, tmp_path: Path) -> None:
    """With the library gone the objects are linked again: an empty object and a truncated generated source
    are made again, not linked or compiled as they are (the truncated C would not compile)."""
    (lib,) = libraries(cache)
    original = lib.read_bytes()
    lib.unlink()
    obj = sorted((cache / "obj").glob("sphere-*.o"))[0]
    obj.write_bytes(b"")
    source = sorted((cache / "gen").glob("*/sphere.c"))[0]
    source.write_bytes(source.read_bytes()[:100])
    proc = render(cache, scene, tmp_path / "out.png")
    assert proc.returncode == 0, proc.stderr
    assert obj.stat().st_size > 0 and lib.read_bytes() == original


def test_the_solver_library_loads_through_the_checks(cache: Path) -> None:
    from implgen.roots import solvers

    solvers.library.cache_clear()
    try:
        assert list(solvers.real_roots([-2.0, 0.0, 1.0])) == pytest.approx([-(2**0.5), 2**0.5])
        (roots,) = sorted((cache / "lib").glob("roots-*.so"))
        assert roots.with_name(roots.name + ".sha256").exists()
    finally:
        solvers.library.cache_clear()


# ------------------------------------------------------------------------------------------ the compiler


def test_a_failing_compiler_is_one_line_naming_cc(cache: Path, tmp_path: Path) -> None:
    scene = scene_with_equation(tmp_path, "x + 0.375*y")
    line = one_line_error(render(cache, scene, tmp_path / "out.png", CC="false"), "CC", "false", "failed")
    assert "exit status 1" in line


def test_a_compiler_that_fails_after_writing_leaves_no_temporary_file(cache: Path, tmp_path: Path) -> None:
    """A compiler that writes half an object and then fails: one line, and its output is removed (nothing named
    .tmp-*, no object), so no later build can take it for an entry."""
    cc = tmp_path / "halfcc"
    log = tmp_path / "written.txt"
    write = f'[ "$1" = -o ] && echo half > "$2" && echo "$2" >> {log}'
    cc.write_text(f"#!/bin/sh\nwhile [ $# -gt 0 ]; do {write}; shift; done\nexit 1\n")
    cc.chmod(0o700)
    before = {p for p in cache.rglob("*") if p.suffix in (".o", ".so")}
    scene = scene_with_equation(tmp_path, "x + 0.4375*y")
    one_line_error(render(cache, scene, tmp_path / "out.png", CC=str(cc)), "CC", "halfcc", "failed")
    after = {p for p in cache.rglob("*") if p.suffix in (".o", ".so") or p.name.startswith(".tmp-")}
    written = log.read_text().split()
    assert written and all(Path(w).name.startswith(".tmp-") for w in written)  # it did write, under a temp name
    assert after == before


def test_unlink_quietly_removes_files_and_links_never_their_targets(tmp_path: Path) -> None:
    from implgen.cachedir import unlink_quietly

    (tmp_path / "f").write_text("x")
    (tmp_path / "target").write_text("keep")
    (tmp_path / "link").symlink_to(tmp_path / "target")
    (tmp_path / "folder").mkdir()
    for name in ("f", "link", "gone", "folder"):
        unlink_quietly(tmp_path / name)  # a missing file or a folder: no error
    assert sorted(p.name for p in tmp_path.iterdir()) == ["folder", "target"]
    assert (tmp_path / "target").read_text() == "keep"


def test_a_compiler_that_writes_nothing_caches_nothing(cache: Path, tmp_path: Path) -> None:
    before = {p for p in cache.rglob("*") if p.suffix in (".o", ".so")}
    scene = scene_with_equation(tmp_path, "x + 0.625*y")
    one_line_error(render(cache, scene, tmp_path / "out.png", CC="true"), "CC", "wrote nothing")
    after = {p for p in cache.rglob("*") if p.suffix in (".o", ".so") or p.name.startswith(".tmp-")}
    assert after == before  # no empty object or library, no temporary file left behind
    # the real compiler afterwards builds it
    proc = render(cache, scene, tmp_path / "out.png")
    assert proc.returncode == 0, proc.stderr


def test_a_bad_size_bound_is_one_line(cache: Path, scene: Path, tmp_path: Path) -> None:
    proc = render(cache, scene, tmp_path / "out.png", IMPLGEN_CACHE_MAX_MB="lots")
    one_line_error(proc, "IMPLGEN_CACHE_MAX_MB", "megabytes")


# ------------------------------------------------------------------------------------------ the bound


def _size(cache: Path) -> int:
    from implgen.compile import cachesize

    return sum(u.size for u in cachesize.inventory(cache))


def _age_everything(cache: Path, seconds: float = 3600) -> None:
    """As if the cache had been filled an hour ago, by other processes."""
    past = time.time() - seconds
    for p in [cache, *cache.rglob("*")]:
        os.utime(p, (past, past), follow_symlinks=False)


def test_the_cache_stays_within_its_bound_and_keeps_the_library_in_use(
    cache: Path, tmp_path: Path, monkeypatch
) -> None:
    """As the viewer does: one equation after another, each library loaded and the previous one let go. The
    cache stays within a 1 MB bound (it grew by ~0.26 MB per equation, for ever); the library held from the
    start and the current one stay."""
    import gc

    from implgen import cachedir
    from implgen.compile import clib
    from implgen.scene import build
    from implgen.scene.load import load_scene

    (warm_lib,) = libraries(cache)
    held = clib.load(warm_lib)  # in use by this process throughout
    _age_everything(cache)
    monkeypatch.setattr(cachedir, "used_here", set())
    bound_mb = 1.0
    monkeypatch.setenv("IMPLGEN_CACHE_MAX_MB", str(bound_mb))
    built, current = [], None
    for k, eq in enumerate(["x + 0.25*y", "x + 0.5*y", "y - 0.25*z", "z + 0.75*x", "x - 0.125*z"]):
        lib = build.build_scene(load_scene(scene_with_equation(tmp_path, eq))).library
        current = None  # the previous equation's library is let go, as the viewer's document does
        gc.collect()
        current = clib.load(lib)
        built.append(lib)
        assert _size(cache) <= bound_mb * 1e6, f"over the bound after build {k}"
        assert warm_lib.exists() and lib.exists()  # the library in use and the one just built
    assert held is not None and current is not None
    assert not all(p.exists() for p in built[:-1])  # older ones were evicted


def test_old_entries_are_evicted_least_recently_used_first(cache: Path, tmp_path: Path, monkeypatch) -> None:
    from implgen import cachedir
    from implgen.compile import cachesize

    monkeypatch.setattr(cachedir, "used_here", set())
    _age_everything(cache)
    (lib,) = libraries(cache)
    os.utime(lib)  # used just now by another process: protected for a minute
    objs = sorted((cache / "obj").glob("*.o"), key=lambda p: p.stat().st_size)
    os.utime(objs[0], (time.time() - 60, time.time() - 60))  # the most recently used of the old ones
    removed = cachesize.evict(bound=lib.stat().st_size + objs[0].stat().st_size + 2000)
    assert removed and lib.exists() and objs[0].exists()
    assert [u.mtime for u in removed] == sorted(u.mtime for u in removed)


# ------------------------------------------------------------------------------------------ implgen cache


def test_cache_info_and_clear(cache: Path, tmp_path: Path) -> None:
    outside = tmp_path / "outside"
    outside.mkdir()
    (outside / "precious.so").write_bytes(b"keep me")
    (cache / "notes.txt").write_text("mine")  # not a name of the layout: left alone
    (cache / "obj" / "mine.o").write_bytes(b"mine")
    (cache / "lib" / ("scene-" + "1" * 32 + ".so")).symlink_to(outside / "precious.so")
    (cache / "glue").rename(tmp_path / "glue_moved")
    (cache / "glue").symlink_to(outside)  # a link in place of a subfolder: removed, not followed
    info = cache_command(cache, "info")
    assert info.returncode == 0, info.stderr
    for word in ("lib", "obj", "gen", "spec", "total", "bound 500.0 MB", str(cache)):
        assert word in info.stdout, info.stdout
    cleared = cache_command(cache, "clear")
    assert cleared.returncode == 0, cleared.stderr
    assert "removed" in cleared.stdout
    left = sorted(str(p.relative_to(cache)) for p in cache.rglob("*"))
    assert left == ["notes.txt", "obj", "obj/mine.o"]
    assert (outside / "precious.so").read_bytes() == b"keep me"
    again = cache_command(cache, "info")
    assert "total: 0 entries" in again.stdout


def test_cache_commands_refuse_a_folder_others_can_write(cache: Path) -> None:
    cache.chmod(0o777)
    for what in ("info", "clear"):
        one_line_error(cache_command(cache, what), "IMPLGEN_CACHE", "writable")
    assert libraries(cache)  # nothing removed


def test_cache_command_usage_is_one_line(cache: Path) -> None:
    one_line_error(cache_command(cache, "purge"), "cache", "info, clear")


def test_the_exact_reference_cache_is_data_never_a_pickle(tmp_path: Path, monkeypatch) -> None:
    """measure/cases/reference.py keeps its exact roots as JSON numbers: a pickle (code, when loaded) planted under the
    entry's name is not read, and neither is a file others can write; both are computed again."""
    import pickle

    import numpy as np

    from implgen.measure.cases import reference

    monkeypatch.setenv("IMPLGEN_CACHE", str(tmp_path / "cache"))
    coeffs = np.array([[-2.0, 0.0, 1.0], [6.0, -5.0, 1.0]])  # roots +-sqrt(2); 2 and 3
    first = reference.reference(coeffs, workers=1)
    path = reference._cache_file(coeffs)
    assert path.suffix == ".json" and [[r.value for r in row] for row in first] == [[-(2**0.5), 2**0.5], [2.0, 3.0]]
    marker = tmp_path / "ran"
    path.write_bytes(pickle.dumps(f"print(open({str(marker)!r}, 'w'))"))
    again = reference.reference(coeffs, workers=1)
    assert not marker.exists() and [[r.value for r in row] for row in again] == [[-(2**0.5), 2**0.5], [2.0, 3.0]]
    path.write_text("[[[9.0, 1, 1.0]], [[9.0, 1, 1.0]]]")  # well-formed, but writable by others
    os.chmod(path, 0o666)
    assert reference.reference(coeffs, workers=1)[0][0].value == -(2**0.5)
