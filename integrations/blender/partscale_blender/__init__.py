"""partscale for Blender: part-aware resizing of the selected mesh from the sidebar.

The panel (View3D > Sidebar > partscale) shows the zones and elements partscale finds in the
active mesh object (``partscale suggest``), and Apply runs partscale's mesh route on it (``fit
--add``, ``fit --size`` or ``scale``): the object is exported with Blender's glTF exporter, edited
by the partscale installed on this computer (found on PATH or set in the add-on's preferences),
imported back, and its mesh data replaced in place: name, transform, modifiers, materials and UV
maps are kept, and Ctrl+Z undoes it like any other edit.
"""

from __future__ import annotations

import os
import re
import tempfile

import bpy
from bpy.props import (
    BoolProperty,
    EnumProperty,
    FloatProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from . import core

bl_info = {
    "name": "partscale",
    "author": "partscale",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > partscale",
    "description": "Part-aware resizing: add shelves, seats or doors, or resize to a target size",
    "category": "Object",
}

_AXES = [("X", "X", "Blender's X axis"), ("Y", "Y", "Blender's Y axis"), ("Z", "Z", "Up")]
_MODES = [
    ("ADD", "+N elements", "Add (or with a negative count, remove) whole elements along the axis"),
    ("SIZE", "Target size", "Resize to a length along the axis, part-aware"),
    ("ZONE", "Zone", "Stretch or tile a zone (in % of the extent) so its end goes to a position"),
]
_SUFFIX = re.compile(r"\.\d{3}$")


def _prefs(context) -> PartscalePreferences | None:
    addon = context.preferences.addons.get(__package__ or __name__)
    return addon.preferences if addon is not None else None


def _command(context) -> list[str]:
    prefs = _prefs(context)
    return core.find_partscale(prefs.partscale_path if prefs is not None else "")


class PartscalePreferences(bpy.types.AddonPreferences):
    bl_idname = __package__ or __name__

    partscale_path: StringProperty(  # type: ignore[valid-type]
        name="partscale",
        description="The partscale executable (or a Python that has partscale installed); "
        "empty: partscale on PATH",
        subtype="FILE_PATH",
        default="",
    )

    def draw(self, context):
        self.layout.prop(self, "partscale_path")


class PartscaleSettings(bpy.types.PropertyGroup):
    axis: EnumProperty(name="Axis", items=_AXES, default="Z")  # type: ignore[valid-type]
    mode: EnumProperty(name="Mode", items=_MODES, default="ADD")  # type: ignore[valid-type]
    count: IntProperty(name="+N", default=1, min=-20, max=20)  # type: ignore[valid-type]
    size: FloatProperty(  # type: ignore[valid-type]
        name="Size", default=1.0, min=0.001, unit="LENGTH", subtype="DISTANCE"
    )
    start: FloatProperty(name="Zone start %", default=30.0, min=0.0, max=100.0)  # type: ignore[valid-type]
    end: FloatProperty(name="Zone end %", default=70.0, min=0.0, max=100.0)  # type: ignore[valid-type]
    to: FloatProperty(name="End to %", default=120.0, min=0.0, max=1000.0)  # type: ignore[valid-type]
    zone_mode: EnumProperty(  # type: ignore[valid-type]
        name="Zone mode",
        items=[("stretch", "Stretch", "Scale the zone"), ("tile", "Tile", "Repeat the zone")],
        default="stretch",
    )
    show_planes: BoolProperty(  # type: ignore[valid-type]
        name="Show planes",
        description="Draw the zone's planes, or the elements found, across the object",
        default=True,
    )
    # what `partscale suggest` found, for the object named in suggested_for (not saved or undone)
    suggested_for: StringProperty(default="")  # type: ignore[valid-type]
    suggestions: StringProperty(default="")  # type: ignore[valid-type]


def _check_mesh(op, context):
    obj = context.active_object
    if obj is None or obj.type != "MESH":
        kind = "nothing" if obj is None else f"{obj.name} (type {obj.type})"
        op.report({"ERROR"}, f"partscale: expected a mesh object selected, got {kind}")
        return None
    return obj


def _export(context, obj, path: str) -> None:
    """The object alone as GLB (Y up, its UVs, normals and materials; modifiers not applied)."""
    selected = list(context.selected_objects)
    active = context.view_layer.objects.active
    for o in selected:
        o.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj
    try:
        bpy.ops.export_scene.gltf(
            filepath=path,
            export_format="GLB",
            use_selection=True,
            export_apply=False,
            export_yup=True,
            export_texcoords=True,
            export_normals=True,
            export_materials="EXPORT",
            export_animations=False,
        )
    finally:
        obj.select_set(False)
        for o in selected:
            o.select_set(True)
        context.view_layer.objects.active = active


def _import_mesh(context, path: str):
    """The mesh data of the one mesh object in ``path``; the imported objects are removed."""
    before = set(bpy.data.objects)
    bpy.ops.import_scene.gltf(filepath=path)
    new = [o for o in bpy.data.objects if o not in before]
    meshes = [o for o in new if o.type == "MESH"]
    data = meshes[0].data if len(meshes) == 1 else None
    for o in new:
        bpy.data.objects.remove(o, do_unlink=True)
    if data is None:
        raise core.PartscaleError(
            f"partscale: expected one mesh in the result, got {len(meshes)} mesh objects"
        )
    return data


def _weld_like(old, new) -> None:
    """Join ``new``'s co-located vertices where ``old`` had none: glTF splits a mesh's vertices
    wherever UVs or normals differ (every corner of a flat cube), which Blender keeps joined.
    A source that had co-located vertices of its own (imported from glTF) keeps them apart."""
    import bmesh

    seen = {tuple(round(c, 7) for c in v.co) for v in old.vertices}
    if len(seen) < len(old.vertices) or not len(new.vertices):
        return
    size = max(
        max(v.co[i] for v in new.vertices) - min(v.co[i] for v in new.vertices) for i in range(3)
    )
    bm = bmesh.new()
    bm.from_mesh(new)
    bmesh.ops.remove_doubles(bm, verts=bm.verts, dist=max(size, 1e-9) * 1e-6)
    bm.to_mesh(new)
    bm.free()


def _replace_mesh(obj, new) -> None:
    """Put ``new`` in place of ``obj``'s mesh: its materials, UV map names and name kept."""
    old = obj.data
    _weld_like(old, new)
    originals = list(old.materials)
    by_name = {m.name: m for m in originals if m is not None}
    imported = [m for m in new.materials if m is not None]
    for i, m in enumerate(new.materials):
        match = by_name.get(_SUFFIX.sub("", m.name)) if m is not None else None
        if match is None and m is not None and m.name in by_name:
            match = by_name[m.name]
        if match is None and i < len(originals):
            match = originals[i]
        if match is not None:
            new.materials[i] = match
    for uv_new, uv_old in zip(new.uv_layers, old.uv_layers, strict=False):
        uv_new.name = uv_old.name
    if old.uv_layers.active is not None and old.uv_layers.active.name in new.uv_layers:
        new.uv_layers.active = new.uv_layers[old.uv_layers.active.name]
    name = old.name
    obj.data = new
    old.name = f"{name}.partscale-before"
    new.name = name
    if old.users == 0:
        bpy.data.meshes.remove(old)
    for m in imported:  # the importer's copies of the materials, now unused
        if m.users == 0:
            bpy.data.materials.remove(m)


class PARTSCALE_OT_suggest(bpy.types.Operator):
    """Find the active mesh's zones and elements with partscale suggest"""

    bl_idname = "partscale.suggest"
    bl_label = "Suggest zones"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def execute(self, context):
        obj = _check_mesh(self, context)
        if obj is None:
            return {"CANCELLED"}
        settings = context.window_manager.partscale
        try:
            command = _command(context)
            wm = context.window_manager
            wm.progress_begin(0, 3)  # the cursor shows the steps (partscale runs for seconds)
            with tempfile.TemporaryDirectory(prefix="partscale-") as folder:
                src = os.path.join(folder, "object.glb")
                csdf = os.path.join(folder, "object.csdf.npz")
                _export(context, obj, src)
                wm.progress_update(1)
                core.run(command, "import", src, "-o", csdf, "--res", "96")
                wm.progress_update(2)
                text = core.run(command, "suggest", csdf, "--json")
        except core.PartscaleError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        finally:
            context.window_manager.progress_end()
        settings.suggestions = text
        settings.suggested_for = obj.name
        self.report({"INFO"}, f"partscale: zones found in {obj.name}")
        return {"FINISHED"}


class PARTSCALE_OT_apply(bpy.types.Operator):
    """Resize the active mesh part-aware with partscale's mesh route (undoable)"""

    bl_idname = "partscale.apply"
    bl_label = "Apply"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.mode == "OBJECT"

    def execute(self, context):
        obj = _check_mesh(self, context)
        if obj is None:
            return {"CANCELLED"}
        s = context.window_manager.partscale
        req = core.Request(
            axis=s.axis,
            mode=s.mode,
            count=s.count,
            size=s.size,
            start=s.start,
            end=s.end,
            to=s.to,
            zone_mode=s.zone_mode,
        )
        before = len(obj.data.polygons)
        try:
            command = _command(context)
            with tempfile.TemporaryDirectory(prefix="partscale-") as folder:
                src = os.path.join(folder, "object.glb")
                dst = os.path.join(folder, "result.glb")
                args = core.edit_args(req, src, dst)
                context.window_manager.progress_begin(0, 3)
                _export(context, obj, src)
                context.window_manager.progress_update(1)
                core.run(command, *args)
                context.window_manager.progress_update(2)
                new = _import_mesh(context, dst)
        except core.PartscaleError as exc:
            self.report({"ERROR"}, str(exc))
            return {"CANCELLED"}
        finally:
            context.window_manager.progress_end()
        _replace_mesh(obj, new)
        self.report(
            {"INFO"}, f"partscale: {obj.name} edited ({before} -> {len(obj.data.polygons)} faces)"
        )
        return {"FINISHED"}


class PARTSCALE_PT_panel(bpy.types.Panel):
    bl_label = "partscale"
    bl_idname = "PARTSCALE_PT_panel"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "partscale"

    def draw(self, context):
        layout = self.layout
        obj = context.active_object
        s = context.window_manager.partscale
        if obj is None or obj.type != "MESH":
            layout.label(text="Select a mesh object", icon="INFO")
            return
        layout.label(text=obj.name, icon="MESH_DATA")
        layout.operator(PARTSCALE_OT_suggest.bl_idname, icon="VIEWZOOM")
        if s.suggestions and s.suggested_for == obj.name:
            box = layout.box()
            try:
                lines = core.summarise_suggestions(s.suggestions)
            except core.PartscaleError as exc:
                lines = {"": [str(exc)]}
            for axis, found in lines.items():
                col = box.column(align=True)
                col.label(text=f"{axis}: {'nothing found' if not found else ''}")
                for line in found:
                    col.label(text=f"   {line}")
        layout.prop(s, "axis", expand=True)
        layout.prop(s, "show_planes")
        layout.prop(s, "mode")
        if s.mode == "ADD":
            layout.prop(s, "count")
        elif s.mode == "SIZE":
            layout.prop(s, "size")
        else:
            col = layout.column(align=True)
            col.prop(s, "start")
            col.prop(s, "end")
            col.prop(s, "to")
            layout.prop(s, "zone_mode", expand=True)
        layout.operator(PARTSCALE_OT_apply.bl_idname, icon="CHECKMARK")


def _world_box(obj):
    """(min corner, max corner) of the object's bounding box in world coordinates."""
    pts = [obj.matrix_world @ _vector(c) for c in obj.bound_box]
    lo = tuple(min(p[i] for p in pts) for i in range(3))
    hi = tuple(max(p[i] for p in pts) for i in range(3))
    return lo, hi


def _vector(c):
    from mathutils import Vector

    return Vector(c)


_SHADER = None


def _draw_planes():
    """Draw the zone's planes (orange) or the suggested elements' boundaries (blue) across the
    active mesh, along the panel's axis: they follow the panel's sliders as they move."""
    global _SHADER
    context = bpy.context
    obj = context.active_object
    wm = context.window_manager
    s = getattr(wm, "partscale", None)
    if s is None or obj is None or obj.type != "MESH" or not s.show_planes:
        return
    import gpu
    from gpu_extras.batch import batch_for_shader

    lo, hi = _world_box(obj)
    a = "XYZ".index(s.axis)
    if s.mode == "ZONE":
        at, color = core.zone_planes(lo[a], hi[a], s.start, s.end), (1.0, 0.55, 0.1, 0.35)
    elif s.suggestions and s.suggested_for == obj.name:
        at, color = core.element_planes(s.suggestions, s.axis), (0.2, 0.6, 1.0, 0.25)
    else:
        return
    if not at:
        return
    if _SHADER is None:
        try:
            _SHADER = gpu.shader.from_builtin("UNIFORM_COLOR")
        except ValueError:  # Blender before 3.4
            _SHADER = gpu.shader.from_builtin("3D_UNIFORM_COLOR")
    batch = batch_for_shader(_SHADER, "TRIS", {"pos": core.plane_quads(lo, hi, s.axis, at)})
    gpu.state.blend_set("ALPHA")
    gpu.state.depth_test_set("LESS_EQUAL")
    _SHADER.bind()
    _SHADER.uniform_float("color", color)
    batch.draw(_SHADER)
    gpu.state.depth_test_set("NONE")
    gpu.state.blend_set("NONE")


_HANDLE = None


CLASSES = (
    PartscalePreferences,
    PartscaleSettings,
    PARTSCALE_OT_suggest,
    PARTSCALE_OT_apply,
    PARTSCALE_PT_panel,
)


def _numpy_compat() -> None:
    """Let Blender 3.4's glTF importer run with NumPy 1.24-1.26 (as Debian 12 ships them).

    That importer calls ``np.bool``, an alias NumPy 1.24 removed (2.0 has it again); the alias
    is the builtin ``bool`` it always was.
    """
    try:
        import numpy as np
    except ImportError:
        return
    if not hasattr(np, "bool"):
        np.bool = bool  # type: ignore[attr-defined]


def register():
    _numpy_compat()
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.WindowManager.partscale = PointerProperty(type=PartscaleSettings)
    global _HANDLE
    _HANDLE = bpy.types.SpaceView3D.draw_handler_add(_draw_planes, (), "WINDOW", "POST_VIEW")


def unregister():
    global _HANDLE
    if _HANDLE is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_HANDLE, "WINDOW")
        _HANDLE = None
    del bpy.types.WindowManager.partscale
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)
