"""The viewer's state as YAML a user can keep: a spec file, or a whole scene file that `implgen render` takes.

Written from the parsed state (equations printed from their expression trees, numbers as parsed), never from
what was typed. Shapes are written inline, so a saved scene stands on its own.
"""

from __future__ import annotations

import numpy as np
import yaml

from implgen.scene.model import Leaf, Material, Node, Scene
from implgen.spec.grammar import format_expression
from implgen.spec.parse import Spec, param_symbol


def _num(v: float) -> float | int:
    v = float(v)
    return int(v) if v.is_integer() and abs(v) < 2**53 else v


def _vec(v) -> list[float | int]:
    return [_num(x) for x in v]


def spec_mapping(spec: Spec, values: dict[str, float] | None = None) -> dict:
    """A spec file's mapping; `values` become the params' defaults."""
    out: dict = {"name": spec.name, "equation": spec.as_written}  # the parsed tree, in the user's order
    if spec.params:
        out["params"] = {k: _num((values or {}).get(k, v)) for k, v in spec.params.items()}
    if spec.bounds is not None:
        names = {param_symbol(p): p for p in spec.params}
        out["bounds"] = {
            a: [format_expression(lo, names), format_expression(hi, names)] for a, (lo, hi) in spec.bounds.items()
        }
    if spec.ranges:  # a slider's span, holding the value the file gives
        given = values or {}
        out["ranges"] = {
            k: [_num(min(lo, given.get(k, lo))), _num(max(hi, given.get(k, hi)))] for k, (lo, hi) in spec.ranges.items()
        }
    if spec.description:
        out["description"] = spec.description
    return out


def material_mapping(m: Material) -> dict:
    out: dict = {"color": _vec(m.color)}
    if m.checker_scale > 0:
        out = {"checker": {"colors": [_vec(m.color), _vec(m.color2)], "scale": _num(m.checker_scale)}}
    for k in ("ambient", "diffuse", "specular", "shininess", "reflectivity", "transparency", "ior"):
        out[k] = _num(getattr(m, k))
    out["absorption"] = _vec(m.absorption)
    if getattr(m, "inside", None) is not None:
        out["inside"] = _vec(m.inside)
    return out


def _node(n: Node) -> dict:
    if isinstance(n, Leaf):
        out = {k: v for k, v in spec_mapping(n.spec, n.params).items() if k != "description"}
        if not np.array_equal(n.matrix, np.eye(3, 4)):
            m = n.matrix
            out["transform"] = {"position": _vec(m[:, 3]), "axes": [_vec(m[:, i]) for i in range(3)]}
        if n.clip is not None:
            out["clip"] = {n.clip.kind: _num(n.clip.size)}
            if any(n.clip.center):
                out["clip"]["center"] = _vec(n.clip.center)
    else:
        out = {n.op: [_node(n.left), _node(n.right)]}
    if n.material is not None:
        out["material"] = material_mapping(n.material)
    return out


def scene_mapping(sc: Scene) -> dict:
    """A scene file's mapping for this scene model (lights at intensity 1 with colour x intensity)."""
    cam = sc.camera
    return {
        "image": {"width": sc.width, "height": sc.height, "spp": sc.spp, "max_depth": sc.max_depth},
        "camera": {
            "position": _vec(cam.position),
            "look_at": _vec(cam.look_at),
            "up": _vec(cam.up),
            "fov": _num(cam.fov),
        },
        "background": _vec(sc.background),
        "lights": [{"position": _vec(li.position), "color": _vec(li.color)} for li in sc.lights],
        "objects": [_node(o) for o in sc.objects],
    }


def to_yaml(mapping: dict) -> str:
    return yaml.safe_dump(mapping, sort_keys=False, default_flow_style=None, width=110)


def yaml_text(doc, width: int, height: int, spp: int) -> str:
    """The viewer's document (view/document.py) as a scene file `implgen render` takes: camera, lights,
    background, the shape inline with its clip and colours (or a scene file's objects), the page's full frame as
    its image (on the parse pool: SymPy prints the equations). Rendered, it is the page's full frame, pixel for
    pixel."""
    return to_yaml(scene_mapping(doc.scene(width, height, spp)))


def c_text(spec: Spec) -> str:
    """What `implgen SPEC.yaml --lang c` writes for the shape (on the parse pool)."""
    from implgen.codegen.emit import generate

    files = generate(spec, langs=("c",))
    return "".join(f"/* ---- {name} ---- */\n{text}\n" for name, text in sorted(files.items()))
