"""Blender side of the live-versus-baked comparison in voxel_addon/bench/viewport.py
(issue 12, Speed): one fresh Blender GUI per side, so both sides grow from the same
baseline (a process that ran the other side first reuses its freed memory).

    blender --factory-startup -P tools/viewport_compare_bench_job.py -- \
        OUT.json live|baked WORLD DISTANCE MATERIAL_LIMIT_S

Both sides show the chunks within DISTANCE of the view's chunk, from the moment the
world file is opened (timed from there: OpenCL, GL and shader start-up are part of
the time to the first picture on both sides).
- live: tick Show, redraw until every chunk is drawn; then region redraws at full
  quality. Memory step by step (RSS after each step) and the bytes of what stays
  (chunk data on the CPU, GL buffers and textures, which llvmpipe keeps in RAM).
- baked: the user's Bake to Objects (bpy.ops.voxel.bake, one object, light atlas)
  of the same chunks, the first Solid redraw, Solid redraws; then Material Preview
  (EEVEE): redraws until its shaders are compiled, within MATERIAL_LIMIT_S.

Memory is the Blender process's resident set (VmRSS of /proc/self/status, what
psutil reports; psutil is not in Blender's Python) after gc, as growth from the
baseline taken once the add-on is registered; the peak is VmHWM, reset at the
baseline (clear_refs 5).
"""
from __future__ import annotations

import gc
import math
import sys
import time
from pathlib import Path

import bpy

sys.path.insert(0, str(Path(__file__).resolve().parent))
import viewport_bench_job as V  # noqa: E402  (area, look, all_drawn, region_draw_ms)

R: dict = {}
MB = 1 << 20


def mem() -> tuple[float, float]:
    """(RSS, peak RSS) in MB."""
    got = {}
    for line in open("/proc/self/status"):
        if line.startswith(("VmRSS:", "VmHWM:")):
            got[line[:5]] = int(line.split()[1]) / 1024.0
    return got["VmRSS"], got["VmHWM"]


def reset_peak() -> bool:
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
        return True
    except OSError:
        return False


class Steps:
    """RSS growth after each named step, from one baseline (after gc)."""

    def __init__(self):
        gc.collect()
        self.base = mem()[0]
        R["peak_reset"] = reset_peak()
        R["steps"] = []

    def __call__(self, name: str) -> float:
        gc.collect()
        rss, peak = mem()
        R["steps"].append([name, round(rss - self.base, 1), round(peak - self.base, 1)])
        return rss - self.base


def trimmed(step) -> float:
    """RSS growth once glibc gave back the free memory it keeps (malloc_trim: how
    much of the growth is freed memory that was not returned, e.g. threads' arenas)."""
    import ctypes
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        return -1.0
    return step("(diagnostic) after malloc_trim")


def eye_area(d: int):
    """Block box [x0, x1) x [y0, y1) of the chunks within d of the view's eye chunk."""
    r3 = V.area().spaces.active.region_3d
    eye = r3.view_matrix.inverted().translation
    cx, cy = math.floor(eye.x) >> 4, math.floor(eye.y) >> 4
    return 16 * (cx - d), 16 * (cy - d), 16 * (cx + d + 1), 16 * (cy + d + 1)


def setup(world, d):
    import voxel_addon
    voxel_addon.register()
    sc = bpy.context.scene
    sp = V.area().spaces.active
    sp.overlay.show_overlays = False
    sp.clip_end = 2000.0
    sc.voxel.path = world
    sc.voxel_view.distance, sc.voxel_view.hours = d, 12.0
    V.look(30)
    r = next(r for r in V.area().regions if r.type == "WINDOW")
    R["region"] = [r.width, r.height]
    R["chunks"] = (2 * d + 1) ** 2
    return sc


# ---------------------------------------------------------------------- live
def live(world, d):
    from voxel_addon.blender import session
    from voxel_addon.blender.liveview import LIVE
    sc = setup(world, d)
    vv = sc.voxel_view
    yield 0.5
    step = Steps()
    t0 = time.perf_counter()
    w = session.world(world)
    step("open the world file")
    from voxel_addon import opencl
    from voxel_addon.world import build
    if build.backends()[1] == "opencl":  # what the stream's first batch does, timed apart
        import numpy as np
        from voxel_addon import meshing
        with build.CL_LOCK:
            meshing.build_chunks(np.zeros((18, 18, 256), np.uint16, order="F"), backend="opencl")
    R["opencl"] = opencl.available()
    step("pyopencl, OpenCL context, meshing programs")
    t1 = time.perf_counter()
    vv.quality = "auto"
    vv.show = True
    yield from frames_until_gpu()
    step("moderngl context, Renderer, first targets (first frame)")
    yield from V.all_drawn(900)
    t2 = time.perf_counter()
    R["first_picture_s"], R["show_s"] = t2 - t0, t2 - t1
    step(f"all {R['chunks']} chunks streamed and drawn (draft)")
    LIVE.finish = True
    vv.quality = "full"
    yield from V.frames(2)
    step("full-quality frames")
    # a still view redraws from its kept frame; the pipeline on every redraw (REUSE
    # off) is what a redraw costs when something in the picture changed; draft is a
    # redraw while the view moves
    LIVE.reuse = False
    R["redraw_pipeline_ms"] = V.region_draw_ms(3)
    vv.quality = "draft"
    R["redraw_draft_ms"] = V.region_draw_ms(3)
    vv.quality, LIVE.reuse = "full", True
    yield from V.frames(2)
    R["redraw_ms"] = V.region_draw_ms(3)
    R["rss_mb"] = step("region redraws")
    R["peak_mb"] = mem()[1] - step.base
    R["bytes"] = accounted(w)
    R["trimmed_mb"] = trimmed(step)
    LIVE.finish = False
    yield 0.1


def frames_until_gpu():
    """Redraw until the view's GL objects exist (the first frame made them)."""
    from voxel_addon.blender.liveview import LIVE
    t0 = time.perf_counter()
    while not LIVE.panes:
        if LIVE.error:
            raise RuntimeError(LIVE.error)
        if time.perf_counter() - t0 > 120:
            raise RuntimeError("no voxel frame in 120 s")
        V.area().tag_redraw()
        yield 0.01


class _Sized:
    """A core.chunk.Packed, counted like a view of it (accounted() counts the base:
    the Packed, whose nbytes are its compressed bytes)."""

    def __init__(self, packed):
        self.base = packed


def _arrays(x):
    """NumPy arrays reachable from a light value (an array, packed layers, or a
    chunk's Packed)."""
    import numpy as np
    if isinstance(x, np.ndarray):
        yield x
    elif hasattr(x, "body"):
        yield _Sized(x)
    elif isinstance(x, tuple):
        for v in x:
            if isinstance(v, np.ndarray):
                yield v


def _fields(c, name):
    """A chunk's stored forms of blocks: the array and/or its packed layers."""
    if hasattr(c, "_" + name):
        return (getattr(c, "_" + name), getattr(c, "_bpack", None))
    return (getattr(c, name),)


def accounted(w) -> dict:
    """MB of what the live view keeps, each array counted once: the world's chunks
    (blocks, light, CPU meshes), payload light held only by the view, the GL objects
    (bytes that llvmpipe allocates in RAM)."""
    from voxel_addon.blender.liveview import LIVE
    seen, out = set(), {}

    def add(name, arrays):
        n = 0
        for a in arrays:
            base = a if a.base is None else a.base
            if id(base) not in seen and hasattr(base, "nbytes"):
                seen.add(id(base))
                n += base.nbytes
        out[name] = out.get(name, 0.0) + n / MB

    chunks = list(w.chunks.values())
    out["world_chunks"] = len(chunks)
    # (the fields, not .blocks: a read would unpack packed blocks)
    add("blocks", (a for c in chunks for x in _fields(c, "blocks") for a in _arrays(x)))
    add("light (world)", (a for c in chunks for x in (c._light, c._lpack) for a in _arrays(x)))
    add("meshes: vertices", (c.mesh.vertices for c in chunks if c.mesh is not None))
    add("meshes: quads", (c.mesh.quads for c in chunks if c.mesh is not None))
    add("meshes: ranges", (c.mesh.ranges for c in chunks if c.mesh is not None))
    feed = LIVE.feed
    if feed is not None:
        ps = list(feed.chunks.values())
        add("light (view's payloads)", (a for p in ps for a in _arrays(p.light)))
        add("meshes (view's payloads)", (a for p in ps for a in (p.mesh.vertices, p.mesh.quads)))
    for g in LIVE.panes.values():
        r = g.r
        add("light (renderer)", (a for v in r.lights.values() for a in _arrays(v)))
        out["GL vertex buffers"] = r.geo.nbytes / MB
        out["GL light volume"] = r.vol.tex.nbytes / MB
        out["GL render targets"] = r.targets.nbytes / MB if r.targets else 0.0
        out["GL block textures"] = (r.blocks.tex.nbytes + r.blocks.glow.nbytes) / MB
        out["targets key"] = str(r.targets.shape) if r.targets else ""
    return out


def baked(world, d, limit):
    from voxel_addon.blender import session
    sc = setup(world, d)
    yield 0.5
    step = Steps()
    t0 = time.perf_counter()
    session.world(world)
    step("open the world file")
    x0, y0, x1, y1 = eye_area(d)
    b = sc.voxel_bake
    b.region_min, b.region_max = (x0, y0), (x1, y1)
    b.per, b.light, b.method = "region", "atlas", "greedy"
    t1 = time.perf_counter()
    if bpy.ops.voxel.bake() != {"FINISHED"}:  # Bake to Objects, run at once
        raise RuntimeError("bake failed")
    t2 = time.perf_counter()
    step("Bake to Objects (mesh, materials, light atlas, undo step)")
    R["first_draw_ms"] = V.region_draw_ms(1)
    R["first_picture_s"] = time.perf_counter() - t0
    R["bake_s"] = t2 - t1
    R["triangles"] = sum(len(o.data.polygons) * 2 for o in bpy.data.objects if o.type == "MESH")
    step("first Solid redraw (Blender's GPU batches)")
    R["solid_ms"] = V.region_draw_ms(3)
    R["rss_mb"] = step("Solid redraws")
    R["peak_mb"] = mem()[1] - step.base
    yield 0.1
    yield from material(limit, step)


def material(limit, step):
    """Material Preview: redraw until EEVEE's shaders are compiled (or the limit)."""
    shading = V.area().spaces.active.shading
    t0 = time.perf_counter()
    shading.type = "MATERIAL"
    n = 0
    while True:
        V.area().tag_redraw()
        yield 0.05
        n += 1
        busy = bpy.app.is_job_running("SHADER_COMPILATION")
        if not busy and n >= 3:
            break
        if time.perf_counter() - t0 > limit:
            R["material_timed_out"] = True
            break
    R["material_ready_s"] = time.perf_counter() - t0
    R["material_ms"] = V.region_draw_ms(3)
    R["material_rss_mb"] = step("Material Preview redraws")
    R["material_peak_mb"] = mem()[1] - step.base
    R["material_engine"] = bpy.context.scene.render.engine
    R["trimmed_mb"] = trimmed(step)


# ---------------------------------------------------------------------- main
def main(out, mode, world, d, limit):
    yield from V.report(live(world, d) if mode == "live" else baked(world, d, limit), R, out)


def start():
    args = sys.argv[sys.argv.index("--") + 1:]
    out, mode, world, d, limit = Path(args[0]), args[1], args[2], int(args[3]), float(args[4])
    V.drive(main(out, mode, world, d, limit))


if __name__ == "__main__":
    start()
