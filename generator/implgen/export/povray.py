"""Spec -> POV-Ray `polynomial` object, so POV-Ray can render the same surface for comparison.

POV-Ray wants f expanded into terms `xyz(i,j,k):c` (the coefficient of x^i y^j z^k). We expand exactly in
SymPy's polynomial ring QQ[x, y, z] after substituting the param values, then print each coefficient as the
nearest double (17 significant digits). The `sturm` keyword selects POV-Ray's most careful root solver.
"""

from __future__ import annotations

from collections.abc import Mapping
from fractions import Fraction

import sympy

from implgen.abi import grown_box
from implgen.spec.parse import Spec, exact_polynomial, param_symbol

POVRAY_MAX_ORDER = 35  # POV-Ray 3.7's limit for `polynomial`


def polynomial_terms(spec: Spec, values: Mapping[str, float] | None = None) -> list[tuple[tuple[int, int, int], float]]:
    """[((i, j, k), coefficient), ...] of f with the params set (defaults, overridden by `values`)."""
    params = {**spec.params, **(values or {})}
    subs = {param_symbol(k): sympy.Rational(Fraction(float(v))) for k, v in params.items()}
    poly = exact_polynomial(spec.f.xreplace(subs), [])
    terms = [
        ((int(m[0]), int(m[1]), int(m[2])), float(Fraction(int(c.numerator), int(c.denominator))))
        for m, c in poly.terms()
    ]
    return sorted(terms, key=lambda term: (-sum(term[0]), [-e for e in term[0]]))


def polynomial_object(
    spec: Spec, values: Mapping[str, float] | None = None, sturm: bool = True, indent: str = "  "
) -> str:
    """The body of a POV-Ray `polynomial { ... }` block (without material or transform)."""
    if spec.degree > POVRAY_MAX_ORDER:
        raise ValueError(f"POV-Ray polynomials stop at order {POVRAY_MAX_ORDER}")
    lines = [f"polynomial {{ {spec.degree},"]
    terms = polynomial_terms(spec, values)
    for n, ((i, j, k), c) in enumerate(terms):
        sep = "," if n < len(terms) - 1 else ""
        lines.append(f"{indent}xyz({i},{j},{k}):{c:.17g}{sep}")
    if sturm:
        lines.append(f"{indent}sturm")
    lines.append("}")
    return "\n".join(lines)


# ------------------------------------------------------------------------------------------ scene export
# A whole implgen scene as a POV-Ray 3.7 scene, for bench/povray_compare.py. implgen is right-handed and
# POV-Ray left-handed: we keep our coordinates and give the camera `right -x*aspect`, which mirrors POV-Ray's
# image back so both programs show the same picture. Our `fov` is the VERTICAL field of view
# (runtime_c/tracer_render.c); POV-Ray's `angle` is the horizontal one, so it becomes
# 2 atan(tan(fov/2) * aspect).


def _vec(v) -> str:
    return "<" + ", ".join(f"{float(c):.17g}" for c in v) + ">"


def pov_matrix(m) -> str:
    """POV-Ray `matrix <...>` for our 3x4 object -> world matrix (POV-Ray multiplies row vectors)."""
    a = [[float(m[i][j]) for j in range(4)] for i in range(3)]
    vals = [a[r][c] for c in range(3) for r in range(3)] + [a[0][3], a[1][3], a[2][3]]
    return "matrix <" + ", ".join(f"{v:.17g}" for v in vals) + ">"


def pov_horizontal_angle(vfov_deg: float, aspect: float) -> float:
    import math

    return math.degrees(2.0 * math.atan(math.tan(math.radians(vfov_deg) / 2.0) * aspect))


def _texture(mat) -> str:
    if mat.checker_scale > 0:
        pig = (
            f"pigment {{ checker color rgb {_vec(mat.color)} color rgb {_vec(mat.color2)} "
            f"scale {mat.checker_scale:.17g} }}"
        )
    else:
        pig = f"pigment {{ color rgb {_vec(mat.color)} }}"
    fin = f"ambient {mat.ambient:.17g} diffuse {mat.diffuse:.17g}"
    if mat.specular > 0:
        # Blinn-Phong max(0, n.h)^shininess, as our tracer; POV-Ray's exponent is 1/roughness
        fin += f" specular {mat.specular:.17g} roughness {1.0 / max(mat.shininess, 1e-6):.17g}"
    if mat.reflectivity > 0:
        fin += f" reflection {mat.reflectivity:.17g}"
    return f"texture {{ {pig} finish {{ {fin} }} }}"


def _leaf_object(leaf, texture: str) -> str:
    import numpy as np

    spec = leaf.spec
    m = pov_matrix(leaf.matrix)
    if spec.degree == 1:  # a plane a x + b y + c z + d = 0 (POV-Ray polynomials start at order 2)
        coef = {mono: c for mono, c in polynomial_terms(spec, leaf.params)}
        n = np.array([coef.get((1, 0, 0), 0.0), coef.get((0, 1, 0), 0.0), coef.get((0, 0, 1), 0.0)])
        d = coef.get((0, 0, 0), 0.0)
        length = float(np.linalg.norm(n))
        return f"plane {{ {_vec(n / length)}, {-d / length:.17g}\n  {texture}\n  {m}\n}}"
    body = polynomial_object(spec, leaf.params)[:-1].rstrip()  # drop the closing brace
    return f"{body}\n{clip_text(spec.box(leaf.params))}  {texture}\n  {m}\n}}"


def clip_text(box) -> str:
    """What cuts the surface to its spec box, as implgen's runtime does (it solves only inside the box, grown
    by implgen.abi.grown_box). POV-Ray's `bounded_by` alone does not cut: it only skips rays that miss the box,
    and a surface that leaves the box would render whole. So: `clipped_by` the box (or, with some bounds
    infinite, the planes of the finite ones), and `bounded_by { clipped_by }` when the box is finite."""
    import numpy as np

    if box is None:
        return ""
    lo, hi = grown_box(box)
    if np.all(np.isfinite(box)):
        return f"  clipped_by {{ box {{ {_vec(lo)}, {_vec(hi)} }} }}\n  bounded_by {{ clipped_by }}\n"
    planes = []
    for axis, name in enumerate("xyz"):
        if np.isfinite(hi[axis]):
            planes.append(f"plane {{ {name}, {hi[axis]:.17g} }}")
        if np.isfinite(lo[axis]):
            planes.append(f"plane {{ -{name}, {-lo[axis]:.17g} }}")
    if not planes:
        return ""
    if len(planes) == 1:
        return f"  clipped_by {{ {planes[0]} }}\n"
    return f"  clipped_by {{ intersection {{ {' '.join(planes)} }} }}\n"


def scene_pov(scene, width: int, height: int, coverage: bool = False) -> str:
    """POV-Ray text for an implgen Scene (leaves only; CSG is not exported). coverage=True gives the mask
    render: every non-plane object flat white (`ambient 1 diffuse 0`), no plane, no light, black background."""
    from implgen.scene.model import Leaf

    cam = scene.camera
    aspect = width / height
    lines = [
        "// generated by implgen (implgen.export.povray) -- do not edit",
        "#version 3.7;",
        "global_settings { assumed_gamma 1.0 ambient_light rgb <1, 1, 1> max_trace_level 5 }",
        f"background {{ color rgb {_vec((0, 0, 0) if coverage else scene.background)} }}",
        "camera {",
        "  perspective",
        f"  location {_vec(cam.position)}",
        f"  sky {_vec(cam.up)}",
        "  up y",
        f"  right -x*{aspect:.17g}",
        f"  angle {pov_horizontal_angle(cam.fov, aspect):.17g}",
        f"  look_at {_vec(cam.look_at)}",
        "}",
    ]
    if not coverage:
        for light in scene.lights:
            lines.append(f"light_source {{ {_vec(light.position)} color rgb {_vec(light.color)} }}")
    for node in scene.objects:
        if not isinstance(node, Leaf):
            raise ValueError("scene_pov exports leaf objects only (no CSG)")
        if node.clip is not None:
            raise ValueError("scene_pov does not export a leaf's clip (the surface would show whole)")
        if coverage:
            if node.spec.degree == 1:
                continue
            tex = "texture { pigment { color rgb <1, 1, 1> } finish { ambient 1 diffuse 0 } }"
        else:
            from implgen.scene.model import Material

            tex = _texture(node.material or Material())
        lines.append(_leaf_object(node, tex))
    return "\n".join(lines) + "\n"
