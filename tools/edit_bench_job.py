"""Blender side of voxel_addon/bench/edit.py: runs in the real Blender GUI under Xvfb with
--enable-event-simulate.

    blender --factory-startup --enable-event-simulate -P tools/edit_bench_job.py -- OUT CLICKS

A flat world seen from the top (orthographic), the voxel view shown, the Voxel Edit
tool active; frame end times come from the view's OVERLAYS hook.
"""
from __future__ import annotations

import json
import os
import random
import sys
import time
import traceback
from pathlib import Path

import bpy

ARGS = sys.argv[sys.argv.index("--") + 1:]
OUT, CLICKS = Path(ARGS[0]), int(ARGS[1])
ROOT = Path(__file__).resolve().parents[1]
for p in (os.environ.get("VOXEL_BLENDER_SITE"), str(ROOT / ".blender" / "site"), str(ROOT)):
    if p and p not in sys.path:
        sys.path.insert(0, p)
bpy.context.preferences.view.show_splash = False
R: dict = {"error": None}
FRAMES: list = []
DRAWN: list = []   # (frame end time, {chunk key: version drawn}) per voxel frame


def view3d():
    win = bpy.context.window_manager.windows[0]
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    return win, area, next(r for r in area.regions if r.type == "WINDOW"), area.spaces.active


def ev(type, value, at):
    win, _, region, _ = view3d()
    win.event_simulate(type=type, value=value, x=region.x + at[0], y=region.y + at[1])


def frames_after(t0, n=1):
    while len([t for t in FRAMES if t > t0]) < n:
        view3d()[1].tag_redraw()
        yield 0.01


def steps():
    from mathutils import Quaternion, Vector
    import voxel_addon
    from voxel_addon.blender import session, strokes
    from voxel_addon.blender.liveview import LIVE
    voxel_addon.register()
    sc = bpy.context.scene
    for ob in list(bpy.data.objects):
        bpy.data.objects.remove(ob)
    sc.voxel.path, sc.voxel.seed, sc.voxel.generator = str(OUT / "w.sqlite"), 1, "flat"
    bpy.ops.voxel.world_new()
    w = session.world(sc.voxel.path)
    w.idle_timeout = 1e9
    top = int(max(i for i in range(256) if w.chunk_at(0, 0).blocks[0, 0, i]))
    win, area, region, space = view3d()
    r3 = space.region_3d
    r3.view_perspective, r3.view_rotation = "ORTHO", Quaternion((1.0, 0.0, 0.0, 0.0))
    r3.view_location, r3.view_distance = Vector((8.0, 8.0, top + 1)), 20.0
    space.overlay.show_overlays = False
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.wm.tool_set_by_id(name="voxel.edit_tool")
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.quality, vv.show = 3, 12.0, "full", True
    def frame_end(ctx):
        t = time.perf_counter()
        FRAMES.append(t)
        vers: dict = {}
        for g in LIVE.panes.values():
            vers.update(g.versions)
        DRAWN.append((t, vers))
    LIVE.overlays.append(frame_end)
    R["region"] = [region.width, region.height]
    for i in range(8):  # the view fills in; the first click of a new window is lost
        ev("MOUSEMOVE", "NOTHING", (region.width // 2 + i, region.height // 2))
        yield 0.3
    ev("LEFTMOUSE", "PRESS", (5, 5))
    ev("LEFTMOUSE", "RELEASE", (5, 5))
    while LIVE.stats["drawn"] < LIVE.stats["wanted"] or not LIVE.stats["wanted"]:
        yield 0.2
    sc.voxel_edit.block = "stone"
    rng = random.Random(1)
    lat, own, gap, first = [], [], [], 0

    def drawn(key):
        return max((g.versions.get(key, -1) for g in LIVE.panes.values()), default=-1)

    for _ in range(CLICKS):
        at = (rng.randrange(region.width // 4, 3 * region.width // 4),
              rng.randrange(region.height // 4, 3 * region.height // 4))
        ev("MOUSEMOVE", "NOTHING", at)
        yield from frames_after(time.perf_counter())
        step = bpy.context.scene.voxel_edit.step
        t0 = time.perf_counter()
        ev("LEFTMOUSE", "PRESS", at)        # the edit happens here
        yield 0.005
        ev("LEFTMOUSE", "RELEASE", at)      # the stroke is recorded here
        while bpy.context.scene.voxel_edit.step == step:
            yield 0.005
        x, y, _ = strokes._journal.nodes[bpy.context.scene.voxel_edit.step][2].voxels[0]
        key = (x >> 4, y >> 4)
        want = w.pver.get(key)
        while drawn(key) < want:
            yield 0.005
        done = strokes.STATS["done"]
        shown = [t for t, vers in DRAWN if t > t0 and vers.get(key, -1) >= want]
        after = [t for t, _ in DRAWN if t > done]   # frames that began after the edit
        first += shown[0] == after[0]
        lat.append((shown[0] - t0) * 1e3)
        own.append(strokes.STATS["last_ms"])
        gap.append((shown[0] - done) * 1e3)
    lat.sort()
    own.sort()
    gap.sort()
    R.update(clicks=len(lat), click_median_ms=lat[len(lat) // 2],
             click_p90_ms=lat[min(len(lat) - 1, int(len(lat) * 0.9))],
             stroke_median_ms=own[len(own) // 2], frame_ms=LIVE.stats["ms"],
             first_frame_shows=first, edit_to_frame_ms=gap[len(gap) // 2])
    # a fast drag: all move events queued at once, as a quick hand gives them
    y = region.height // 2 + 41
    xs = list(range(region.width // 2 - 300, region.width // 2 + 300, 30))
    ev("MOUSEMOVE", "NOTHING", (xs[0], y))
    yield 0.3
    step, v0, ms0 = bpy.context.scene.voxel_edit.step, strokes.STATS["voxels"], strokes.STATS["ms"]
    t0 = time.perf_counter()
    ev("LEFTMOUSE", "PRESS", (xs[0], y))
    for x in xs[1:]:
        ev("MOUSEMOVE", "NOTHING", (x, y))
    ev("LEFTMOUSE", "RELEASE", (xs[-1], y))
    while bpy.context.scene.voxel_edit.step == step:
        yield 0.005
    dt = time.perf_counter() - t0
    n = strokes.STATS["voxels"] - v0
    R.update(paint_voxels=n, paint_wall=n / dt,
             paint_path=n / max(1e-9, (strokes.STATS["ms"] - ms0) / 1e3))


def main():
    gen = steps()

    def tick():
        try:
            d = next(gen)
            return 0.01 if d is None else d
        except StopIteration:
            pass
        except Exception:
            R["error"] = traceback.format_exc()
        (OUT / "edit.json").write_text(json.dumps(R, indent=1))
        sys.stdout.flush()
        os._exit(0)
    bpy.app.timers.register(tick, first_interval=0.5)


main()
