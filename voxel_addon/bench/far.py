"""Bench area `far` (issue 22): the far ring's data side: time from an empty file to
a horizon at far 128 and 256 (alone and beside the near stream), a second view,
the generator's surface rate, triangles per level, memory and file growth; and the
drawing side: frame times full and draft at distance 16 with far 256 against far 0
(the live view's settings, at its region size), triangles drawn, memory added."""
from __future__ import annotations

import gc
import os
import time

import numpy as np

from ..far import Builder, grid
from ..generation import make_generator
from ..world import Stream, World

SEED = 7
NEAR = 16
VIEW = (8.0, 8.0)


def _load() -> str:
    return "load average %.1f" % os.getloadavg()[0]


def _horizon(world, far, near=NEAR, drains=None):
    """Seconds from set_view to every wanted tile drained (4 ms drains every 2 ms,
    meshes kept as a consumer keeps them), and the builder and meshes."""
    t0 = time.perf_counter()
    b = Builder(world.file, world.generator)
    b.set_view(*VIEW, far=far, near=near)
    meshes = {}
    while True:
        t = time.perf_counter()
        ready, gone = b.drain(0.004)
        if drains is not None:
            drains.append(time.perf_counter() - t)
        meshes.update((m.key, m) for m in ready)
        for k in gone:
            meshes.pop(k, None)
        if b.error is not None:
            raise b.error
        if b.counts[0] == len(meshes) and b.counts[1] == b.counts[0]:
            break
        time.sleep(0.002)
    return time.perf_counter() - t0, b, meshes


FRAME = (1057, 618)   # the GUI bench's region (bench/gui.py, 1280x720 screen)


def _frames(ctx, proc):
    """Frame ms at distance 16, far 256 against far 0 (interleaved, each the fastest
    of n after a warm-up: the machine is shared), full and draft as the live view makes them (msaa 1, its
    shadow map, draft: half size without shadows, SSAO, blur, god rays, one peel)."""
    import math
    from ..far import ring
    from ..render import Camera, Settings, source
    from ..render.device import mgl
    from ..render.pipeline import Renderer
    far, n = (128 if ctx.quick else 256), (3 if ctx.quick else 7)
    with World.create(ctx.tmp / "farframes.sqlite", seed=SEED) as w:
        w.generate_area([(x, y) for x in range(-NEAR - 1, NEAR + 2)
                         for y in range(-NEAR - 1, NEAR + 2)])
        h0 = float(w.generator.surface(np.array([[8, 8]]))["height"][0])
        cam = Camera(VIEW[0], VIEW[1], h0 + 24.0, math.degrees(math.atan2(-928, 960)), 2.0)
        area = source.world_area(w, cam.x, cam.y, NEAR, 8)
        meshes = ring(w.file, w.generator, cam.x, cam.y, far, NEAR)
    gl = mgl.context()
    full = Settings(distance=NEAR, light_radius=8, msaa=1, shadow_size=1024, dof=False)
    draft = Settings(distance=NEAR, light_radius=8, msaa=1, shadow_size=1024, dof=False,
                     shadows=False, ssao=False, godrays=False, per_sample=False,
                     peel_layers=1, far_draft=True)
    r = Renderer(gl, full)
    r.set_area(area.blocks, area.light, area.cx0, area.cy0, ring=True, light_at=area.light_at)
    r.render(cam, 12.0, FRAME)
    gc.collect()
    rss0 = proc.memory_info().rss
    r.update_far(meshes)
    r.s.far = far
    r.render(cam, 12.0, FRAME)
    added = proc.memory_info().rss - rss0
    tris = r.stats["far_triangles"]
    out = {}
    for q, s, size in (("full", full, FRAME), ("draft", draft, (FRAME[0] // 2, FRAME[1] // 2))):
        r.s = s
        times = {0: [], far: []}
        for i in range(n + 1):
            for f in (0, far):
                s.far = f
                gl.finish()
                t = time.perf_counter()
                r.draw(cam, 12.0, size)
                gl.finish()
                if i:
                    times[f].append((time.perf_counter() - t) * 1e3)
        out[q] = {f: float(np.min(v)) for f, v in times.items()}
    r.release()
    gl.release()
    for q in ("full", "draft"):
        a, b = out[q][0], out[q][far]
        yield (f"far_frame_{q}_ms_far0", a, "ms", f"distance {NEAR}, {FRAME} (draft half), "
               f"the vista toward the mountains, fastest of {n}, {_load()}")
        yield (f"far_frame_{q}_ms_far{far}", b, "ms", f"the same with far {far}")
        yield (f"far_frame_{q}_ratio{far}", b / a, "x", "far on / off (target <= 1.3)")
    yield (f"far_frame_triangles{far}", tris, "", "far triangles drawn in that frame (after "
           "tile culling)")
    yield (f"far_memory_added_mb{far}", added / 2 ** 20, "MiB", "process RSS added by the far "
           "ring: its meshes uploaded (llvmpipe keeps GPU buffers in process memory) and the "
           "first frame (target <= 300)")


def _gui(ctx):
    """The live view in the real Blender GUI (tools/far_bench_job.py; the newest
    Blender, OpenGL): Show ticked with far set, on a file holding the distance-16
    chunks and no far data: seconds to every chunk and to the horizon (every far
    tile), far triangles and GPU bytes, frames full and draft with far on and off."""
    import shutil
    import subprocess
    import sys
    from . import gui
    why = gui.missing()
    if why:
        yield ("far_gui_skipped", 1, "", why)
        return
    world = ctx.tmp / "fargui.sqlite"
    r = subprocess.run([sys.executable, "-m", "voxel_addon", "generate", "--world", str(world),
                        "--seed", str(SEED), "--center", "8", "8", "--radius", "18"],
                       capture_output=True, text=True)
    if r.returncode:
        raise RuntimeError(r.stderr[-2000:])
    yield from _gui_cold(ctx, world, 64 if ctx.quick else 128)
    for far in ((64,) if ctx.quick else (128, 256)):
        copy = ctx.tmp / f"fargui{far}.sqlite"
        shutil.copy(world, copy)
        out = ctx.tmp / f"fargui{far}.json"
        ctx.say(f"Blender GUI: Show with far {far}")
        R = gui.run_job("far", [out, copy, far], out, ctx.tmp / f"fargui{far}.log",
                        timeout=1800, simulate=False, gpu="opengl")
        if not R.get("ok"):
            raise RuntimeError(R.get("error"))
        what = f"Blender {R['blender']} {R['backend']}, distance 16, region " \
               f"{'x'.join(map(str, R['region']))}"
        yield (f"far_gui_show_to_horizon{far}_s", R["horizon_s"], "s",
               f"tick Show (far {far}) -> every far tile drawn ({R['tiles']}); every chunk "
               f"after {R['near_s']:.1f} s; {what}, {_load()}")
        yield (f"far_gui_triangles{far}", R["far_triangles"], "", "far triangles uploaded")
        yield (f"far_gui_gpu_mb{far}", R["far_gpu_mb"], "MiB", "far vertex + index buffers "
               "(both index sets: full and draft)")
        for q in ("full", "draft"):
            a, b = R[f"{q}_0_ms"], R[f"{q}_{far}_ms"]
            yield (f"far_gui_frame_{q}_ms_far0", a, "ms", f"{q} frame, far 0, the pipeline "
                   f"every redraw, GPU finished (fastest of 5 interleaved); {what}")
            yield (f"far_gui_frame_{q}_ms_far{far}", b, "ms", f"the same with far {far}")
            yield (f"far_gui_frame_{q}_ratio{far}", b / a, "x", "far on / off (target <= 1.3)")


def _gui_cold(ctx, world, far):
    """Show to horizon as a fresh install meets it (issue 28: far 128 <= 6 s): an empty
    kernel cache (pocl's and pyopencl's), the same file; the far tiles alone (every
    one drawn) and with every chunk, wall and process CPU; no frame rows."""
    import shutil
    from . import gui
    copy, cache = ctx.tmp / f"farcold{far}.sqlite", ctx.tmp / f"farcold{far}_kernels"
    # cold means cold: no kernels, and no WAL of an earlier run (its far tiles) beside
    shutil.rmtree(cache, ignore_errors=True)
    for extra in ("-wal", "-shm"):
        copy.with_name(copy.name + extra).unlink(missing_ok=True)
    shutil.copy(world, copy)
    out = ctx.tmp / f"farcold{far}.json"
    ctx.say(f"Blender GUI: Show with far {far}, empty kernel cache")
    env = {"POCL_CACHE_DIR": str(cache / "pocl"), "PYOPENCL_CACHE_DIR": str(cache / "pyopencl"),
           "VOXEL_TRACE": "1", "VOXEL_BENCH_FRAMES": "0"}
    R = gui.run_job("far", [out, copy, far], out, ctx.tmp / f"farcold{far}.log",
                    timeout=1800, simulate=False, gpu="opengl", env=env)
    if not R.get("ok"):
        raise RuntimeError(R.get("error"))
    what = f"Blender {R['blender']} {R['backend']}, distance 16, load {R['load']:.1f}"
    yield (f"far_gui_cold_far_drawn{far}_s", R["far_s"], "s",
           f"fresh install (empty kernel cache): tick Show (far {far}) -> every far tile drawn "
           f"({R['tiles']}; the first after {R['first_far_s']:.1f} s); {what}; goal 6 s")
    yield (f"far_gui_cold_far_drawn{far}_cpu_s", R["far_cpu_s"], "s",
           "the same, process CPU (every thread: pocl's builds, llvmpipe's drawing)")
    yield (f"far_gui_cold_horizon{far}_s", R["horizon_s"], "s",
           f"the same -> every far tile and every chunk drawn ({R['near_s']:.1f} s to the "
           f"chunks; process CPU {R['horizon_cpu_s']:.1f} s)")


def run(ctx):
    import psutil
    proc = psutil.Process()
    yield from _frames(ctx, proc)
    yield from _gui(ctx)
    fars = (64, 128) if ctx.quick else (128, 256)
    note_q = " (quick: smaller far)" if ctx.quick else ""
    with World.create(ctx.tmp / "farwarm.sqlite", seed=SEED) as w:  # kernel builds
        _, b, _ = _horizon(w, 8, 0)
        b.close()

    gen = make_generator("overworld", SEED, None, None)
    rng = np.random.default_rng(1)
    for backend in ("opencl", "numpy"):
        g = make_generator("overworld", SEED, None, backend) if backend != gen.backend_used \
            else gen
        xy = rng.integers(-4096, 4096, (65536 if backend == "opencl" else 8192, 2))
        g.surface(xy[:64])
        t = time.perf_counter()
        g.surface(xy)
        dt = time.perf_counter() - t
        yield (f"far_surface_{backend}_columns_per_s", len(xy) / dt, "1/s",
               f"Generator.surface (2D passes pruned to height, block, trees; 1-column "
               f"domains), overworld, {_load()}")

    for far in fars:
        path = ctx.tmp / f"far{far}.sqlite"
        gc.collect()
        rss0 = proc.memory_info().rss
        drains = []
        with World.create(path, seed=SEED) as w:
            dt, b, meshes = _horizon(w, far, drains=drains)
            gc.collect()
            grown = proc.memory_info().rss - rss0
            tris = sum(m.triangles for m in meshes.values())
            mb = sum(m.nbytes for m in meshes.values()) / 2 ** 20
            b.close()
        yield (f"far_horizon{far}_s", dt, "s",
               f"empty file to every far tile drained, far {far} beyond near {NEAR}, "
               f"{len(meshes)} tiles ({b.stats['built']} built), {_load()}{note_q}")
        d = np.array(drains) * 1e3
        yield (f"far_consumer_max_ms{far}", float(d.max()), "ms",
               f"longest drain call (4 ms budget) of {len(d)} while building, p99 "
               f"{np.percentile(d, 99):.2f} ms, {_load()}")
        yield (f"far_triangles{far}", tris, "", "the far ring's triangles (every tile, before "
               "culling), " + ", ".join(
                   f"level {lv} (s={grid.spacing(lv)}): "
                   f"{sum(m.triangles for k, m in meshes.items() if k[0] == lv)}"
                   for lv in grid.LEVELS))
        yield (f"far_mesh_mb{far}", mb, "MiB", f"far meshes' vertex + index bytes "
               f"({mesh_bytes_note()}): the GPU copy is the same size")
        yield (f"far_rss_mb{far}", grown / 2 ** 20, "MiB", "process RSS growth while building "
               "(meshes, builder, generator runner, SQLite cache)")
        yield (f"far_file_mb{far}", os.path.getsize(path) / 2 ** 20, "MiB",
               "world file with only far tables (samples of every tile)")
        with World.open(path) as w:
            dt, b, meshes = _horizon(w, far)
            b.close()
        yield (f"far_second_view{far}_s", dt, "s", f"the same view again: tiles loaded from the "
               f"file ({b.stats['loaded']} loaded, {b.stats['built']} built), {_load()}")

    far = fars[-1]
    with World.create(ctx.tmp / "farstream.sqlite", seed=SEED) as w:
        s = Stream(w, NEAR)
        s.set_view(*VIEW)
        dt, b, meshes = _horizon(w, far)
        b.close()
        s.close()
    yield (f"far_horizon{far}_with_stream_s", dt, "s", f"as far_horizon{far}_s with the near "
           f"stream (distance {NEAR}) working from the same empty file, {_load()}{note_q}")


def mesh_bytes_note() -> str:
    from ..far import mesh
    return f"{mesh.BYTES_PER_VERTEX} B per vertex, 4 B per index"
