"""Viewport bench (issue 12): the live view in the real Blender GUI under Xvfb at
1280x720 on llvmpipe (the region is what Blender's default layout leaves of it).

Rows: frame ms still at full quality and in draft (what a redraw costs while the
view moves), our CPU time per redraw outside GL, the time from ticking Show to
every chunk of distance 16 drawn (a generated file, and in the full run an empty
file the stream generates), and the longest redraw and chunk upload while it streams.
first_minute(): a fresh install's first Show (empty kernel cache) in every Blender and
GPU backend: seconds to the first chunks and to the whole view.
compare(): the live view against the same chunks baked into an object that Blender
draws (Solid, Material Preview), one fresh Blender per side, at distance 16 (8 with
--quick): redraw, memory and time to the picture as ratios, and what the live view's
memory is made of.
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
    yield from first_minute(ctx)
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
           f"draft (moving): 0.4 of the region's size, no shadows/SSAO/DOF/god rays, plants "
           f"out to 128 blocks, MSAA 1, region {size}")
    yield ("viewport_python_ms", R["python_ms"], "ms", "our CPU time per redraw outside GL (full)")
    yield ("viewport_redraw_live_ms", R["view_draw_ms"], "ms",
           "whole region redraw with the live view, pipeline every redraw (redraw_timer DRAW, "
           "GPU finished); against the baked mesh: the _d8/_d16 rows (fresh Blender per side)")
    yield ("viewport_first_picture_live_s", R["show8_s"], "s", "tick Show -> all drawn, distance 8")
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
    yield from backends(ctx, world)
    yield from frames(ctx, world, 8 if ctx.quick else 16, 64 if ctx.quick else 256,
                      8 if ctx.quick else 30)
    yield from compare(ctx, world, 8 if ctx.quick else 16)
    for key in ("generated", "empty"):
        if f"show16_{key}_s" in R:
            yield (f"viewport_show_view16_{key}_s", R[f"show16_{key}_s"], "s",
                   f"tick Show -> all {R['chunks16']} chunks of distance 16 drawn, {key} file")
            yield (f"viewport_max_redraw_{key}_ms", R[f"max_redraw_{key}_ms"], "ms",
                   f"longest redraw while streaming ({R[f'frames16_{key}']} redraws), {key} file")
            yield (f"viewport_max_upload_{key}_ms", R[f"max_upload_{key}_ms"], "ms",
                   "longest chunk upload within one redraw while streaming")


def first_minute(ctx, distance: int = 8, opened_first: float = 5.0):
    """A fresh install's first Show (issue 28), in every installed Blender on each GPU
    backend (tools/first_bench_job.py, one fresh Blender each): a new world, an empty
    kernel cache (pocl's and pyopencl's); seconds from Show to the first chunks drawn
    and to every chunk of the default distance drawn, and the OpenCL warm-up's build
    time (NumPy streams meanwhile). Goals: 2 s and 5 s. Twice: Show ticked as the
    world is chosen (the kernels build after Show), and Show ticked OPENED_FIRST
    seconds after the world was opened, as with New or Open World (`_opened` rows: the
    kernels build from the open, blender/session.py)."""
    for blender, gpu in gui.variants():
        for wait in (0.0, opened_first):
            yield from _first(ctx, blender, gpu, distance, wait)


def _first(ctx, blender, gpu, distance, wait):
    from ..world import World
    tag = f"{blender.replace('.', '')}_{gpu}" + ("_opened" if wait else "")
    ctx.say(f"Blender {blender} GUI on {gpu}: first Show, empty kernel cache"
            + (f", Show {wait:g} s after the world opened" if wait else ""))
    world, cache = ctx.tmp / f"first_{tag}.sqlite", ctx.tmp / f"first_{tag}_kernels"
    World.create(world, seed=2019, generator="overworld").close()
    out = ctx.tmp / f"first_{tag}.json"
    env = {"POCL_CACHE_DIR": str(cache / "pocl"), "PYOPENCL_CACHE_DIR": str(cache / "pyopencl"),
           "VOXEL_TRACE": "1",  # the timeline (core/trace) in the job's JSON
           "VOXEL_BENCH_OPEN_FIRST": str(wait)}
    R = gui.run_job("first", [out, world, distance], out, ctx.tmp / f"first_{tag}.log",
                    timeout=900, simulate=False, blender=blender, gpu=gpu, env=env)
    if not R.get("ok"):
        raise RuntimeError(R.get("error"))
    what = f"Blender {R['blender']} {R['backend']}, distance {distance} ({R['chunks']} chunks)"
    when = f"Show {wait:g} s after New/Open" if wait else "Show as the world is chosen"
    yield (f"viewport_cold_first_chunks_{tag}_s", R["first_s"], "s",
           f"fresh install (empty kernel cache, new world), {when}: tick Show -> first chunks "
           f"drawn (OpenCL still building then: {R['warming_at_first']}); {what}; goal 2 s")
    yield (f"viewport_cold_whole_view_{tag}_s", R["whole_s"], "s",
           f"the same -> every chunk drawn; goal 5 s (load {R['load']:.1f})")
    yield (f"viewport_cold_whole_view_{tag}_cpu_s", R["whole_cpu_s"], "s",
           "the same, process CPU (every thread: pocl's builds, llvmpipe's drawing; "
           f"helper processes' {R.get('children_cpu_s', 0.0):.2f} s included)")
    if R.get("warm_ended_s") is not None and not wait:
        yield (f"viewport_cold_after_warmup_{tag}_s", R["whole_s"] - R["warm_ended_s"], "s",
               "from the warm-up's end (every kernel built) to every chunk drawn")
    yield (f"viewport_cold_opencl_warmup_{tag}_s", R["warm"]["took"] or 0.0, "s",
           f"the OpenCL warm-up (generator + meshing kernels built and run) beside the "
           f"NumPy stream{'; failed: ' + R['warm']['error'] if R['warm']['error'] else ''}")


def backends(ctx, world):
    """The live view at distance 16 in every installed Blender on each GPU backend it is
    set up for (tools/viewport_backends_bench_job.py; one fresh Blender each, from a copy
    of the same file, the same view): frame full and draft (the pipeline every redraw,
    GPU finished), our Python per redraw, draw calls, the still view's redraw from its
    kept frame; ratios to the first OpenGL run (issue 19's targets: the gpu module on
    OpenGL within 1.2x of the old moderngl path, our Python <= 2 ms per redraw)."""
    import shutil
    base = None
    for blender, gpu in gui.variants():
        tag = f"{blender.replace('.', '')}_{gpu}"
        ctx.say(f"Blender {blender} GUI on {gpu}: the live view at distance 16")
        copy = ctx.tmp / f"backend_{tag}.sqlite"
        shutil.copy(world, copy)
        out = ctx.tmp / f"backend_{tag}.json"
        R = gui.run_job("viewport_backends", [out, copy], out, ctx.tmp / f"backend_{tag}.log",
                        timeout=1800, simulate=False, blender=blender, gpu=gpu)
        if not R.get("ok"):
            raise RuntimeError(R.get("error"))
        base = base or R
        what = (f"Blender {R['blender']} {R['backend']} ({R['renderer']}), distance 16 "
                f"({R['chunks']} chunks), region {'x'.join(map(str, R['region']))}")
        for q in ("full", "draft"):
            yield (f"viewport_frame_{q}_{tag}_ms", R[f"{q}_ms"], "ms",
                   f"{q} quality, the pipeline every redraw, GPU finished (min of 6; median "
                   f"{R[f'{q}_ms_median']:.0f}); {what}")
            yield (f"viewport_python_{q}_{tag}_ms", R[f"{q}_python_ms"], "ms",
                   f"our Python per {q} redraw outside the GPU calls (median)")
            yield (f"viewport_submit_{q}_{tag}_ms", R[f"{q}_submit_ms"], "ms",
                   "issuing the passes and the composite (Python + the backend's CPU work)")
            yield (f"viewport_draw_calls_{q}_{tag}", R[f"{q}_draw_calls"], "",
                   f"geometry draws per {q} frame (region batches, all passes)")
            yield (f"viewport_frame_{q}_{tag}_ratio", R[f"{q}_ms"] / base[f"{q}_ms"], "",
                   f"to Blender {base['blender']} {base['backend']} (<1: faster)")
        yield (f"viewport_still_{tag}_ms", R["still_ms"], "ms",
               "a still view's redraw from its kept frame (the handler, GPU finished)")
        yield (f"viewport_python_still_{tag}_ms", R["still_python_ms"], "ms",
               "our Python per redraw from the kept frame")
        yield (f"viewport_redraw_still_{tag}_ms", R["still_region_ms"], "ms",
               "whole region redraw of the still view (Blender's redraw_timer)")
        yield (f"viewport_redraw_blender_only_{tag}_ms", R["blender_region_ms"], "ms",
               "whole region redraw with the view off (Blender's own drawing)")
        yield (f"viewport_show_d16_{tag}_s", R["show_s"], "s",
               "tick Show -> every chunk of distance 16 drawn (generated file)")


def frames(ctx, world, d, far, rounds=30):
    """The live view's frame on Blender's gpu module against the moderngl frame of the
    same scene, and far FAR against far 0 (issue 28), in one Blender (the newest,
    OpenGL; tools/frames_bench_job.py): the same payloads, far tiles, settings, camera
    and size; ROUNDS interleaved rounds in a rotated order, the GPU finished in each
    frame (and before the live frame starts: Blender's own drawing of the region,
    queued when the handler runs, is not the frame's). Sides: gpu (the live view's redraw), gpr (its Renderer alone), mgl
    (moderngl). Medians of wall and process CPU time, and ratios as the median of
    each round's ratio (the machine's load moves both sides of a round alike).
    Goals: gpu/moderngl <= 1.05, far/far 0 <= 1.3."""
    import os
    import shutil
    copy = ctx.tmp / "frames.sqlite"
    shutil.copy(world, copy)
    out = ctx.tmp / "frames.json"
    ctx.say(f"Blender GUI: gpu-module and moderngl frames, far {far} and 0, {rounds} rounds")
    R = gui.run_job("frames", [out, copy, d, far, rounds], out, ctx.tmp / "frames.log",
                    timeout=1800, simulate=False, gpu="opengl")
    if not R.get("ok"):
        raise RuntimeError(R.get("error"))
    import statistics as st
    what = (f"Blender {R['blender']} {R['backend']} ({R['renderer']}), distance {d} "
            f"({R['chunks']} chunks, {R['tiles']} far tiles), region "
            f"{'x'.join(map(str, R['region']))}, {rounds} rounds, load "
            f"{os.getloadavg()[0]:.1f} after")
    sides = (("gpu", "the live view's frame on Blender's gpu module (composite included)"),
             ("gpr", "the live view's Renderer alone on the gpu module (Renderer.draw)"),
             ("mgl", "moderngl (Renderer.draw), its own EGL context in the same process"))
    for q in ("full", "draft"):
        for side, name in sides:
            for f in (0, far):
                t = f"{q}_{side}_{f}"
                yield (f"viewport_frame_{side}_{q}_far{f}_ms", st.median(R[f"{t}_ms"]), "ms",
                       f"{q} frame, far {f}, {name}: median wall, GPU finished; "
                       f"{R[f'{t}_calls']} draw calls; {what}")
                yield (f"viewport_frame_{side}_{q}_far{f}_cpu_ms", st.median(R[f"{t}_cpu_ms"]),
                       "ms", "the same: process CPU (all threads, llvmpipe's included)")
        for k, what in (("python", "our Python outside the GPU calls"),
                        ("submit", "issuing the passes and the composite (Python + the "
                                   "backend's CPU work)"),
                        ("composite_cpu", "composite alone, process CPU (GPU finished before "
                                          "and after it)"),
                        ("host_cpu", "Blender's own drawing of the region queued before the "
                                     "redraw's handler, process CPU: finished before the "
                                     "frame's timing starts, not part of the frame")):
            yield (f"viewport_frame_gpu_{q}_{k}_ms", st.median(R[f"{q}_gpu_0_{k}_ms"]), "ms",
                   f"the live redraw's {what}, far 0 (median)")
        for c, how in (("", "wall"), ("_cpu", "process CPU")):
            for side in ("gpu", "gpr"):
                yield (f"viewport_frame_{side}_to_mgl_{q}{c}_ratio", R[f"{q}_{side}_to_mgl{c}"], "",
                       f"{side} / mgl, {q}, far 0, {how} (median of the rounds' ratios; goal "
                       "<= 1.05)")
                yield (f"viewport_frame_{side}_to_mgl_{q}_far{far}{c}_ratio",
                       R[f"{q}_{side}_to_mgl_far{c}"], "", f"the same with far {far}")
            for side in ("gpu", "gpr", "mgl"):
                yield (f"viewport_frame_far{far}_to_far0_{side}_{q}{c}_ratio",
                       R[f"{q}_far_to_0_{side}{c}"], "",
                       f"far {far} / far 0, {side}, {q}, {how} (median of the rounds' ratios; "
                       "goal <= 1.3)")


MATERIAL_LIMIT_S = {8: 90.0, 16: 240.0}  # EEVEE's shader compilation on llvmpipe


def compare(ctx, world, d):
    """The live view against the same chunks baked by the user's Bake to Objects and
    drawn by Blender (Solid, Material Preview), one fresh Blender per side from a copy
    of the same world file (tools/viewport_compare_bench_job.py): redraw, memory (RSS
    growth from the same baseline, and peak), time from opening the file to the
    picture; ratios baked/live (>1: the live view wins). Rows end in _d{d}."""
    import shutil
    S = {}
    for side in ("live", "baked"):
        ctx.say(f"Blender GUI: {side} side of the comparison at distance {d}")
        copy = ctx.tmp / f"compare_{side}.sqlite"
        shutil.copy(world, copy)  # the live side saves the light it made into its copy
        out = ctx.tmp / f"compare_{side}.json"
        S[side] = gui.run_job("viewport_compare", [out, side, copy, str(d), str(MATERIAL_LIMIT_S[d])],
                              out, ctx.tmp / f"compare_{side}.log", timeout=1800, simulate=False)
        if not S[side].get("ok"):
            raise RuntimeError(S[side].get("error"))
    L, B = S["live"], S["baked"]
    n, sz, t = f"_d{d}", "x".join(map(str, L["region"])), f"distance {d} ({L['chunks']} chunks)"
    tris = f"{B['triangles']} triangles"
    mat = (f"not compiled after {B['material_ready_s']:.0f} s (limit): redraws while EEVEE "
           "still compiles" if B.get("material_timed_out") else
           f"shaders compiled after {B['material_ready_s']:.1f} s")
    yield (f"viewport_redraw_live{n}_ms", L["redraw_ms"], "ms",
           f"region redraw of a still live view (full quality, from its kept frame), {t}, "
           f"region {sz}")
    yield (f"viewport_redraw_live_pipeline{n}_ms", L["redraw_pipeline_ms"], "ms",
           "the same with the whole pipeline run on every redraw (something in it changed)")
    yield (f"viewport_redraw_live_draft{n}_ms", L["redraw_draft_ms"], "ms",
           "the same in draft quality (what a redraw costs while the view moves)")
    yield (f"viewport_redraw_baked_solid{n}_ms", B["solid_ms"], "ms", f"Solid, one object, {tris}")
    yield (f"viewport_redraw_baked_material{n}_ms", B["material_ms"], "ms",
           f"Material Preview ({B['material_engine']}), {mat}")
    yield (f"viewport_frame_ratio_baked_solid_to_live{n}", B["solid_ms"] / L["redraw_ms"], "",
           ">1: the live view redraws faster than Solid")
    yield (f"viewport_frame_ratio_baked_solid_to_live_pipeline{n}",
           B["solid_ms"] / L["redraw_pipeline_ms"], "", ">1: even the full pipeline beats Solid")
    yield (f"viewport_frame_ratio_baked_solid_to_live_draft{n}", B["solid_ms"] / L["redraw_draft_ms"],
           "", ">1: a moving live view (draft) redraws faster than Solid")
    yield (f"viewport_frame_ratio_baked_material_to_live{n}", B["material_ms"] / L["redraw_ms"], "",
           ">1: the live view redraws faster than Material Preview")
    yield (f"viewport_first_picture_live{n}_s", L["first_picture_s"], "s",
           f"open the file -> all drawn (OpenCL start {L['first_picture_s'] - L['show_s']:.1f} s, "
           f"tick Show -> all drawn {L['show_s']:.1f} s)")
    yield (f"viewport_first_picture_baked{n}_s", B["first_picture_s"], "s",
           f"open the file -> Bake to Objects ({B['bake_s']:.1f} s) -> first Solid redraw")
    yield (f"viewport_first_picture_baked_material{n}_s",
           B["first_picture_s"] + B["material_ready_s"], "s",
           f"the same, then Material Preview until its shaders are compiled ({mat})")
    yield (f"viewport_time_ratio_baked_to_live{n}", B["first_picture_s"] / L["first_picture_s"], "",
           ">1: the live view shows the world sooner (baked: Solid)")
    yield (f"viewport_memory_live{n}_mb", L["rss_mb"], "MB",
           "RSS growth after gc from the baseline with the add-on registered (fresh Blender)")
    yield (f"viewport_memory_baked{n}_mb", B["rss_mb"], "MB", "the same, baked object in Solid")
    yield (f"viewport_memory_baked_material{n}_mb", B["material_rss_mb"], "MB",
           f"the same after Material Preview ({mat})")
    yield (f"viewport_memory_ratio_baked_to_live{n}", B["rss_mb"] / max(L["rss_mb"], 1.0), "",
           ">1: the live view needs less memory (baked: Solid)")
    yield (f"viewport_memory_peak_live{n}_mb", L["peak_mb"], "MB", "peak RSS growth (VmHWM)")
    yield (f"viewport_memory_peak_baked{n}_mb", B["peak_mb"], "MB",
           "peak RSS growth, bake and Solid (VmHWM)")
    yield (f"viewport_memory_peak_baked_material{n}_mb", B["material_peak_mb"], "MB",
           "peak RSS growth, including Material Preview")
    yield (f"viewport_memory_peak_ratio_baked_to_live{n}", B["peak_mb"] / max(L["peak_mb"], 1.0), "",
           ">1: the live view's peak is lower (baked: Solid)")
    yield from breakdown(L, n)


def breakdown(L, n):
    """What the live view's RSS growth is made of: the growth at each step, and the
    bytes of what it keeps (each array once; GL objects live in RAM on llvmpipe)."""
    last = 0.0
    for i, (name, rss, peak) in enumerate(L["steps"]):
        if name.startswith("(diagnostic)"):
            yield (f"viewport_memory_live{n}_trimmed_mb", rss, "MB",
                   "RSS growth after malloc_trim (freed memory glibc had kept)")
            continue
        yield (f"viewport_memory_live{n}_step{i + 1}_mb", rss - last, "MB",
               f"RSS growth of step {i + 1}: {name} (peak so far {peak:.0f} MB)")
        last = rss
    parts = {k: v for k, v in L["bytes"].items() if isinstance(v, float)}
    for k, v in parts.items():
        slug = "".join(ch if ch.isalnum() else "_" for ch in k.lower()).strip("_")
        while "__" in slug:
            slug = slug.replace("__", "_")
        yield (f"viewport_memory_live{n}_keeps_{slug}_mb", v, "MB",
               f"kept by the live view: {k}" + (f" ({L['bytes']['world_chunks']} chunks in the world)"
                                                 if k == "blocks" else ""))
    yield (f"viewport_memory_live{n}_keeps_other_mb", L["rss_mb"] - sum(parts.values()), "MB",
           "RSS growth not in the parts above: GL driver (llvmpipe shader code), OpenCL "
           "(pocl, LLVM), Python modules and objects, allocator slack")
