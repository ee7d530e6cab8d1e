"""GUI test script (runs inside Blender, see tests/gui/runner.py): the live voxel view
of two imports of one small build, with the resource stack (`with`) and without one
(`without`), each screenshot once every chunk is drawn."""
import math
import time

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
        t0 = time.monotonic()
        while time.monotonic() - t0 < 120:
            area.tag_redraw()
            s = LIVE.stats
            if s["frames"] > 3 and s["drawn"] >= s["wanted"] > 0 and s["quality"] == "full":
                break
            yield 0.2
        yield 1.0
        area.tag_redraw()
        yield 0.5
        gui.result["status"][name] = {**{k: v for k, v in LIVE.stats.items()
                                         if isinstance(v, (int, float, str))}, "error": LIVE.error}
        gui.result["rect"] = gui.rect(gui.region(area))
        yield from gui.screenshot(name)
