"""Render bench (thesis tables 6.10–6.14 analogue) on the GL it gets (here Mesa llvmpipe):
per reference scene and effect the frame time at 640×360, triangles and draw calls per
frame, and the Python side's cost per frame; plus the CPU cost at view distance 32.

Frame ms: ctx.finish(), then draw() and ctx.finish() again (no readback). Python side:
`submit` is the wall time until draw() returns and `thread_cpu` the calling thread's CPU
time in it (time.thread_time: llvmpipe's raster threads excluded, but work the driver
does in the calling thread, e.g. vertex setup, included). `cull` is the frustum
culling of all regions (NumPy), the part that grows with the view distance.
"""
from __future__ import annotations

import time

VARIANTS = [("default", None), ("no_effects", "none"), ("no_shadows", "-shadows"),
            ("ssao", "+ssao"), ("peel0", "peel0"), ("msaa1", "msaa1"), ("msaa4", "msaa4"),
            ("no_godrays", "-godrays"), ("no_dof", "-dof"), ("no_fog", "-fog"),
            ("no_waving", "-waving")]


def _frame(gl, r, cam, hours, size):
    """(frame ms, submit ms, thread CPU ms) of one frame."""
    gl.finish()
    t0, c0 = time.perf_counter(), time.thread_time()
    r.draw(cam, hours, size)
    sub, cpu = time.perf_counter() - t0, time.thread_time() - c0
    gl.finish()
    return (time.perf_counter() - t0) * 1e3, sub * 1e3, cpu * 1e3


def _measure(gl, r, cam, hours, size, n):
    _frame(gl, r, cam, hours, size)  # compile + warm up
    runs = [_frame(gl, r, cam, hours, size) for _ in range(n)]
    return [min(x[i] for x in runs) for i in range(3)]


def run(ctx):
    from ..meshing import scenes
    from ..render import Camera, Settings, sky, source
    from ..render.pipeline import Renderer
    gl = source.context()
    size = (320, 180) if ctx.quick else (640, 360)
    variants = VARIANTS[:2] if ctx.quick else VARIANTS
    n = 1 if ctx.quick else 2
    table = {}
    for name in scenes.SCENES:
        sc = scenes.SCENES[name]
        a = source.scene_area(name)
        r = Renderer(gl, Settings())
        r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
        hours = sky.parse_time(sc.time)
        for vname, eff in variants:
            r.s = Settings().with_effects(eff)
            ms, sub, cpu = _measure(gl, r, Camera(*sc.camera), hours, size, n)
            table[name, vname] = ms
            st = r.stats
            note = f"{size[0]}x{size[1]}, {st['triangles']} tris, {st['draw_calls']} draws"
            yield (f"render_{name}_{vname}_ms", ms, "ms", note)
            if vname == "default":
                yield (f"render_{name}_triangles", st["triangles"], "",
                       f"per frame incl. {st.get('shadow_triangles', 0)} in the shadow map")
                yield (f"render_{name}_draw_calls", st["draw_calls"], "", "per frame, all passes")
                yield (f"render_{name}_submit_ms", sub, "ms", "wall time until draw() returns")
                yield (f"render_{name}_thread_cpu_ms", cpu, "ms", "calling thread CPU time")
        r.release()
    yield from _distance32(ctx, gl)
    gl.release()

    def draw(ax):
        import numpy as np
        names = list(scenes.SCENES)
        x = np.arange(len(variants))
        for i, s in enumerate(names):
            ax.bar(x + i * 0.2 - 0.3, [table[s, v] for v, _ in variants], 0.2, label=s)
        ax.set_xticks(x, [v for v, _ in variants], rotation=45, ha="right")
        ax.set_ylabel(f"ms per frame ({size[0]}x{size[1]}, llvmpipe)")
        ax.legend()
    ctx.plot("render_effects", draw)


def _distance32(ctx, gl):
    """View distance 32 (65 × 65 chunks): the landscape scene's chunk meshes tiled over
    the whole area (the same geometry a real world would have per chunk), light window
    bounded; measured on a small viewport so llvmpipe's raster time stays short."""
    from .. import opencl
    from ..meshing import build_chunk
    from ..render import Camera, Settings, sky, source
    from ..render.pipeline import Renderer
    d = 8 if ctx.quick else 32
    a = source.scene_area("landscape")
    tiles = [[build_chunk(a.blocks[16 * i:16 * i + 18, 16 * j:16 * j + 18], backend="opencl" if opencl.available() else "numpy")
              for j in range(4)] for i in range(4)]
    meshes = {(cx, cy): tiles[cx % 4][cy % 4] for cx in range(-d, d + 1) for cy in range(-d, d + 1)}
    s = Settings(distance=d, msaa=1, waving=False)  # CPU side is measured; keep llvmpipe short
    r = Renderer(gl, s)
    r.set_meshes(meshes)
    r.set_light(a.light, a.cx0, a.cy0)  # outside the window: open daylight
    cam = Camera(8, 8, 100, 30, -15)
    hours = sky.parse_time("10:00")
    ms, sub, cpu = _measure(gl, r, cam, hours, (160, 90), 1 if ctx.quick else 2)
    st = r.stats
    vp = cam.view_proj()
    t0 = time.perf_counter()
    reps = 20
    for _ in range(reps):
        for p in ("opaque", "cutout", "cutout2", "blend"):
            r.geo.visible(p, vp)
    cull = (time.perf_counter() - t0) / reps * 1e3
    regions = sum(len(p["first"]) for p in r.geo.parts.values())
    note = f"distance {d}: {len(meshes)} chunks, {regions} region draws before culling"
    yield (f"render_d{d}_submit_ms", sub, "ms", note)
    yield (f"render_d{d}_thread_cpu_ms", cpu, "ms", "calling thread CPU time in draw()")
    yield (f"render_d{d}_cull_ms", cull, "ms", "NumPy frustum culling of all regions, 4 passes")
    yield (f"render_d{d}_frame_ms", ms, "ms", f"160x90, {st['triangles']} tris, "
           f"{st['draw_calls']} draws (llvmpipe)")
    yield (f"render_d{d}_triangles", st["triangles"], "", "per frame")
    r.release()
