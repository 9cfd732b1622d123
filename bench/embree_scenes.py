"""Scenes for the Embree adapter's checks and benchmark (tests/test_embree.py, bench/embree.py): the scene file
tests/c/embree_check.c reads, the driver built against the runtime and Embree, and the exact judge of a ray
the two tracers disagree on.

A scene is a list of Obj (a generated example shape, its params in declared order, its object -> world 3x4
matrix) plus a camera, a light, an optional ground square (Embree: two triangles; implgen's tracer: the plane
y = 0 clipped to the same square) and an optional triangle mesh (Embree only).
"""

from __future__ import annotations

import math
import subprocess
from dataclasses import dataclass, field
from fractions import Fraction
from pathlib import Path

import numpy as np

from implgen.roots.exactray import ExactJudge, Placed

ROOT = Path(__file__).resolve().parents[1]
SHAPES = ("blobs10", "chmutov8", "heart", "piriform", "sphere", "torus_y", "torus_z")  # what the driver links


@dataclass
class Obj:
    shape: str
    params: tuple[float, ...]
    m: tuple[float, ...]  # 12 values, row-major 3x4


@dataclass
class Scene:
    objects: list[Obj]
    camera: tuple[float, ...] = (0, 2.4, 7, 0, 0.6, 0, 0, 1, 0, 40)  # eye, look at, up, vertical fov
    light: tuple[float, float, float] = (4.0, 8.0, 5.0)
    ground: float = 6.0  # half size of the ground square; 0: none
    mesh: int = 0  # triangles of the Embree-only mesh; 0: none
    extra: dict = field(default_factory=dict)

    def text(self) -> str:
        lines = ["camera " + " ".join(repr(float(v)) for v in self.camera)]
        lines.append("light " + " ".join(repr(float(v)) for v in self.light))
        if self.ground:
            lines.append(f"ground {float(self.ground)!r}")
        if self.mesh:
            lines.append(f"mesh {int(self.mesh)}")
        for o in self.objects:
            lines.append(" ".join(["obj", o.shape, *(repr(float(v)) for v in (*o.params, *o.m))]))
        return "\n".join(lines) + "\n"


def placed(scale: float, rot_x: float, rot_y: float, t: tuple[float, float, float]) -> tuple[float, ...]:
    """scale * R_y(rot_y) R_x(rot_x), then a translation (degrees)."""
    a, b = math.radians(rot_y), math.radians(rot_x)
    ca, sa, cb, sb = math.cos(a), math.sin(a), math.cos(b), math.sin(b)
    r = [[ca, sa * sb, sa * cb], [0, cb, -sb], [-sa, ca * sb, ca * cb]]
    return tuple(v for i in range(3) for v in (*(scale * r[i][j] for j in range(3)), t[i]))


def showcase() -> Scene:
    """Seven shapes of degree 2 to 10 under rotations, scales and translations, on a ground square."""
    return Scene(
        [
            Obj("torus_y", (1.0, 0.3), placed(1.0, 60, 20, (-2.2, 1.1, 0.0))),
            Obj("heart", (), placed(1.0, -90, 30, (0.0, 1.05, -0.5))),
            Obj("chmutov8", (), placed(0.7, 0, 25, (2.0, 0.75, -1.4))),
            Obj("sphere", (1.0,), placed(0.5, 0, 0, (-0.6, 0.5, 1.6))),
            Obj("piriform", (), placed(1.5, 0, -40, (1.2, 0.5, 1.5))),
            Obj("blobs10", (), placed(0.4, 30, 10, (-3.2, 0.45, 1.8))),
            Obj("torus_z", (0.8, 0.2), placed(1.0, 0, 0, (3.3, 0.25, 0.5))),
        ]
    )


def grid(n: int, seed: int = 1) -> Scene:
    """n small shapes on a square grid over the ground, each turned at random (the benchmark's 1 to 10,000)."""
    rng = np.random.default_rng(seed)
    side = max(1, math.ceil(math.sqrt(n)))
    step = 8.0 / side
    objs = []
    for k in range(n):
        i, j = divmod(k, side)
        name = SHAPES[k % len(SHAPES)]
        params = {"torus_y": (1.0, 0.3), "torus_z": (1.0, 0.25), "sphere": (1.0,)}.get(name, ())
        x, z = -4.0 + step * (j + 0.5), -4.0 + step * (i + 0.5)
        objs.append(Obj(name, params, placed(0.35 * step, *rng.uniform(0, 360, 2), (x, 0.4 * step, z))))
    return Scene(objs, camera=(0, 9, 9, 0, 0, 0, 0, 1, 0, 50), ground=6.0)


def build_driver(out: Path, sanitize: bool) -> Path:
    """tests/c/embree_check.c with the runtime, the shapes it names and Embree, with the project's warnings."""
    from implgen.compile.clib import SANITIZE_FLAGS, WARNING_FLAGS, compiler
    from implgen.resources import EMBREE_SOURCES, SHAPE_SOURCES, SOLVER_SOURCES, TRACER_SOURCES, runtime_sources

    flags = list(SANITIZE_FLAGS) if sanitize else ["-O2"]
    sources = [ROOT / "tests/c/embree_check.c"]
    sources += runtime_sources(SOLVER_SOURCES, SHAPE_SOURCES, TRACER_SOURCES, EMBREE_SOURCES)
    sources += [ROOT / "generated" / f"{s}.c" for s in SHAPES]
    includes = [f"-I{ROOT / d}" for d in ("runtime_c", "generated", "tests/c")]
    cmd = [compiler(), *WARNING_FLAGS, *flags, "-pthread", *includes, "-o", str(out), *map(str, sources)]
    proc = subprocess.run([*cmd, "-lembree3", "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return out


def read_agree(path: Path, n: int) -> dict[str, np.ndarray]:
    """The agree mode's answers for n pixels (tests/c/embree_check.c's layout)."""
    raw = path.read_bytes()
    rays = np.frombuffer(raw, np.float32, 12 * n).reshape(n, 12)
    ids = np.frombuffer(raw, np.int32, 4 * n, offset=48 * n).reshape(n, 4)
    ts = np.frombuffer(raw, np.float64, 2 * n, offset=64 * n).reshape(n, 2)
    return {
        "o": rays[:, 0:3],
        "d": rays[:, 3:6],
        "so": rays[:, 6:9],
        "sd": rays[:, 9:12],
        "obj_tracer": ids[:, 0],
        "obj_embree": ids[:, 1],
        "occ_tracer": ids[:, 2],
        "occ_embree": ids[:, 3],
        "t_tracer": ts[:, 0],
        "t_embree": ts[:, 1],
    }


def exact_judge(scene: Scene) -> ExactJudge:
    """The exact judge (implgen.roots.exactray.ExactJudge) of the scene's objects, in order, the ground square
    last: each object's f(o + t d) over Q, the float ray and the double matrix taken exactly, clipped to its
    padded box exactly, roots located by Descartes and bisection."""
    from implgen.spec.entry import load_spec

    objects = []
    for o in scene.objects:
        spec = load_spec(ROOT / "examples/shapes" / f"{o.shape}.yaml")
        objects.append(Placed.of(spec, dict(zip(spec.params, o.params)), o.m))
    if scene.ground:
        h = Fraction(scene.ground)
        objects.append(Placed([((0, 1, 0), Fraction(1))], 1, [(-h, h), (Fraction(-1), Fraction(1)), (-h, h)]))
    return ExactJudge(objects)
