"""GUI test script (runs inside Blender, see tests/gui/runner.py): File › Import ›
Voxel World as it runs after the file browser (execute -> modal job), in the real
window: Esc while objects are half-made leaves bpy.data and the scene as they were;
run again to the end, the window keeps handling ticks while the job works."""
import time

import bpy

KINDS = ("objects", "meshes", "materials", "images", "node_groups", "collections")


def state():
    out = {k: sorted(d.name for d in getattr(bpy.data, k)) for k in KINDS}
    out["scene"] = sorted(c.name for c in bpy.context.scene.collection.children)
    return out


def half_made():
    """The job's collection exists but is not in the scene yet (objects stage)."""
    linked = {c.name for c in bpy.context.scene.collection.children}
    return [c.name for c in bpy.data.collections
            if c.name.startswith("Voxel Bake") and c.name not in linked and len(c.objects)]


def importing():
    ops = getattr(bpy.context.window_manager.windows[0], "modal_operators", None)
    if ops is None:  # before Blender 4.2: the job's collection tells
        return bool(half_made())
    return any(o.bl_idname == "IMPORT_SCENE_OT_voxel_world" for o in ops)


def start(gui):
    p = gui.params
    return sorted(bpy.ops.import_scene.voxel_world(
        "EXEC_DEFAULT", filepath=p["world"], region=p["region"], per="tile", tile=16,
        modal_run=True))


def run(gui):
    gui.use_repo_addon()
    gui.move(*gui.center(gui.region(gui.area("VIEW_3D"))))
    before = state()
    gui.result["first"] = start(gui)
    t0, seen = time.monotonic(), []
    while time.monotonic() - t0 < 60 and not seen:
        yield None  # one tick: the job runs its steps from its own timer meanwhile
        seen = half_made()
    gui.result["half_made"] = seen
    gui.result["running_before_esc"] = importing()
    gui.key("ESC")
    yield 0.5
    gui.result["running_after_esc"] = importing()
    gui.result["clean_after_esc"] = state() == before
    gui.result["diff_after_esc"] = {k: sorted(set(v) ^ set(before[k]))
                                    for k, v in state().items() if v != before[k]}

    gui.result["second"] = start(gui)
    t0, ticks = time.monotonic(), 0
    yield None
    while time.monotonic() - t0 < 120 and importing():
        yield None
        ticks += 1
    gui.result["ticks"] = ticks
    coll = [c for c in bpy.context.scene.collection.children if c.name.startswith("Voxel Bake")]
    gui.result["collections"] = [c.name for c in coll]
    gui.result["objects"] = sorted(o.name for c in coll for o in c.objects)
    yield from gui.screenshot("imported")
