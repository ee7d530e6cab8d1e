"""Viewport bench (issue 12): the live view in the real Blender GUI under Xvfb at
1280x720 on llvmpipe (the region is what Blender's default layout leaves of it).

Rows: frame ms still at full quality and in draft (what a redraw costs while the
view moves), our CPU time per redraw outside GL, the time from ticking Show to
every chunk of distance 16 drawn (a generated file, and in the full run an empty
file the stream generates), and the longest redraw and chunk upload while it streams.
Needs `python build.py setup` (.blender/, Xvfb); without them the area yields
nothing but a note. Blender runs tools/viewport_bench_job.py (through bench/gui.py).
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from . import gui

ROOT = Path(__file__).resolve().parents[2]


def run(ctx):
    from ..world import World
    why = gui.missing()
    if why:
        yield ("viewport_skipped", 1, "", why)
        return
    world, empty = ctx.tmp / "view.sqlite", ctx.tmp / "view_empty.sqlite"
    ctx.say("generating the distance-16 area (+ ring)")
    r = subprocess.run([sys.executable, "-m", "voxel_addon", "generate", "--world", str(world),
                        "--seed", "2019", "--radius", "18"], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=str(ROOT)))
    if r.returncode:
        raise RuntimeError(r.stderr[-2000:])
    World.create(empty, seed=2019, generator="overworld").close()
    out = ctx.tmp / "viewport.json"
    ctx.say("Blender GUI: frames, draft, show at distance 16")
    R = gui.run_job("viewport", [out, world, empty, "1" if ctx.quick else "0"], out,
                    ctx.tmp / "viewport.log", timeout=1800, simulate=False)
    if not R.get("ok"):
        raise RuntimeError(R.get("error"))
    size = "x".join(map(str, R["region"]))
    yield ("viewport_frame_ms", R["full_ms"], "ms", f"still, full quality, region {size}, distance 8")
    yield ("viewport_frame_draft_ms", R["draft_ms"], "ms",
           f"draft (moving): half resolution, no shadows/SSAO/DOF/god rays, MSAA 1, region {size}")
    yield ("viewport_python_ms", R["python_ms"], "ms", "our CPU time per redraw outside GL (full)")
    if "baked_draw_ms" in R:
        note = f"distance 8 ({(2 * 8 + 1) ** 2} chunks) baked into one mesh, Solid shading"
        yield ("viewport_redraw_live_ms", R["view_draw_ms"], "ms",
               "whole region redraw with the live view (redraw_timer DRAW, GPU finished)")
        yield ("viewport_redraw_baked_solid_ms", R["baked_draw_ms"], "ms", note)
        yield ("viewport_frame_ratio_baked_to_live", R["baked_draw_ms"] / R["view_draw_ms"], "",
               ">1: the live view redraws faster")
        yield ("viewport_first_picture_live_s", R["show8_s"], "s", "tick Show -> all drawn, distance 8")
        yield ("viewport_first_picture_baked_s", R["baked_first_picture_s"], "s",
               f"bake + build objects + first draw ({R['baked_triangles']} triangles)")
        yield ("viewport_time_ratio_baked_to_live", R["baked_first_picture_s"] / R["show8_s"], "",
               ">1: the live view shows the world sooner")
        yield ("viewport_memory_live_mb", R["view_rss_mb"], "MB", "Blender's RSS growth, live view")
        yield ("viewport_memory_baked_mb", R["baked_rss_mb"], "MB", "Blender's RSS growth, baked mesh")
        yield ("viewport_memory_ratio_baked_to_live", R["baked_rss_mb"] / max(R["view_rss_mb"], 1.0),
               "", ">1: the live view needs less memory")
    if "still_draw_ms" in R:
        yield ("viewport_redraw_live_still_ms", R["still_draw_ms"], "ms",
               "whole region redraw of a still view from its kept frame (pipeline skipped)")
        yield ("viewport_frame_still_ms", R["still_frame_ms"], "ms",
               "draw handler, redraw from the kept frame (GPU finished)")
        yield ("viewport_python_still_ms", R["still_python_ms"], "ms",
               "our CPU time outside GL per redraw from the kept frame")
        yield ("viewport_frame_keep_ms", R["keep_ms"], "ms",
               "full frame that is also kept for the redraws after it")
        yield ("viewport_redraw_blender_only_ms", R["blender_draw_ms"], "ms",
               "whole region redraw with the view off (Blender's own drawing)")
        for k, what in (("live", "live view, pipeline every redraw"),
                        ("still", "live view, still: from the kept frame"),
                        ("blender", "view off: Blender's own drawing")):
            yield (f"viewport_redraw_{k}_cpu_ms", R[f"{k}_cpu_ms"], "ms",
                   f"process CPU per whole region redraw (all threads), {what}")
        if "baked_draw_ms" in R:
            yield ("viewport_frame_ratio_baked_to_live_still", R["baked_draw_ms"] / R["still_draw_ms"],
                   "", ">1: a still live view redraws faster than the baked mesh")
    for key in ("generated", "empty"):
        if f"show16_{key}_s" in R:
            yield (f"viewport_show_view16_{key}_s", R[f"show16_{key}_s"], "s",
                   f"tick Show -> all {R['chunks16']} chunks of distance 16 drawn, {key} file")
            yield (f"viewport_max_redraw_{key}_ms", R[f"max_redraw_{key}_ms"], "ms",
                   f"longest redraw while streaming ({R[f'frames16_{key}']} redraws), {key} file")
            yield (f"viewport_max_upload_{key}_ms", R[f"max_upload_{key}_ms"], "ms",
                   "longest chunk upload within one redraw while streaming")
