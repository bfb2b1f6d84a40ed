"""Run inside Blender's Python (the bpy module or ``blender -b --python``): install and enable the
partscale add-on from its zip, import a glTF with Blender's importer, add elements through the
add-on's operator, undo it, and try the bad inputs. Writes what it saw as JSON for the test.

Arguments (after ``--`` for the blender binary): ZIP GLB PARTSCALE OUT_DIR
"""

from __future__ import annotations

import json
import os
import sys
from collections import Counter

import bpy

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else sys.argv[1:]
ZIP, GLB, PARTSCALE, OUT = argv[:4]
AXIS = os.environ.get("PARTSCALE_TEST_AXIS", "Z")
COUNT = int(os.environ.get("PARTSCALE_TEST_COUNT", "1"))


def snapshot(obj) -> dict:
    mesh = obj.data
    return {
        "name": obj.name,
        "mesh_name": mesh.name,
        "matrix": [list(row) for row in obj.matrix_world],
        "faces": len(mesh.polygons),
        "vertices": [list(v.co) for v in mesh.vertices],
        "materials": [m.name if m else None for m in mesh.materials],
        "material_users": {m.name: m.users for m in mesh.materials if m},
        "material_indices": sorted({p.material_index for p in mesh.polygons}),
        "uv_layers": [uv.name for uv in mesh.uv_layers],
        "uv_range": (
            [
                min(d.uv[0] for d in mesh.uv_layers[0].data),
                max(d.uv[0] for d in mesh.uv_layers[0].data),
                min(d.uv[1] for d in mesh.uv_layers[0].data),
                max(d.uv[1] for d in mesh.uv_layers[0].data),
            ]
            if mesh.uv_layers
            else None
        ),
        "modifiers": [(m.name, m.type) for m in obj.modifiers],
        "n_materials_in_file": len(bpy.data.materials),
        "n_meshes_in_file": len(bpy.data.meshes),
        "n_objects_in_file": len(bpy.data.objects),
    }


def call(op, obj) -> str | None:
    """Run ``op`` with ``obj`` active; the error it reported (one string) or None."""
    with bpy.context.temp_override(
        active_object=obj, object=obj, selected_objects=[obj] if obj else []
    ):
        try:
            op()
        except RuntimeError as exc:
            return str(exc)
    return None


bpy.ops.wm.read_factory_settings(use_empty=True)
# install and enable the add-on from the zip the build makes, as a user would
bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
import addon_utils  # noqa: E402

addon_utils.enable("partscale_blender", default_set=True, handle_error=None)
assert hasattr(bpy.ops.partscale, "apply"), "add-on not enabled"
prefs = bpy.context.preferences.addons["partscale_blender"].preferences
prefs.partscale_path = PARTSCALE

bpy.ops.import_scene.gltf(filepath=GLB)
obj = next(o for o in bpy.context.scene.objects if o.type == "MESH")
obj.location = (0.25, -0.5, 0.1)  # a transform of its own (unchanged by the edit)
obj.rotation_euler = (0.0, 0.0, 0.0)
obj.modifiers.new("Bevel", "BEVEL")  # a modifier (kept, not applied)
bpy.context.view_layer.objects.active = obj
bpy.context.view_layer.update()
result: dict = {"before": snapshot(obj)}
wm = bpy.context.window_manager
wm.partscale.axis = AXIS
wm.partscale.mode = "ADD"
wm.partscale.count = COUNT

result["suggest_error"] = call(bpy.ops.partscale.suggest, obj)
result["suggestions"] = wm.partscale.suggestions
bpy.ops.ed.undo_push(message="before partscale")
result["apply_error"] = call(bpy.ops.partscale.apply, obj)
obj = bpy.data.objects[result["before"]["name"]]
result["after"] = snapshot(obj)
# the result as GLB, for partscale's element finder in the test
for o in bpy.context.scene.objects:
    o.select_set(o == obj)
bpy.ops.export_scene.gltf(
    filepath=os.path.join(OUT, "after.glb"), export_format="GLB", use_selection=True
)
for o in bpy.context.scene.objects:
    o.select_set(False)

# undo: the operator is registered with UNDO; ed.undo steps back over it
result["undo_error"] = None
try:
    bpy.ops.ed.undo()
except RuntimeError as exc:
    result["undo_error"] = str(exc)
obj = bpy.data.objects.get(result["before"]["name"])
result["undone"] = snapshot(obj) if obj is not None else None
result["apply_options"] = sorted(bpy.types.PARTSCALE_OT_apply.bl_options)

# bad input: a non-mesh object, then no partscale found
bpy.ops.object.empty_add()
empty = bpy.context.active_object
result["non_mesh_error"] = call(bpy.ops.partscale.apply, empty)
obj = bpy.data.objects[result["before"]["name"]]
bpy.context.view_layer.objects.active = obj
prefs.partscale_path = os.path.join(OUT, "no-such-partscale")
result["bad_path_error"] = call(bpy.ops.partscale.apply, obj)
prefs.partscale_path = ""
os.environ["PATH"] = OUT  # nothing called partscale there
result["no_partscale_error"] = call(bpy.ops.partscale.apply, obj)
# partscale's own refusal, passed on in one line (remove more elements than there are)
prefs.partscale_path = PARTSCALE
wm.partscale.count = -20
result["refused_error"] = call(bpy.ops.partscale.apply, obj)

# a mesh made in Blender: a cube with a material, 2 m -> 3 m along X (Target size)
bpy.ops.mesh.primitive_cube_add(size=2.0, location=(3.0, 0.0, 1.0))
cube = bpy.context.active_object
cube.name = "Box"
paint = bpy.data.materials.new("paint")
cube.data.materials.append(paint)
result["cube_before"] = snapshot(cube)
wm.partscale.axis, wm.partscale.mode, wm.partscale.size = "X", "SIZE", 3.0
result["cube_error"] = call(bpy.ops.partscale.apply, cube)
cube = bpy.data.objects["Box"]
result["cube_after"] = snapshot(cube)
result["cube_dimensions"] = list(cube.dimensions)
result["cube_loose_edges"] = sum(1 for e in cube.data.edges if e.is_loose)
uses = Counter(k for p in cube.data.polygons for k in p.edge_keys)
result["cube_boundary_edges"] = sum(1 for n in uses.values() if n == 1)

# a zone along Blender's Y (partscale's -z): the first quarter from -Y stretched to 3/4
bpy.ops.mesh.primitive_cube_add(size=2.0, location=(-3.0, 0.0, 1.0))
slab = bpy.context.active_object
slab.name = "Slab"
wm.partscale.axis, wm.partscale.mode = "Y", "ZONE"
wm.partscale.start, wm.partscale.end, wm.partscale.to = 0.0, 25.0, 75.0
wm.partscale.zone_mode = "stretch"
result["slab_error"] = call(bpy.ops.partscale.apply, slab)
result["slab_after"] = snapshot(bpy.data.objects["Slab"])

with open(os.path.join(OUT, "result.json"), "w") as f:
    json.dump(result, f)
print("addon_run: done", flush=True)
sys.stderr.flush()
# the bpy module can crash while Python shuts it down (after everything above is written)
os._exit(0)
