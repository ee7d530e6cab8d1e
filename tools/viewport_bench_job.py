"""Blender side of voxel_addon/bench/viewport.py (there it is only a path, never
imported): runs in the real Blender GUI under Xvfb, started as a script (`__main__`).

    blender --factory-startup -P tools/viewport_bench_job.py -- OUT.json WORLD EMPTY_WORLD QUICK

Frame times come from the draw handler itself (LIVE.frames) with the GPU
finished inside each frame (LIVE.finish), so they are what a redraw costs.
"""
from __future__ import annotations

import json
import math
import os
import statistics
import sys
import time
import traceback
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parents[1]
OUT = WORLD = EMPTY = None
QUICK = True
R: dict = {}


def area():
    for win in bpy.context.window_manager.windows:
        for a in win.screen.areas:
            if a.type == "VIEW_3D":
                return a
    raise RuntimeError("no 3D viewport")


def look(yaw):
    from mathutils import Euler
    r3 = area().spaces.active.region_3d
    r3.view_perspective = "PERSP"
    r3.view_location = (8.0, 8.0, 70.0)
    r3.view_rotation = Euler((math.radians(70), 0, math.radians(yaw))).to_quaternion()
    r3.view_distance = 40.0


def frames(n, timeout=300.0):
    """Generator: n more redraws of the voxel view (the last frame's entries)."""
    from voxel_addon.blender.liveview import LIVE
    start = LIVE.stats["frames"]
    t0 = time.time()
    while LIVE.stats["frames"] < start + n:
        if time.time() - t0 > timeout:
            raise RuntimeError(f"no frames: {LIVE.stats}")
        area().tag_redraw()
        yield 0.01
    return list(LIVE.frames)[-n:]


def all_drawn(timeout):
    """Generator: redraw until every wanted chunk is drawn; returns the seconds."""
    from voxel_addon.blender.liveview import LIVE
    t0 = time.perf_counter()
    while True:
        s = LIVE.stats
        n = (2 * bpy.context.scene.voxel_view.distance + 1) ** 2
        if s["wanted"] == n and s["drawn"] >= s["wanted"]:
            return time.perf_counter() - t0
        if LIVE.error:
            raise RuntimeError(LIVE.error)
        if time.perf_counter() - t0 > timeout:
            raise RuntimeError(f"not all drawn after {timeout} s: {s}")
        area().tag_redraw()
        yield 0.01


def region_draw_ms(n) -> float:
    """Fastest of n synchronous redraws of the 3D viewport's region (Blender's own
    redraw_timer), GPU work finished (a pixel read back)."""
    import gpu
    win = bpy.context.window_manager.windows[0]
    a = area()
    reg = next(r for r in a.regions if r.type == "WINDOW")
    best = 1e9
    for _ in range(n):
        with bpy.context.temp_override(window=win, area=a, region=reg):
            t = time.perf_counter()
            bpy.ops.wm.redraw_timer(type="DRAW", iterations=1)
            gpu.state.active_framebuffer_get().read_color(0, 0, 1, 1, 4, 0, "UBYTE")
            best = min(best, (time.perf_counter() - t) * 1e3)
    return best


def region_draw_cpu_ms(n) -> float:
    """Median CPU time of the whole process (llvmpipe's threads included) per
    synchronous redraw of the region: what a redraw costs on a loaded machine."""
    import gpu
    win = bpy.context.window_manager.windows[0]
    a = area()
    reg = next(r for r in a.regions if r.type == "WINDOW")
    ts = []
    for _ in range(n):
        with bpy.context.temp_override(window=win, area=a, region=reg):
            t = time.process_time()
            bpy.ops.wm.redraw_timer(type="DRAW", iterations=1)
            gpu.state.active_framebuffer_get().read_color(0, 0, 1, 1, 4, 0, "UBYTE")
            ts.append((time.process_time() - t) * 1e3)
    return statistics.median(ts)


def still(sc, vv):
    """A still view: whole-region redraws that reuse the kept frame (measured as the
    baked mesh is), the handler's own time for them, and a full frame that keeps
    itself (time of day nudged so each one runs the pipeline)."""
    from voxel_addon.blender.liveview import LIVE
    LIVE.reuse = True
    h = vv.hours
    keep = []
    for i in range(3):
        vv.hours = h + 0.001 * (i % 2)
        keep += yield from frames(1)
    vv.hours = h
    yield from frames(1)
    R["keep_ms"] = min(f[0] for f in keep if not f[5])
    kept = yield from frames(3)
    R["still_frame_ms"] = min(f[0] for f in kept if f[5])
    R["still_python_ms"] = statistics.median(f[1] for f in kept if f[5])
    R["still_draw_ms"] = region_draw_ms(3)
    R["still_cpu_ms"] = region_draw_cpu_ms(3)
    if not LIVE.frames[-1][5]:
        raise RuntimeError("a still redraw ran the pipeline")
    LIVE.reuse = False
    R["live_cpu_ms"] = region_draw_cpu_ms(3)
    vv.show = False  # the floor of both: Blender's own redraw of that region
    yield 0.3
    region_draw_ms(10)  # (Blender's viewport anti-aliasing adds samples until it converges)
    R["blender_draw_ms"] = region_draw_ms(3)
    R["blender_cpu_ms"] = region_draw_cpu_ms(3)


def aim(world, distance):
    """The add-on registered, the view on WORLD at DISTANCE, noon, overlays off, looking
    along yaw 30 (Show not ticked yet); returns (scene, its voxel_view)."""
    import voxel_addon
    voxel_addon.register()
    sc = bpy.context.scene
    sp = area().spaces.active
    sp.overlay.show_overlays = False
    sp.clip_end = 2000.0
    vv = sc.voxel_view
    sc.voxel.path = world
    vv.distance, vv.hours = distance, 12.0
    look(30)
    return sc, vv


def run():
    from voxel_addon.blender.liveview import LIVE
    sc, vv = aim(WORLD, 8)
    r = next(r for r in area().regions if r.type == "WINDOW")
    R["region"] = [r.width, r.height]
    vv.show = True
    R["show8_s"] = yield from all_drawn(300)
    LIVE.finish = True
    LIVE.reuse = False  # these rows: the pipeline on every redraw (still() reuses)
    vv.quality = "full"
    yield from frames(2)
    n = 3 if QUICK else 6
    full = yield from frames(n)
    R["full_ms"] = min(f[0] for f in full)
    R["python_ms"] = statistics.median(f[1] for f in full)
    vv.quality = "draft"
    yield from frames(2)
    draft = yield from frames(n)
    R["draft_ms"] = min(f[0] for f in draft)
    R["draft_python_ms"] = statistics.median(f[1] for f in draft)
    vv.quality = "full"
    yield from frames(1)
    R["view_draw_ms"] = region_draw_ms(3)
    yield from still(sc, vv)
    vv.quality = "auto"
    LIVE.finish, LIVE.reuse = False, True
    for key, path in (("generated", WORLD), ("empty", EMPTY)):
        if QUICK and key == "empty":
            continue
        vv.show = False
        yield 0.2
        sc.voxel.path = path
        vv.distance = 16
        look(30)
        yield 0.2
        LIVE.frames.clear()
        LIVE.stats.update(drawn=0, wanted=0)  # (the last file's counts until a frame)
        vv.show = True
        R[f"show16_{key}_s"] = yield from all_drawn(600)
        R[f"max_redraw_{key}_ms"] = max(f[0] for f in LIVE.frames)
        R[f"max_upload_{key}_ms"] = max(f[4] for f in LIVE.frames)
        R[f"frames16_{key}"] = len(LIVE.frames)
        R["chunks16"] = LIVE.stats["wanted"]
    import voxel_addon
    voxel_addon.unregister()


def main():
    yield from report(run(), R, OUT)


def report(job, r: dict, out: Path):
    """Generator: run job, then write r (with "ok", or "error": the traceback) to
    out as JSON and quit Blender: what every bench job ends with."""
    try:
        yield from job
        r["ok"] = True
    except Exception:
        r["ok"] = False
        r["error"] = traceback.format_exc()
    out.write_text(json.dumps(r, indent=1))
    bpy.ops.wm.quit_blender()


def start():
    global OUT, WORLD, EMPTY, QUICK
    args = sys.argv[sys.argv.index("--") + 1:]
    OUT, WORLD, EMPTY, QUICK = Path(args[0]), args[1], args[2], args[3] == "1"
    drive(main())


def drive(gen):
    """Run a job generator from a timer (yielded values: seconds to the next step),
    with the checkout and Blender's site packages importable."""
    for p in (os.environ.get("VOXEL_BLENDER_SITE"), str(ROOT / ".blender" / "site"), str(ROOT)):
        if p and p not in sys.path:
            sys.path.insert(0, p)
    bpy.context.preferences.view.show_splash = False

    def timer():
        try:
            return next(gen)
        except StopIteration:
            return None
    bpy.app.timers.register(timer, first_interval=1.0, persistent=True)


if __name__ == "__main__":
    start()
