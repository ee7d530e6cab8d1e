"""Blender side of the far rows of voxel_addon/bench/far.py (there it is only a path):
runs in the real Blender GUI under Xvfb, started as a script (`__main__`).

    blender --factory-startup -P tools/far_bench_job.py -- OUT.json WORLD FAR

WORLD holds the chunks of distance 16 and no far data. Far is set, then Show is
ticked: the seconds until every chunk and until every far tile is drawn (the horizon;
tiles built from the file's chunks and the generator's 2D passes). Then frames at
full and draft quality with far on and off, interleaved (the draw handler's own
times with the GPU finished, LIVE.finish), the fastest of N each.
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
N = 5


def run(out: Path, world: str, far: int):
    import voxel_addon
    from voxel_addon.blender.liveview import LIVE
    if not hasattr(bpy.types.Scene, "voxel_view"):
        voxel_addon.register()
    sc = bpy.context.scene
    sc.voxel.path = world
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.quality = 16, 12.0, "auto"
    sp = V.area().spaces.active
    sp.overlay.show_overlays = False
    sp.clip_end = 5000.0
    V.look(-44.0)
    yield 0.5
    vv.far = far
    import os
    from voxel_addon.core import trace
    t0, m0, c0 = time.perf_counter(), time.monotonic(), time.process_time()
    vv.show = True
    near = None
    seen = 0  # far tiles drawn: when the first came (the horizon begins)
    while True:
        s = LIVE.stats
        if near is None and s["wanted"] > 0 and s["drawn"] >= s["wanted"]:
            near = time.perf_counter() - t0
        if not seen and s["far_drawn"] > 0:
            seen = 1
            R["first_far_s"] = time.perf_counter() - t0
        if "far_s" not in R and s["far_wanted"] > 0 and s["far_drawn"] >= s["far_wanted"]:
            R["far_s"] = time.perf_counter() - t0  # every far tile (the chunks aside)
            R["far_cpu_s"] = time.process_time() - c0
        if near is not None and s["far_wanted"] > 0 and s["far_drawn"] >= s["far_wanted"]:
            break
        if LIVE.error:
            raise RuntimeError(LIVE.error)
        if time.perf_counter() - t0 > 1200:
            raise RuntimeError(f"no horizon after 1200 s: {s}")
        yield 0.1  # (the view asks for its own redraws while loading)
    R["near_s"], R["horizon_s"] = near, time.perf_counter() - t0
    R["horizon_cpu_s"] = time.process_time() - c0  # every thread's (pocl's, llvmpipe's)
    R["load"] = os.getloadavg()[0]
    R["trace"] = trace.since(m0)  # VOXEL_TRACE=1: where the seconds went
    R["tiles"] = LIVE.stats["far_wanted"]
    pane = next(iter(LIVE.panes.values()))
    R["far_triangles"] = pane.r.far.triangles
    R["far_gpu_mb"] = pane.r.far.nbytes / 2 ** 20
    R["blender"] = bpy.app.version_string
    import gpu
    R["backend"] = gpu.platform.backend_type_get()
    if os.environ.get("VOXEL_BENCH_FRAMES", "1") == "0":  # the cold horizon alone
        vv.show = False
        return
    LIVE.finish, LIVE.reuse = True, False  # the pipeline on every redraw, GPU finished
    times = {}
    for q in ("full", "draft"):
        vv.quality = q
        for _ in range(N):
            for f in (0, far):
                if vv.far != f:
                    vv.far = f
                    if f:  # the tiles again (from the file): wait for all of them
                        while LIVE.stats["far_drawn"] < LIVE.stats["far_wanted"] or \
                                not LIVE.stats["far_wanted"]:
                            V.area().tag_redraw()
                            yield 0.05
                fr = yield from V.frames(3)
                times.setdefault(f"{q}_{f}", []).append(min(x.ms for x in fr if x.quality == q
                                                            and not x.reused))
    LIVE.finish, LIVE.reuse = False, True
    for k, v in times.items():
        R[f"{k}_ms"] = min(v)
    R["region"] = [r.width for r in V.area().regions if r.type == "WINDOW"] + \
        [r.height for r in V.area().regions if r.type == "WINDOW"]
    R["blender"] = bpy.app.version_string
    import gpu
    R["backend"] = gpu.platform.backend_type_get()
    vv.show = False


def main(out, world, far):
    yield from V.report(run(out, world, far), R, out)


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    V.drive(main(Path(args[0]), args[1], int(args[2])))
