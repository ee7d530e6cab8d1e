"""GUI test script (runs inside Blender, see tests/gui/runner.py): this Blender (A,
the window, the live view on) and a second Blender (B, started from here in
background mode: other_blender.py) edit one world file. A sees B's stroke through
its session's poll timer (nothing done by hand) and its live view remeshes that
chunk; B sees A's strokes; each one's undo leaves the other's voxels alone (B puts
stone over A's lamp: A's undo keeps B's stone)."""
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import bpy

A1, A2, B1 = (3, 3, 100), (5, 3, 100), (4, 3, 100)  # one chunk: (0, 0)


def run(gui):
    gui.use_repo_addon()
    from voxel_addon.blender import session
    from voxel_addon.blender.liveview import LIVE
    from voxel_addon.core.blocks import REGISTRY
    p = gui.params
    sc = bpy.context.scene
    sc.voxel.path = p["world"]
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.show = 1, 12.0, True
    area = gui.area("VIEW_3D")
    r3 = area.spaces.active.region_3d
    r3.view_location, r3.view_distance = (8.0, 8.0, 100.0), 40.0
    r3.view_rotation = (1.0, 0.0, 0.0, 0.0)  # straight down: the eye over chunk (0, 0)
    w = session.world(p["world"])
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and not (LIVE.feed and (0, 0) in LIVE.feed.chunks):
        area.tag_redraw()
        yield 0.1
    gui.result["shown"] = LIVE.feed is not None and (0, 0) in LIVE.feed.chunks
    if not gui.result["shown"]:
        gui.result["view"] = {"error": LIVE.error, "handle": LIVE.handle is not None,
                              "stats": {k: v for k, v in LIVE.stats.items()
                                        if isinstance(v, (int, float, str))},
                              "feed": None if LIVE.feed is None else sorted(LIVE.feed.chunks)}
        return
    step0 = sc.voxel_edit.step
    with gui.context(area):
        gui.result["a1"] = sorted(bpy.ops.voxel.edit(location=A1, block="lamp_red"))
    t0 = time.monotonic()  # the view takes A's stroke in: the version to beat
    while time.monotonic() - t0 < 30 and LIVE.feed.chunks[(0, 0)].version < w.pver[(0, 0)]:
        area.tag_redraw()
        yield 0.1
    v0 = LIVE.feed.chunks[(0, 0)].version
    out = Path(p["out"])
    paths = json.dumps([q for q in sys.path if Path(q, "voxel_addon").is_dir()
                        or Path(q).name == "site"])  # the repo and this Blender's packages
    blender = os.environ.get("VOXEL_BLENDER") or bpy.app.binary_path  # its launcher
    b = subprocess.Popen([blender, "-b", "--factory-startup", "--python-exit-code",
                          "1", "--python", p["other"], "--", p["world"], str(out), paths],
                         stdout=open(out / "b.log", "w"), stderr=subprocess.STDOUT)
    # B's stroke reaches A by A's poll timer alone (and the view remeshes chunk (0, 0))
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and w.get_block(*B1) != REGISTRY.id("glass"):
        if b.poll() is not None:
            break
        yield 0.2
    gui.result["a_sees_b"] = [REGISTRY[w.get_block(*c)].name for c in (A1, B1)]
    t0 = time.monotonic()
    while time.monotonic() - t0 < 30 and LIVE.feed.chunks[(0, 0)].version <= v0:
        area.tag_redraw()
        yield 0.1
    gui.result["remeshed"] = LIVE.feed.chunks[(0, 0)].version > v0
    with gui.context(area):
        gui.result["a2"] = sorted(bpy.ops.voxel.edit(location=A2, block="sand"))
    (out / "a2.done").write_text("")
    t0 = time.monotonic()
    while time.monotonic() - t0 < 60 and b.poll() is None:
        yield 0.2
    gui.result["b_code"] = b.returncode
    gui.result["b"] = json.loads((out / "b.json").read_text()) if (out / "b.json").exists() \
        else (out / "b.log").read_text()[-3000:]
    # B undid its glass meanwhile: A's timer takes that in too
    yield 1.5
    gui.result["a_after_b_undo"] = REGISTRY[w.get_block(*B1)].name
    sc.voxel_edit.step = step0  # Ctrl+Z twice: A's lamp (under B's stone now) and sand
    from voxel_addon.blender import strokes
    strokes.on_undo_redo(sc)
    gui.result["a_after_undo"] = [REGISTRY[w.get_block(*c)].name for c in (A1, A2, B1)]
