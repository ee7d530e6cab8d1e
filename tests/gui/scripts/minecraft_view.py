"""GUI test script (runs inside Blender, see tests/gui/runner.py): File › Import ›
Minecraft World as the menu runs it (execute -> modal job) on a small build, then the
live voxel view of the imported world, seen from the south-east."""
import math
import time

import bpy


def importing():
    ops = getattr(bpy.context.window_manager.windows[0], "modal_operators", None)
    return ops is not None and any(o.bl_idname == "IMPORT_SCENE_OT_voxel_minecraft" for o in ops)


def run(gui):
    from mathutils import Euler
    gui.use_repo_addon()
    p = gui.params
    sc = bpy.context.scene
    sc.voxel.path = ""
    gui.result["started"] = sorted(bpy.ops.import_scene.voxel_minecraft(
        "EXEC_DEFAULT", filepath=p["level"], modal_run=True))
    t0 = time.monotonic()
    yield None
    while time.monotonic() - t0 < 120 and importing():
        yield None
    gui.result["world"] = bpy.path.abspath(sc.voxel.path)
    for o in list(bpy.data.objects):  # only the voxels in the picture
        o.hide_set(True)
    area = gui.area("VIEW_3D")
    sp = area.spaces.active
    sp.overlay.show_overlays = False
    sp.show_gizmo = False
    sp.clip_end = 1000.0
    r3 = sp.region_3d
    r3.view_perspective = "PERSP"
    r3.view_location = (22.0, -20.0, 132.0)
    r3.view_rotation = Euler([math.radians(a) for a in (62, 0, 35)]).to_quaternion()
    r3.view_distance = 52.0
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.show = 3, 10.5, True
    from voxel_addon.blender.liveview import LIVE
    gui.result["status"] = yield from gui.until_drawn(area, LIVE, 180)
    gui.result["rect"] = gui.rect(gui.region(area))
    yield from gui.screenshot("minecraft")
