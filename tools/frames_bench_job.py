"""Blender side of voxel_addon/bench/viewport.py's frames() rows (there it is only a
path): the gpu-module frame against the moderngl frame of the same scene, and far
FAR against far 0, in one Blender GUI under Xvfb, interleaved round by round.

    blender --factory-startup -P tools/frames_bench_job.py -- OUT.json WORLD DISTANCE FAR ROUNDS

WORLD holds the chunks of DISTANCE. Show is ticked with far FAR, the vista of the far
bench; once every chunk and far tile is drawn, a moderngl Renderer (render/device/mgl.py)
on its own standalone EGL context in a thread of this process (GL contexts are per
thread: Blender's stays current on the main thread) takes the same payloads, far
tiles, palette, settings, camera and size. Each round, in a rotated order, with far 0
and with far FAR: the live view's frame ("gpu": the pipeline every redraw, the
composite into Blender's region, GPU finished: LIVE.finish, which also finishes
Blender's own drawing of the region queued before the handler runs, outside the
frame's timing, and times the composite on its own), the live view's Renderer
drawn alone ("gpr": Renderer.draw in the draw handler, GPU finished: the same work as
the moderngl side) and the moderngl frame ("mgl": Renderer.draw, GPU finished); wall
time and the process's CPU time (all threads, llvmpipe's included: it moves less with
the machine's load). Far off means the frame's Settings.far = 0 with the
tiles kept (as bench/far.py's frames do): the near stream and the far builder are idle.
Both drivers are the same llvmpipe (Blender's library path), in one process.
"""
from __future__ import annotations

import statistics
import sys
import threading
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tools"))
import viewport_bench_job as V  # noqa: E402  (its start() runs only as __main__)
R: dict = {}


class Mgl:
    """A moderngl Renderer in its own thread (its EGL context current there only)."""

    def __init__(self):
        self.job, self.done, self.result = None, threading.Event(), None
        self.wake = threading.Event()
        self.t = threading.Thread(target=self._loop, daemon=True, name="bench-mgl")
        self.t.start()

    def _loop(self):
        while True:
            self.wake.wait()
            self.wake.clear()
            fn = self.job
            if fn is None:
                return
            try:
                self.result = fn()
            except Exception as e:  # noqa: BLE001 - handed to the job's thread
                self.result = e
            self.done.set()

    def call(self, fn):
        """Generator: fn() on the thread; returns its result (yields while waiting)."""
        self.done.clear()
        self.job = fn
        self.wake.set()
        while not self.done.wait(0.002):
            yield 0.005
        if isinstance(self.result, Exception):
            raise self.result
        return self.result

    def stop(self):
        self.job = None
        self.wake.set()


def mgl_setup(feed, palette):
    from voxel_addon.render.device.mgl import MglDevice, context
    from voxel_addon.render.pipeline import Renderer
    from voxel_addon.render.settings import Settings
    ctx = context()
    r = Renderer(MglDevice(ctx), Settings())
    if palette is not None:
        r.set_palette(palette)
    r.update_chunks(list(feed.chunks.values()))
    r.update_far(list(feed.tiles.values()))
    return r, ctx.info.get("GL_RENDERER", "")


def timed_frame(r, s, cam, hours, size):
    """(wall ms, process CPU ms, draw calls) of r.draw with the GPU finished."""
    r.s = s
    r.dev.finish()
    t, c = time.perf_counter(), time.process_time()
    r.draw(cam, hours, size)
    r.dev.finish()
    return ((time.perf_counter() - t) * 1e3, (time.process_time() - c) * 1e3,
            r.stats.get("draw_calls", 0))


class Gpr:
    """The live view's own Renderer (gpu module) drawn alone, as the moderngl side is:
    an overlay of the next redraw (inside Blender's draw handler, its state kept)."""

    def __init__(self):
        self.job, self.result = None, None

    def __call__(self, context):
        if self.job is None:
            return
        from voxel_addon.blender.liveview import LIVE, host
        pane = next(iter(LIVE.panes.values()))
        with host.kept():
            self.result = timed_frame(pane.r, *self.job)
        self.job = None

    def call(self, *job):
        self.job, self.result = job, None
        while self.result is None:
            V.area().tag_redraw()
            yield 0.01
        return self.result


def run(world: str, distance: int, far: int, rounds: int):
    import gpu
    import voxel_addon
    from voxel_addon.blender import session
    from voxel_addon.blender.liveview import LIVE, options
    from voxel_addon.blender.liveview import view as lv
    if not hasattr(bpy.types.Scene, "voxel_view"):
        voxel_addon.register()
    R.update(blender=bpy.app.version_string, backend=gpu.platform.backend_type_get(),
             renderer=gpu.platform.renderer_get())
    sc = bpy.context.scene
    sc.voxel.path = world
    vv = sc.voxel_view
    vv.distance, vv.hours, vv.quality, vv.far = distance, 12.0, "auto", far
    sp = V.area().spaces.active
    sp.overlay.show_overlays = False
    sp.clip_end = 5000.0
    V.look(-44.0)
    yield 0.5
    t0 = time.perf_counter()
    vv.show = True
    while True:
        s = LIVE.stats
        if s["wanted"] and s["drawn"] >= s["wanted"] and s["far_wanted"] and \
                s["far_drawn"] >= s["far_wanted"]:
            break
        if LIVE.error:
            raise RuntimeError(LIVE.error)
        if time.perf_counter() - t0 > 1200:
            raise RuntimeError(f"no horizon after 1200 s: {s}")
        yield 0.1
    R["horizon_s"], R["chunks"], R["tiles"] = time.perf_counter() - t0, s["wanted"], s["far_wanted"]
    reg = next(r for r in V.area().regions if r.type == "WINDOW")
    size = (reg.width, reg.height)
    R["region"] = list(size)
    w = session.world(world)
    palette = w.colors() if hasattr(w, "colors") else None
    mgl = Mgl()
    r, R["mgl_renderer"] = yield from mgl.call(lambda: mgl_setup(LIVE.feed, palette))
    # far off for a frame without touching the feed: the settings the view draws with
    want = {"far": far}
    real = lv.settings_of

    def settings_of(v, draft=False, render=False, **kw):
        s = real(v, draft, render, **kw)
        s.far = want["far"]
        return s
    lv.settings_of = settings_of
    LIVE.finish, LIVE.reuse = True, False
    gpr = Gpr()
    LIVE.overlays.append(gpr)
    r3 = V.area().spaces.active.region_3d
    times: dict = {}
    try:
        for q in ("full", "draft"):
            vv.quality = q
            yield from V.frames(2)
            cam = options.view_camera(r3.view_matrix, r3.window_matrix, distance * 16 * 1.5 + 256.0)
            qsize = size if q == "full" else tuple(max(8, int(x * lv.DRAFT_SCALE)) for x in size)
            base = options.settings_of(vv, q == "draft")
            base.fov = min(150.0, max(10.0, cam.fov))

            def mgl_s(f, base=base):
                import copy
                s = copy.copy(base)
                s.far = f
                return s
            for f in (0, far):  # each side's first frames (shader builds, targets)
                yield from mgl.call(lambda f=f: timed_frame(r, mgl_s(f), cam, 12.0, qsize))
                yield from gpr.call(mgl_s(f), cam, 12.0, qsize)
            steps = [(side, f) for side in ("gpu", "gpr", "mgl") for f in (0, far)]
            for i in range(rounds):
                k = i % len(steps)
                for side, f in steps[k:] + steps[:k]:  # rotated: no side always first
                    if side == "gpu":
                        want["far"] = f
                        LIVE.touch()  # (the view reads its settings again)
                        fr = yield from V.frames(1)
                        ms, cpu, calls = fr[-1].ms, fr[-1].cpu_ms, fr[-1].draw_calls
                        if fr[-1].reused or fr[-1].quality != q:
                            raise RuntimeError(f"not a {q} pipeline frame: {fr[-1]}")
                        for k in ("python_ms", "submit_ms", "upload_ms", "host_cpu_ms",
                                  "composite_cpu_ms"):  # where it goes
                            times.setdefault(f"{q}_gpu_{f}_{k}", []).append(getattr(fr[-1], k))
                    elif side == "gpr":
                        ms, cpu, calls = yield from gpr.call(mgl_s(f), cam, 12.0, qsize)
                    else:
                        ms, cpu, calls = yield from mgl.call(
                            lambda f=f: timed_frame(r, mgl_s(f), cam, 12.0, qsize))
                    times.setdefault(f"{q}_{side}_{f}", []).append(ms)
                    times.setdefault(f"{q}_{side}_{f}_cpu", []).append(cpu)
                    R[f"{q}_{side}_{f}_calls"] = calls
            R[f"{q}_size"] = list(qsize)
    finally:
        LIVE.overlays.remove(gpr)
        lv.settings_of = real
        LIVE.finish, LIVE.reuse = False, True
        try:
            yield from mgl.call(r.release)
        finally:
            mgl.stop()
    for k, v in times.items():
        R[k if k.endswith("_ms") else f"{k}_ms"] = v
    def ratio(a, b):  # the median of each round's ratio
        return statistics.median(x / y for x, y in zip(times[a], times[b]))
    for q in ("full", "draft"):
        for c in ("", "_cpu"):
            for side in ("gpu", "gpr"):
                R[f"{q}_{side}_to_mgl{c}"] = ratio(f"{q}_{side}_0{c}", f"{q}_mgl_0{c}")
                R[f"{q}_{side}_to_mgl_far{c}"] = ratio(f"{q}_{side}_{far}{c}", f"{q}_mgl_{far}{c}")
            for side in ("gpu", "gpr", "mgl"):
                R[f"{q}_far_to_0_{side}{c}"] = ratio(f"{q}_{side}_{far}{c}", f"{q}_{side}_0{c}")
    import os
    R["load"] = os.getloadavg()
    vv.show = False


if __name__ == "__main__":
    args = sys.argv[sys.argv.index("--") + 1:]
    V.drive(V.report(run(args[1], int(args[2]), int(args[3]), int(args[4])), R, Path(args[0])))
