"""Runs inside the real Blender (GUI, under Xvfb): the live voxel view.

    blender --factory-startup -P tests/gui/viewport_job.py -- OUT WORLD [STEPS]

Drives the 3D viewport through timers, one step after the other, and writes
OUT/<name>.png (screenshots of the X screen: what a person sees), OUT/result.json
(per step what the view reported) and OUT/error.txt on a Python error. The checks on
the pictures are made by tests/gui/test_viewport.py.
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import time
import traceback
from pathlib import Path

import bpy

ARGS = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
OUT, WORLD = Path(ARGS[0]), ARGS[1]
ONLY = ARGS[2].split(",") if len(ARGS) > 2 else None
ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
bpy.context.preferences.view.show_splash = False

RESULT: dict = {"steps": {}}


def shot(name):
    """The X screen as OUT/name.png."""
    path = OUT / f"{name}.png"
    subprocess.run(f"xwd -root -silent | xwdtopnm 2>/dev/null | pnmtopng > {path}",
                   shell=True, check=True)
    return str(path)


def view3d():
    for win in bpy.context.window_manager.windows:
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                return win, area, area.spaces.active
    raise RuntimeError("no 3D viewport")


def region_rect():
    """The 3D viewport's WINDOW region in screen pixels (x, y from the top, w, h)."""
    win, area, _ = view3d()
    r = next(r for r in area.regions if r.type == "WINDOW")
    return {"x": r.x, "y": win.height - (r.y + r.height), "w": r.width, "h": r.height}


def set_view(loc, rot_euler, dist, persp="PERSP"):
    from mathutils import Euler
    _, area, sp = view3d()
    r3 = sp.region_3d
    r3.view_perspective = persp
    r3.view_location = loc
    r3.view_rotation = Euler([math.radians(a) for a in rot_euler]).to_quaternion()
    r3.view_distance = dist
    area.tag_redraw()


def status():
    from voxel_addon.blender import viewport
    return dict(viewport.STATUS)


def wait_frames(n=2, full=True, timeout=120.0):
    """Generator: redraw until n more frames were drawn, all chunks are in and (full)
    the last frame was full quality."""
    from voxel_addon.blender import viewport
    t0 = time.time()
    start = viewport.STATUS["frames"]
    while time.time() - t0 < timeout:
        _, area, _ = view3d()
        area.tag_redraw()
        s = viewport.STATUS
        if (s["frames"] >= start + n and s["drawn"] >= s["wanted"] > 0
                and (not full or s["quality"] == "full")):
            return
        yield 0.1
    raise RuntimeError(f"timed out waiting for frames: {viewport.STATUS}")


def settle(n=3):
    """Generator: a few plain redraws (Show off: no voxel frames to count)."""
    for _ in range(n):
        view3d()[1].tag_redraw()
        yield 0.2


# ------------------------------------------------------------------ scene
def setup():
    import voxel_addon
    voxel_addon.register()
    sc = bpy.context.scene
    sc.voxel.path = WORLD
    vv = sc.voxel_view
    vv.distance = 4
    vv.hours = 12.0
    # Blender's default cube: one in front of the terrain, one buried in it
    cube = bpy.data.objects.get("Cube")
    cube.location = (8.0, 8.0, 120.0)
    cube.scale = (4.0, 4.0, 4.0)
    buried = cube.copy()
    buried.data = cube.data
    buried.name = "Buried"
    buried.location = (8.0, 8.0, 20.0)
    sc.collection.objects.link(buried)
    for o in ("Light", "Camera"):
        if o in bpy.data.objects:
            bpy.data.objects[o].hide_set(True)
    _, _, sp = view3d()
    sp.overlay.show_floor = sp.overlay.show_axis_x = sp.overlay.show_axis_y = False
    sp.overlay.show_cursor = False
    sp.overlay.show_text = False
    sp.show_gizmo = False
    sp.clip_end = 1000.0
    bpy.ops.object.select_all(action="DESELECT")
    yield 0.5


def step_top():
    """Top view from above the two cubes, perspective."""
    sc = bpy.context.scene
    set_view((8.0, 8.0, 80.0), (0, 0, 0), 140.0)
    sc.voxel_view.show = False
    yield from settle()
    RESULT["steps"]["off"] = {"png": shot("off"), "rect": region_rect()}
    sc.voxel_view.show = True
    yield from wait_frames()
    RESULT["steps"]["on"] = {"png": shot("on"), "rect": region_rect(), "status": status()}


def run():
    try:
        yield from setup()
        for name, fn in STEPS.items():
            if ONLY is None or name in ONLY:
                yield from fn()
        RESULT["ok"] = True
    except Exception:
        (OUT / "error.txt").write_text(traceback.format_exc())
        RESULT["ok"] = False
    (OUT / "result.json").write_text(json.dumps(RESULT, indent=1))
    bpy.ops.wm.quit_blender()


STEPS = {"top": step_top}
_gen = run()


def _timer():
    try:
        return next(_gen)
    except StopIteration:
        return None


OUT.mkdir(parents=True, exist_ok=True)
bpy.app.timers.register(_timer, first_interval=1.0)
