"""GUI test script (runs inside Blender, see tests/gui/runner.py): the live voxel view
of two imports of one small build, with the resource stack (`with`) and without one
(`without`), each screenshot once every chunk is drawn."""
import math

import bpy


def run(gui):
    from mathutils import Euler
    gui.use_repo_addon()
    p = gui.params
    sc = bpy.context.scene
    area = gui.area("VIEW_3D")
    sp = area.spaces.active
    sp.overlay.show_overlays = False
    sp.show_gizmo = False
    sp.clip_end = 1000.0
    for o in list(bpy.data.objects):  # only the voxels in the picture
        o.hide_set(True)
    r3 = sp.region_3d
    r3.view_perspective = "PERSP"
    r3.view_location = (9.0, -8.0, 65.0)
    r3.view_rotation = Euler([math.radians(a) for a in (60, 0, 30)]).to_quaternion()
    r3.view_distance = 16.0
    from voxel_addon.blender.liveview import LIVE
    gui.result["status"] = {}
    for name in ("with", "without"):
        vv = sc.voxel_view
        vv.show = False
        yield 0.2
        sc.voxel.path = p[name]
        vv.distance, vv.hours, vv.show = 2, 12.0, True
        gui.result["status"][name] = yield from gui.until_drawn(area, LIVE, 120)
        gui.result["rect"] = gui.rect(gui.region(area))
        yield from gui.screenshot(name)
