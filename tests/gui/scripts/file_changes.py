"""GUI test script (runs inside Blender, see tests/gui/runner.py): the live view shown
while another program changes its world file (test_file_changes.py checks):

  replaced  another world moved over the file: the view draws the new one; a stroke
            goes into the new file, never into the old one (kept here by a hard link)
  deleted   the file removed: the view stops drawing it, the panel says so; a stroke
            is one line, no file is made
  damaged   the file cut short: the view stops drawing it, the panel says so; a
            stroke is one line

Each change comes as the view moves on (its stream reading and saving chunks: a
failure there printed a traceback). Between the cases a fresh world is moved to the
path and shown again. Screenshots:
<case>.png (and shown.png, the first world)."""
import os
import time

import bpy

A, B, C = (3, 3, 100), (4, 3, 100), (5, 3, 100)  # chunk (0, 0), above every flat top


def run(gui):
    gui.use_repo_addon()
    from voxel_addon.blender import session
    from voxel_addon.blender.liveview import LIVE
    p = gui.params
    path = p["world"]
    sc = bpy.context.scene
    for name in ("Cube", "Light", "Camera"):
        o = bpy.data.objects.get(name)
        if o is not None:
            o.hide_set(True)
    sc.voxel.path = path
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.far = 1, 12.0, 0
    area = gui.area("VIEW_3D")
    sp = area.spaces.active
    sp.overlay.show_overlays, sp.show_gizmo, sp.show_region_ui = False, False, True
    r3 = sp.region_3d
    r3.view_perspective = "ORTHO"
    r3.view_location, r3.view_distance = (8.0, 8.0, 64.0), 30.0
    r3.view_rotation = (1.0, 0.0, 0.0, 0.0)  # straight down on chunk (0, 0)
    vv.show = True
    res = gui.result
    yield 0.3  # the sidebar exists: its Voxel tab (the View panel's sentence)
    ui = gui.region(area, "UI")
    ui.active_panel_category = "Voxel"

    def view():
        from voxel_addon.blender.ui.view import problem_lines
        why = LIVE.problem(bpy.context)
        with gui.context(area, ui):  # as the View panel draws it in the sidebar
            lines = problem_lines(bpy.context, why) if why else []
        return {"problem": why, "lines": lines, "error": LIVE.error,
                "seed": LIVE.feed.world.seed if LIVE.feed else None,
                "drawn": LIVE.stats["drawn"], "frames": LIVE.stats["frames"]}

    def until(ok, timeout=20.0):
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout and not ok():
            area.tag_redraw()
            ui.tag_redraw()
            yield 0.1

    def shown(seed):  # the view draws the world of SEED (its feed, every chunk in)
        yield from until(lambda: LIVE.feed is not None and LIVE.feed.world.seed == seed
                         and not LIVE.error and LIVE.stats["drawn"] >= LIVE.stats["wanted"] > 0
                         and LIVE.stats["quality"] == "full")
        yield from gui.until_drawn(area, LIVE, 10.0)

    def stroke(at, block):
        with gui.context(area):
            try:
                return sorted(bpy.ops.voxel.edit(location=at, block=block))
            except RuntimeError as e:  # the operator's ERROR report
                return str(e)

    def moved():  # the view goes on: the stream reads and makes chunks as the file changes
        r3.view_location = (r3.view_location[0] + 64.0, 8.0, 64.0)
        area.tag_redraw()
        yield 0.05
        area.tag_redraw()
        yield 0.05

    def settled(name):  # a few polls (a damaged header is believed at its second) and redraws
        yield from until(lambda: False, 3.0)
        yield from gui.screenshot(name)
        res[name] = view()

    yield from shown(p["seed_a"])
    res["region"] = gui.rect(gui.region(area))
    yield from gui.screenshot("shown")
    res["shown"] = view()

    # -- replaced: another world moved over the open file
    os.link(path, p["old"])  # the old file stays reachable: nothing more may go into it
    yield from moved()
    os.replace(p["b"], path)
    yield from shown(p["seed_b"])
    yield from gui.screenshot("replaced")
    res["replaced"] = view()
    res["replaced"]["stroke"] = stroke(A, "lamp_red")
    res["replaced"]["open_seed"] = session.world(path).seed
    os.link(path, p["new"])  # (read by the test once Blender is gone)

    # -- deleted
    yield from moved()
    os.remove(path)
    yield from settled("deleted")
    res["deleted"]["stroke"] = stroke(B, "glass")
    res["deleted"]["exists"] = os.path.exists(path)

    # -- a world at the path again, then cut short
    os.replace(p["c"], path)
    yield from shown(p["seed_c"])
    res["back"] = view()
    yield from gui.screenshot("back")
    yield from moved()
    with open(path, "r+b") as f:
        f.truncate(1000)
    yield from settled("damaged")
    res["damaged"]["stroke"] = stroke(C, "sand")
    yield from settled("damaged_after")
