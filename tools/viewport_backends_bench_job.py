"""Blender side of voxel_addon/bench/viewport.py's backend rows (there it is only a path,
never imported): the live view at distance 16 in the real Blender GUI under Xvfb, on
the Blender and GPU backend it was started with.

    blender --gpu-backend B --factory-startup -P tools/viewport_backends_bench_job.py -- OUT.json WORLD

Per quality (full, draft): the pipeline on every redraw (the kept frame off) with the
GPU finished inside each frame (LIVE.finish), so a frame's time is what a redraw
costs; our Python per redraw; the draw calls. Then the still view's redraws from the
kept frame, and Blender's own redraw of the region with the view off.
"""
from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
import viewport_bench_job as V  # noqa: E402  (area, look, frames, all_drawn, region_draw_ms)

R: dict = {}


def run(world):
    import gpu
    from voxel_addon.blender.liveview import LIVE
    _, vv = V.aim(world, 16)
    R.update(backend=gpu.platform.backend_type_get(), renderer=gpu.platform.renderer_get(),
             blender=bpy.app.version_string)
    r = next(r for r in V.area().regions if r.type == "WINDOW")
    R["region"] = [r.width, r.height]
    t0 = time.perf_counter()
    vv.show = True
    yield from V.all_drawn(900)
    R["show_s"] = time.perf_counter() - t0
    R["chunks"] = LIVE.stats["wanted"]
    LIVE.finish, LIVE.reuse = True, False
    for q in ("full", "draft"):
        vv.quality = q
        yield from V.frames(2)
        fr = yield from V.frames(6)
        R[f"{q}_ms"] = min(f.ms for f in fr)
        R[f"{q}_ms_median"] = statistics.median(f.ms for f in fr)
        R[f"{q}_python_ms"] = statistics.median(f.python_ms for f in fr)
        R[f"{q}_submit_ms"] = statistics.median(f.submit_ms for f in fr)
        R[f"{q}_draw_calls"] = fr[-1].draw_calls
    vv.quality, LIVE.reuse = "full", True
    h = vv.hours
    for i in range(3):  # a frame that keeps itself (the hour nudged: the pipeline runs)
        vv.hours = h + 0.001 * (i % 2)
        yield from V.frames(1)
    vv.hours = h
    yield from V.frames(1)
    kept = [f for f in (yield from V.frames(4)) if f.reused]
    if not kept:
        raise RuntimeError("a still redraw ran the pipeline")
    R["still_ms"] = min(f.ms for f in kept)
    R["still_python_ms"] = statistics.median(f.python_ms for f in kept)
    R["still_region_ms"] = V.region_draw_ms(3)
    LIVE.finish = False
    vv.show = False
    yield 0.3
    V.region_draw_ms(10)  # (Blender's viewport anti-aliasing adds samples until it converges)
    R["blender_region_ms"] = V.region_draw_ms(3)
    import voxel_addon
    voxel_addon.unregister()


def main(out, world):
    yield from V.report(run(world), R, out)


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    V.drive(main(Path(args[0]), args[1]))
