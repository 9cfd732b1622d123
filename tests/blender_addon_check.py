"""Run inside Blender by tests/test_blender_addon.py:

    blender -b --factory-startup --python tests/blender_addon_check.py -- ADDON.zip IMPLGEN RESULT.json

Installs and enables the add-on as a user does (Preferences > Add-ons > Install), points its preference at the
`implgen` command, adds a torus through the operator, and writes what it finds as JSON: the menu entry, the new
object's mesh (counts, manifold edges, consistent winding, signed volume), and the one-line errors of bad input.
The test judges; this only looks.
"""

import json
import sys

import bmesh
import bpy

TORUS = "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)"


def mesh_facts(obj) -> dict:
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    facts = {
        "name": obj.name,
        "in_scene": obj.name in bpy.context.scene.objects,
        "vertices": len(bm.verts),
        "edges": len(bm.edges),
        "faces": len(bm.faces),
        "triangles": all(len(f.verts) == 3 for f in bm.faces),
        "manifold": all(e.is_manifold for e in bm.edges),
        "contiguous": all(e.is_contiguous for e in bm.edges),
        "volume": bm.calc_volume(signed=True),
    }
    bm.free()
    return facts


def error_of(**kwargs) -> str | None:
    """The operator's report when it refuses (Blender raises it as a RuntimeError to a Python caller)."""
    try:
        bpy.ops.mesh.implgen_surface_add(**kwargs)
    except RuntimeError as err:
        return str(err)
    return None


def main(zip_path: str, implgen: str, result: str) -> None:
    bpy.ops.preferences.addon_install(filepath=zip_path)
    bpy.ops.preferences.addon_enable(module="implgen_blender")
    prefs = bpy.context.preferences.addons["implgen_blender"].preferences
    prefs.implgen = implgen
    draw_funcs = getattr(bpy.types.VIEW3D_MT_mesh_add.draw, "_draw_funcs", [])
    out = {"menu": any(getattr(f, "__module__", "").startswith("implgen_blender") for f in draw_funcs)}
    before = set(bpy.data.objects.keys())
    out["status"] = sorted(
        bpy.ops.mesh.implgen_surface_add(equation=TORUS, params="R=1, r=0.35", cells=32, clip="sphere:3")
    )
    added = [bpy.data.objects[name] for name in set(bpy.data.objects.keys()) - before]
    out["added"] = [mesh_facts(obj) for obj in added]
    out["errors"] = {
        "equation": error_of(equation="x^2 + w", clip="sphere:3"),
        "params": error_of(equation="x^2 + y^2 + z^2 - a", params="a=one"),
        "clip": error_of(equation="x^2 + y^2 + z^2 - 1", clip="cube:2"),
        "unbounded": error_of(equation="x^2 + y^2 - 1", clip=""),
    }
    prefs.implgen = "/nonexistent/implgen"
    out["errors"]["program"] = error_of(equation="x^2 + y^2 + z^2 - 1")
    out["objects_after_errors"] = len(bpy.data.objects) - len(before) - len(added)
    with open(result, "w") as fh:
        json.dump(out, fh)


main(*sys.argv[sys.argv.index("--") + 1 :])
