"""implgen in Blender: Add > Mesh > Implicit surface, the closed mesh of f(x, y, z) = 0 made by `implgen mesh`.

An add-on for Blender 3.4 and later (`bl_info`), laid out as a Blender 4.2+ extension too
(`blender_manifest.toml`). It runs the `implgen` command (the path in the add-on's preferences, else PATH) in a
separate process: install implgen with pip first. docs/blender.md in implgen's repository says more.
"""

import bpy
from bpy.props import IntProperty, StringProperty

from . import surface

bl_info = {
    "name": "implgen: implicit surfaces",
    "author": "the implgen authors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Add > Mesh > Implicit surface",
    "description": "The closed mesh of an implicit surface f(x, y, z) = 0, made by implgen",
    "category": "Add Mesh",
}


class ImplgenPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    implgen: StringProperty(
        name="implgen",
        description="The implgen command; empty: the one on PATH",
        subtype="FILE_PATH",
        default="",
    )

    def draw(self, context):
        self.layout.prop(self, "implgen")


def implgen_setting(context) -> str:
    addon = context.preferences.addons.get(__package__)
    return addon.preferences.implgen if addon is not None and addon.preferences is not None else ""


def link_mesh(context, verts, faces):
    """A new object holding the mesh, at the 3D cursor, selected and active."""
    data = bpy.data.meshes.new("Implicit surface")
    data.from_pydata(verts, [], faces)
    data.polygons.foreach_set("use_smooth", [True] * len(data.polygons))
    data.update()
    obj = bpy.data.objects.new("Implicit surface", data)
    obj.location = context.scene.cursor.location
    context.collection.objects.link(obj)
    for other in context.view_layer.objects:
        other.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    return obj


class MESH_OT_implgen_surface_add(bpy.types.Operator):
    """Add the closed mesh of an implicit surface f(x, y, z) = 0 (inside: f < 0), made by implgen"""

    bl_idname = "mesh.implgen_surface_add"
    bl_label = "Implicit surface"
    bl_options = {"REGISTER", "UNDO"}

    equation: StringProperty(
        name="Equation", description="f(x, y, z), as in an implgen spec", default="x^2 + y^2 + z^2 - 1"
    )
    params: StringProperty(name="Params", description="NAME=VALUE, comma-separated (as implgen mesh --param)")
    cells: IntProperty(name="Cells", description="cells along the longest side", default=64, min=4, max=256)
    clip: StringProperty(
        name="Clip", description="sphere:R or box:H (as implgen mesh --clip); empty: none", default="sphere:3"
    )

    def execute(self, context):
        try:
            program = surface.find_implgen(implgen_setting(context))
            verts, faces = surface.mesh(program, self.equation, self.params, self.cells, self.clip)
        except surface.SurfaceError as err:
            self.report({"ERROR"}, str(err))
            return {"CANCELLED"}
        link_mesh(context, verts, faces)
        return {"FINISHED"}


def menu_entry(self, context):
    self.layout.operator(MESH_OT_implgen_surface_add.bl_idname, text="Implicit surface", icon="SURFACE_DATA")


CLASSES = (ImplgenPreferences, MESH_OT_implgen_surface_add)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.VIEW3D_MT_mesh_add.append(menu_entry)


def unregister():
    bpy.types.VIEW3D_MT_mesh_add.remove(menu_entry)
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
