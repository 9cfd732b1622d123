"""The C/Python boundary has one source of truth, the runtime headers: a probe compiled against them prints
what the compiler sees (sizeof, offsetof, the values of the limits and enums), and implgen.abi -- which reads
the same headers as text -- must agree. Also: every runtime C file belongs to exactly one library list."""

from __future__ import annotations

import ctypes

import numpy as np

from conftest import RUNTIME, compile_c, run_c
from implgen import abi, resources
from implgen.roots.solvers import METHODS
from implgen.scene.load import MAX_CSG_DEPTH, MAX_DEPTH, MAX_SPP
from implgen.scene.model import Material
from implgen.scene.tracer import OPS, RtHit
from implgen.spec.parse import MAX_DEGREE


def _probe(tmp_path, body: list[str]) -> dict[str, int]:
    # every header that stands alone (has an include guard); body fragments are included by their .c only
    headers = [h.name for h in sorted(RUNTIME.glob("*.h")) if "#ifndef IMPLGEN_" in h.read_text()]
    includes = "".join(f'#include "{h}"\n' for h in headers)
    src = tmp_path / "probe.c"
    src.write_text(
        "#include <stddef.h>\n#include <stdio.h>\n"
        + includes
        + "int main(void)\n{\n"
        + "\n".join(body)
        + "\n    return 0;\n}\n"
    )
    exe = compile_c(tmp_path / "probe", [src], sanitize=False)
    out = run_c(exe)
    return {k: int(v) for k, v in (line.split() for line in out.splitlines())}


def test_limits_and_enums_match_what_the_compiler_sees(tmp_path):
    names = sorted(abi.constants())
    assert {
        "IG_MAX_DEGREE",
        "RT_MAX_CSG_DEPTH",
        "RT_MAX_DEPTH",
        "RT_MAX_SPP",
        "RT_MATERIAL_DOUBLES",
        "RT_UNION",
        "IG_ROOTS_AUTO",
        "IG_ROOTS_CLOSED_PLAIN",
        "RT_NSTATS",
    } <= set(names)
    seen = _probe(tmp_path, [f'    printf("{n} %ld\\n", (long)({n}));' for n in names])
    assert seen == abi.constants()
    assert MAX_DEGREE == seen["IG_MAX_DEGREE"] and MAX_CSG_DEPTH == seen["RT_MAX_CSG_DEPTH"]
    assert MAX_DEPTH == seen["RT_MAX_DEPTH"] and MAX_SPP == seen["RT_MAX_SPP"]
    assert METHODS["auto"] == seen["IG_ROOTS_AUTO"] and METHODS["bernstein"] == seen["IG_ROOTS_BERNSTEIN"]
    assert OPS == {
        "union": seen["RT_UNION"],
        "intersection": seen["RT_INTERSECTION"],
        "difference": seen["RT_DIFFERENCE"],
    }


def test_struct_layouts_match(tmp_path):
    body = ['    printf("sizeof_hit %zu\\n", sizeof(rt_hit));', '    printf("sizeof_mat %zu\\n", sizeof(rt_material));']
    for name, *_ in abi.struct_fields("rt_hit"):
        body.append(f'    printf("hit.{name} %zu\\n", offsetof(rt_hit, {name}));')
    for name, *_ in abi.struct_fields("rt_material"):
        body.append(f'    printf("mat.{name} %zu\\n", offsetof(rt_material, {name}));')
    seen = _probe(tmp_path, body)
    assert ctypes.sizeof(RtHit) == seen["sizeof_hit"]
    for name, *_ in abi.struct_fields("rt_hit"):
        assert getattr(RtHit, name).offset == seen[f"hit.{name}"], name
    # a packed material lists rt_material's doubles in memory order, padded to RT_MATERIAL_DOUBLES
    assert seen["sizeof_mat"] <= 8 * abi.value("RT_MATERIAL_DOUBLES")
    m = Material(color=(0.1, 0.2, 0.3), ior=1.7, absorption=(4.0, 5.0, 6.0), inside=(0.7, 0.8, 0.9))
    packed = m.packed()
    assert len(packed) == abi.value("RT_MATERIAL_DOUBLES")
    for name, count in abi.material_fields():
        index = seen[f"mat.{name}"] // 8
        value = getattr(m, name)
        assert packed[index : index + count] == (list(value) if count > 1 else [value]), name


def test_every_runtime_source_is_in_exactly_one_library_list():
    lists = [
        resources.SOLVER_SOURCES,
        resources.BENCH_SOURCES,
        resources.SHAPE_SOURCES,
        resources.MESH_SOURCES,
        resources.TRACER_SOURCES,
        resources.EMBREE_SOURCES,
    ]
    listed = [name for group in lists for name in group]
    assert len(listed) == len(set(listed))
    assert sorted(listed) == sorted(p.name for p in RUNTIME.glob("*.c"))


def test_grown_box_is_the_box_ig_shape_prepare_clips_to(tmp_path):
    """abi.grown_box, the Python side's one statement of how far shape.c grows a box (the NumPy ray caster, the
    exact judge and the POV-Ray clip use it), against ig_shape_prepare's prep.lo and prep.hi, bit for bit: boxes
    with open sides, a zero side, tiny and huge bounds."""
    boxes = [
        (-1.25, -0.25, -1.25, 1.25, 0.25, 1.25),
        (-np.inf, 0.0, -3.0, np.inf, 2.0, np.inf),
        (1e-300, -7.5e200, -0.1, 3e-300, 1e201, 0.1),
        (-np.inf, -np.inf, -np.inf, np.inf, np.inf, np.inf),
        (0.0, 0.0, -5.0, 0.0, 1.0, -4.0),
    ]
    rows = ",\n".join(
        "    {" + ", ".join(float(v).hex() if np.isfinite(v) else ("-" if v < 0 else "") + "INFINITY" for v in b) + "}"
        for b in boxes
    )
    src = tmp_path / "grow.c"
    src.write_text(
        '#include <math.h>\n#include <stdio.h>\n#include <string.h>\n#include "shape.h"\n'
        f"static const double BOXES[][6] = {{\n{rows}}};\n"
        "static int bounds(const double *params, double box[6])\n{\n"
        "    memcpy(box, BOXES[(int)params[0]], sizeof BOXES[0]);\n    return 1;\n}\n"
        "static void coeffs(const double o[3], const double d[3], const double *p, double *c)\n{\n"
        "    (void)p;\n    c[0] = o[0];\n    c[1] = d[0];\n}\n"
        "int main(void)\n{\n"
        '    const ig_shape shape = {"probe", 1, 1, coeffs, NULL, NULL, bounds, NULL};\n'
        f"    for (int k = 0; k < {len(boxes)}; ++k) {{\n"
        "        const double params[1] = {k};\n        ig_shape_prep prep;\n"
        "        ig_shape_prepare(&shape, params, &prep);\n"
        '        for (int i = 0; i < 3; ++i)\n            printf("%a %a\\n", prep.lo[i], prep.hi[i]);\n'
        "    }\n    return 0;\n}\n"
    )
    sources = [src, *resources.runtime_sources(resources.SOLVER_SOURCES, ("shape.c",))]
    out = run_c(compile_c(tmp_path / "grow", sources)).split()
    seen = np.array([float.fromhex(v) for v in out]).reshape(len(boxes), 3, 2)
    for box, c in zip(boxes, seen):
        lo, hi = abi.grown_box(box)
        assert np.array_equal(lo, c[:, 0]) and np.array_equal(hi, c[:, 1]), (box, c)
    assert abi.grown_box(boxes[0])[1][0] > 1.25  # it does grow: a torus touching |x| = a + b keeps that root
