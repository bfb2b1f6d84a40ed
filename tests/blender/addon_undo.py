"""Run in Blender with a window (``xvfb-run blender --factory-startup --python THIS -- ...``):
the add-on's Apply, then Edit > Undo, as a user would; and a screenshot of the sidebar panel.

Arguments (after ``--``): ZIP GLB PARTSCALE OUT_DIR. Writes OUT_DIR/undo.json and
OUT_DIR/panel.png, then quits Blender.
"""

from __future__ import annotations

import json
import os
import sys
import traceback

import bpy

argv = sys.argv[sys.argv.index("--") + 1 :]
ZIP, GLB, PARTSCALE, OUT = argv[:4]
result: dict = {}
#: the partscale tab's centre below the sidebar's top (pixels; tabs Item, Tool, View, partscale)
TAB_FROM_TOP = int(os.environ.get("PARTSCALE_TAB_FROM_TOP", "175"))


def view3d():
    win = bpy.context.window_manager.windows[0]
    area = max(
        (a for a in win.screen.areas if a.type == "VIEW_3D"), key=lambda a: a.width * a.height
    )
    region = next(r for r in area.regions if r.type == "WINDOW")
    return win, area, region


def override(**extra):
    win, area, region = view3d()
    return bpy.context.temp_override(
        window=win, screen=win.screen, area=area, region=region, **extra
    )


def snapshot(obj) -> dict:
    return {
        "name": obj.name,
        "faces": len(obj.data.polygons),
        "vertices": len(obj.data.vertices),
        "materials": [m.name for m in obj.data.materials if m],
        "uv_layers": [uv.name for uv in obj.data.uv_layers],
        "matrix": [list(r) for r in obj.matrix_world],
    }


def setup():
    bpy.ops.preferences.addon_install(filepath=ZIP, overwrite=True)
    import addon_utils

    addon_utils.enable("partscale_blender", default_set=True)
    bpy.context.preferences.addons["partscale_blender"].preferences.partscale_path = PARTSCALE
    with override():
        bpy.ops.object.select_all(action="SELECT")
        bpy.ops.object.delete()
        bpy.ops.import_scene.gltf(filepath=GLB)  # after the add-on is enabled (see its register)
    obj = next(o for o in bpy.context.scene.objects if o.type == "MESH")
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def phases():
    """The run, one phase per timer call (events such as the tab click are handled between)."""
    obj = setup()
    name = obj.name
    result["before"] = snapshot(obj)
    wm = bpy.context.window_manager
    wm.partscale.axis, wm.partscale.mode, wm.partscale.count = "Z", "ADD", 1
    with override(active_object=obj, object=obj):
        bpy.ops.partscale.suggest()
    click_tab(obj)
    yield
    with override():
        bpy.ops.screen.screenshot_area(filepath=os.path.join(OUT, "panel.png"))
    obj = bpy.data.objects[name]
    with override(active_object=obj, object=obj):
        bpy.ops.ed.undo_push(message="partscale: before")
        # as a button click runs it: with an undo step (the second argument), which Blender
        # takes only for an operator registered with UNDO
        bpy.ops.partscale.apply("EXEC_DEFAULT", True)
    result["after"] = snapshot(bpy.data.objects[name])
    with override():
        bpy.ops.ed.undo()
    result["undone"] = snapshot(bpy.data.objects[name])
    with override():
        bpy.ops.ed.redo()
    result["redone"] = snapshot(bpy.data.objects[name])


RUN = phases()


def step():
    try:
        next(RUN)
        return 1.0
    except StopIteration:
        pass
    except Exception:
        result["error"] = traceback.format_exc()
    with open(os.path.join(OUT, "undo.json"), "w") as f:
        json.dump(result, f)
    bpy.ops.wm.quit_blender()
    return None


def click_tab(obj):
    """Frame the object and open the sidebar's partscale tab."""
    win, area, _ = view3d()
    space = area.spaces.active
    space.show_region_ui = True
    ui = next(r for r in area.regions if r.type == "UI")
    for o in bpy.context.scene.objects:
        o.select_set(o == obj)
    with override(active_object=obj, object=obj):
        bpy.ops.view3d.view_selected()
    bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)
    # open the sidebar's partscale tab as a user does, with a click on it (Blender 3.4 has no
    # API for the active tab; --enable-event-simulate lets a script send the click)
    x, y = ui.x + ui.width - 10, ui.y + ui.height - TAB_FROM_TOP
    for kind, value in (("MOUSEMOVE", "NOTHING"), ("LEFTMOUSE", "PRESS"), ("LEFTMOUSE", "RELEASE")):
        win.event_simulate(type=kind, value=value, x=x, y=y)


bpy.app.timers.register(step, first_interval=1.0)
