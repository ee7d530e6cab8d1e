"""Blender side of the first-minute rows of voxel_addon/bench/viewport.py (there it is
only a path): runs in the real Blender GUI under Xvfb, started as a script.

    blender --factory-startup -P tools/first_bench_job.py -- OUT.json WORLD DISTANCE

WORLD is a new, empty world file; the bench starts Blender with an empty kernel cache
(POCL_CACHE_DIR, PYOPENCL_CACHE_DIR), as a fresh install has. The view looks at the
origin from above; Show is ticked: seconds until a frame drew chunks and until every
wanted chunk was drawn, with the OpenCL warm-up's time (issue 28). The view paces
its own redraws, as for a person who waits; VOXEL_BENCH_TAG=1 asks for one every
20 ms as this job did before (to compare with the old rows: ~4 s more CPU).
VOXEL_BENCH_OPEN_FIRST=S opens the world first, as New or Open World does (the
kernels start building then), and ticks Show S seconds later.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import viewport_bench_job as V  # noqa: E402  (its start() runs only as __main__)
R: dict = {}


def run(world: str, distance: int):
    import os
    import voxel_addon
    from voxel_addon import opencl
    from voxel_addon.core import trace
    from voxel_addon.blender.liveview import LIVE
    if not hasattr(bpy.types.Scene, "voxel_view"):
        voxel_addon.register()
    sc = bpy.context.scene
    sc.voxel.path = world
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.quality = distance, 12.0, "auto"
    V.look(-44.0)
    wait = float(os.environ.get("VOXEL_BENCH_OPEN_FIRST", "0"))
    if wait:  # as a user does: New or Open World first, Show a few seconds later
        from voxel_addon.blender import session
        session.world(world)
        R["opened_first_s"] = wait
    yield wait or 0.5
    t0, m0, c0 = time.perf_counter(), time.monotonic(), time.process_time()
    k0 = children_cpu()
    th0 = threads_cpu()
    vv.show = True
    first = None
    while True:
        if os.environ.get("VOXEL_BENCH_TAG", "0") == "1":
            V.area().tag_redraw()
        s = LIVE.stats
        if first is None and s["drawn"] > 0:
            first = time.perf_counter() - t0
            R["warming_at_first"] = opencl.warming()
        if first is not None and s["drawn"] >= s["wanted"] > 0:
            break
        if LIVE.error:
            raise RuntimeError(LIVE.error)
        if time.perf_counter() - t0 > 600:
            raise RuntimeError(f"no whole view after 600 s: {s}")
        yield 0.02
    R["first_s"], R["whole_s"], R["chunks"] = first, time.perf_counter() - t0, s["wanted"]
    # every thread's (llvmpipe's too), and the helper processes' (opencl.helper: waited
    # for by the warm-up before the whole view can come)
    R["children_cpu_s"] = children_cpu() - k0
    R["whole_cpu_s"] = time.process_time() - c0 + R["children_cpu_s"]
    th1 = threads_cpu()  # per thread name: pocl's compiler and llvmpipe have their own
    R["threads_cpu_s"] = {k: round(v - th0.get(k, 0.0), 3) for k, v in sorted(th1.items())
                          if v - th0.get(k, 0.0) > 0.005}
    R["load"] = os.getloadavg()[0]
    R["frames"] = [[round(f.ms), f.drawn, f.quality] for f in LIVE.frames]  # (diagnosis)
    while opencl.warming():
        yield 0.1
    R["warm"] = opencl.warm_state()
    if R["warm"]["ended_at"] is not None:
        R["warm_ended_s"] = R["warm"]["ended_at"] - m0
    R["trace"] = trace.since(m0)  # VOXEL_TRACE=1: where the seconds went
    R["blender"] = bpy.app.version_string
    import gpu
    R["backend"] = gpu.platform.backend_type_get()
    vv.show = False


def children_cpu() -> float:
    import resource
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def threads_cpu() -> dict:
    """{thread name: CPU seconds} of this process's threads (Linux /proc; {} elsewhere):
    where the CPU between Show and the whole view went (the trace sees only ours)."""
    import os
    out: dict = {}
    tick = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    try:
        tasks = os.listdir("/proc/self/task")
    except OSError:
        return out
    for t in tasks:
        try:
            stat = Path(f"/proc/self/task/{t}/stat").read_text()
        except OSError:
            continue
        name = "main" if t == str(os.getpid()) else stat[stat.index("(") + 1:stat.rindex(")")]
        f = stat[stat.rindex(")") + 2:].split()
        out[name] = out.get(name, 0.0) + (int(f[11]) + int(f[12])) / tick
    return out


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    V.drive(V.report(run(args[1], int(args[2])), R, Path(args[0])))
