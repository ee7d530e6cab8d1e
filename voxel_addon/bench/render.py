"""Render bench (thesis tables 6.10–6.14 analogue) on the GL it gets (here Mesa llvmpipe):
per reference scene and effect the frame time at 640×360, triangles and draw calls per
frame, and the Python side's cost per frame; plus the CPU cost at view distance 32.

Frame ms: ctx.finish(), then draw() and ctx.finish() again (no readback); the minimum
of n (3) frames after a warm-up frame. Python ms: the wall time of draw() minus the time
spent inside moderngl calls (GLClock wraps every moderngl method and property setter
the pipeline can reach; what happens inside them, including llvmpipe's vertex work in
the calling thread and any driver wait, is GL time). So it is the time of our Python
and NumPy code (culling, command gathering, uniform values, program lookup) plus the
Python-level call overhead of reaching moderngl, measured in the same frames. The
wrapper's own cost outside its clock (calibrated on a no-op per run, times the calls
of the frame) is subtracted; its size is a row of its own.
`cull` is the frustum culling of the whole region table for one matrix.
Transparency: `default` peels 3 layers, `peel0` draws no transparent surface, `oit`
draws them with weighted blended OIT (one forward pass + resolve, render/oit.py); the
quick run keeps default, no_effects and oit.
"""
from __future__ import annotations

import time
from contextlib import contextmanager

VARIANTS = [("default", None), ("no_effects", "none"), ("no_shadows", "-shadows"),
            ("ssao", "+ssao"), ("peel0", "peel0"), ("oit", "oit"), ("msaa1", "msaa1"), ("msaa4", "msaa4"),
            ("no_godrays", "-godrays"), ("no_dof", "-dof"), ("no_fog", "-fog"),
            ("no_waving", "-waving"), ("no_tonemap", "-tonemap"), ("no_clouds", "-clouds"),
            ("no_cloud_shadows", "-cloud_shadows"), ("no_water", "-water"), ("no_ssr", "-ssr"),
            ("no_sea", "-sea"), ("no_fade", "-fade"), ("no_stars", "-stars"),
            ("no_walls", "-walls")]

QUICK = ("default", "no_effects", "oit")


class GLClock:
    """Accumulates wall and calling-thread CPU time spent inside moderngl's API."""

    def __init__(self):
        self.t = self.cpu = 0.0
        self.calls = 0
        self._depth = 0

    @staticmethod
    def overhead(n: int = 20000) -> tuple[float, float]:
        """(CPU s, wall s) per wrapped call that the wrapper adds outside its own
        clock: a wrapped no-op against the bare no-op."""
        def noop():
            return None
        clock = GLClock()
        f = clock.wrap(noop)
        c0, t0 = time.thread_time(), time.perf_counter()
        for _ in range(n):
            f()
        cw, tw = time.thread_time() - c0 - clock.cpu, time.perf_counter() - t0 - clock.t
        c0, t0 = time.thread_time(), time.perf_counter()
        for _ in range(n):
            noop()
        cb, tb = time.thread_time() - c0, time.perf_counter() - t0
        return max(0.0, (cw - cb) / n), max(0.0, (tw - tb) / n)

    def wrap(self, f):
        def w(*a, **k):
            if self._depth:
                return f(*a, **k)
            self._depth = 1
            self.calls += 1
            t0, c0 = time.perf_counter(), time.thread_time()
            try:
                return f(*a, **k)
            finally:
                self.cpu += time.thread_time() - c0
                self.t += time.perf_counter() - t0
                self._depth = 0
        return w

    @contextmanager
    def installed(self):
        import moderngl
        import _moderngl
        pure = {"__getitem__", "__iter__", "get", "mglo"}  # dictionary lookups, no GL
        saved = []
        for cls in (moderngl.Context, moderngl.Buffer, moderngl.Framebuffer, moderngl.Texture,
                    moderngl.TextureArray, moderngl.Texture3D, moderngl.VertexArray,
                    moderngl.Program, moderngl.Query, _moderngl.Uniform):
            for k, v in list(vars(cls).items()):
                if k in pure or (k.startswith("__") and k != "__setitem__"):
                    continue
                if isinstance(v, property):
                    if v.fset is None:
                        continue
                    new = property(v.fget, self.wrap(v.fset), v.fdel)
                elif callable(v):
                    new = self.wrap(v)
                else:
                    continue
                saved.append((cls, k, v))
                setattr(cls, k, new)
        try:
            yield self
        finally:
            for cls, k, v in saved:
                setattr(cls, k, v)


_OVERHEAD = None  # GLClock.overhead(), once per process


def _frame(gl, r, cam, hours, size):
    """(frame ms, Python CPU ms, Python wall ms, wrapped GL calls) of one frame."""
    global _OVERHEAD
    if _OVERHEAD is None:
        _OVERHEAD = GLClock.overhead()
    gl.finish()
    clock = GLClock()
    with clock.installed():
        t0, c0 = time.perf_counter(), time.thread_time()
        r.draw(cam, hours, size)
        cpu, sub = time.thread_time() - c0, time.perf_counter() - t0
    gl.finish()
    oc, ot = _OVERHEAD
    return ((time.perf_counter() - t0) * 1e3, (cpu - clock.cpu - clock.calls * oc) * 1e3,
            (sub - clock.t - clock.calls * ot) * 1e3, clock.calls)


def _measure(gl, r, cam, hours, size, n):
    _frame(gl, r, cam, hours, size)  # compile + warm up
    runs = [_frame(gl, r, cam, hours, size) for _ in range(n)]
    return [min(x[i] for x in runs) for i in range(4)]


def run(ctx):
    from ..meshing import scenes
    from ..light import daytime
    from ..render import Camera, Settings, source
    from ..render.device import mgl
    from ..render.pipeline import Renderer
    gl = mgl.context()
    size = (320, 180) if ctx.quick else (640, 360)
    variants = [v for v in VARIANTS if v[0] in QUICK] if ctx.quick else VARIANTS
    n = 1 if ctx.quick else 3
    table = {}
    for name in scenes.SCENES:
        sc = scenes.SCENES[name]
        a = source.scene_area(name)
        sea = source.scene_sea_level(name)  # as the CLI renders it
        r = Renderer(gl, Settings(sea_level=sea))
        r.set_area(a.blocks, a.light, a.cx0, a.cy0, ring=True, light_at=a.light_at)
        if not source.open_sea(r):  # as the CLI: a dry edge fades into the haze
            sea = -1
        hours = daytime.parse_time(sc.time)
        for vname, eff in variants:
            r.s = Settings(sea_level=sea).with_effects(eff)
            ms, py, py_wall, _ = _measure(gl, r, Camera(*sc.camera), hours, size, n)
            table[name, vname] = ms
            st = r.stats.snapshot()
            note = f"{size[0]}x{size[1]}, {st['triangles']} tris, {st['draw_calls']} draws"
            yield (f"render_{name}_{vname}_ms", ms, "ms", note)
            if vname == "default":
                yield (f"render_{name}_triangles", st["triangles"], "",
                       f"per frame incl. {st.get('shadow_triangles', 0)} in the shadow map")
                yield (f"render_{name}_draw_calls", st["draw_calls"], "", "per frame, all passes")
                yield (f"render_{name}_python_ms", py, "ms",
                       "calling-thread CPU time in draw() outside moderngl calls (GLClock)")
                yield (f"render_{name}_python_wall_ms", py_wall, "ms",
                       "the same as wall time (includes being preempted by llvmpipe's threads)")
        if name == "landscape" and not ctx.quick:
            # the 5-10 s frames before: llvmpipe's unbounded EWA anisotropic filter
            r.s, r.max_anisotropy = Settings(), 4.0
            ms = _measure(gl, r, Camera(*sc.camera), hours, size, 1)[0]
            yield ("render_landscape_llvmpipe_aniso4_ms", ms, "ms",
                   "anisotropy 4 forced on llvmpipe (default caps it to 1 there)")
        r.release()
    yield from _distance16(ctx, gl)
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


def _tiled(a, d):
    """{(cx, cy): mesh} over the (2d+1)² chunks around chunk (0, 0): the 4 × 4 chunk
    meshes of a scene area repeated (the geometry a real world would have per chunk)."""
    from ..meshing import build_chunk
    tiles = [[build_chunk(a.blocks[16 * i:16 * i + 18, 16 * j:16 * j + 18], backend=None)
              for j in range(4)] for i in range(4)]
    return {(cx, cy): tiles[cx % 4][cy % 4] for cx in range(-d, d + 1) for cy in range(-d, d + 1)}


def _distance16(ctx, gl):
    """The full frame (every default effect, 640x360) at view distance 16 over the
    landscape's chunks tiled (33 × 33 chunks), at noon, dusk and night (stars): the
    budget row of the look (issue 20: sky, clouds, water, the edge of the world stay
    within 1.25x); the sea level is the generator's, as the CLI renders a world."""
    from ..light import daytime
    from ..render import Camera, Settings, source
    from ..render.pipeline import Renderer
    d = 4 if ctx.quick else 16
    size = (320, 180) if ctx.quick else (640, 360)
    a = source.scene_area("landscape")
    r = Renderer(gl, Settings(distance=d, sea_level=source.scene_sea_level("landscape")))
    r.set_meshes(_tiled(a, d))
    r.set_light(a.light, a.cx0, a.cy0)
    cam = Camera(8, 8, 100, 30, -12)
    for when in ("12:00", "18:30", "23:30"):
        ms = _measure(gl, r, cam, daytime.parse_time(when), size, 1 if ctx.quick else 3)[0]
        st = r.stats.snapshot()
        yield (f"render_d{d}_full_frame_{when.replace(':', '')}_ms", ms, "ms",
               f"{size[0]}x{size[1]}, default effects, {st['triangles']} tris, "
               f"{st['draw_calls']} draws, at {when} (llvmpipe)")
    r.release()


def _distance32(ctx, gl):
    """View distance 32 (65 × 65 chunks): the landscape scene's chunk meshes tiled over
    the whole area (the same geometry a real world would have per chunk), light window
    bounded; measured on a small viewport so llvmpipe's raster time stays short."""
    from ..meshing import build_chunk
    from ..light import daytime
    from ..render import Camera, Settings, source
    from ..render.pipeline import Renderer
    d = 8 if ctx.quick else 32
    a = source.scene_area("landscape")
    tiles = [[build_chunk(a.blocks[16 * i:16 * i + 18, 16 * j:16 * j + 18], backend=None)
              for j in range(4)] for i in range(4)]
    meshes = _tiled(a, d)
    s = Settings(distance=d, msaa=1, waving=False)  # CPU side is measured; keep llvmpipe short
    r = Renderer(gl, s)
    t0 = time.perf_counter()
    r.set_meshes(meshes)
    gl.finish()
    upload_all = (time.perf_counter() - t0) * 1e3
    r.set_light(a.light, a.cx0, a.cy0)  # outside the window: open daylight
    cam = Camera(8, 8, 100, 30, -15)
    hours = daytime.parse_time("10:00")
    ms, py_static, _, calls = _measure(gl, r, cam, hours, (160, 90), 1 if ctx.quick else 2)
    st = r.stats.snapshot()
    # a moving camera changes the visible set every frame (command gathering + upload)
    pys, walls = [], []
    for i in range(3 if ctx.quick else 15):
        cam.yaw, cam.x = 30 + 7 * i, 8 + 3 * i
        f = _frame(gl, r, cam, hours, (160, 90))
        pys.append(f[1])
        walls.append(f[2])
    # the same draw() when the GL has next to nothing to do (camera at the sky): the
    # Python work without the cache pollution of llvmpipe's in-thread vertex work
    up = Camera(8, 8, 250, 30, 80)
    _frame(gl, r, up, hours, (160, 90))
    idle = sorted(_frame(gl, r, up, hours, (160, 90))[1] for _ in range(5))[2]
    # prepare() (all of a frame's Python: values, culling, batching, uploads) run back
    # to back for two alternating cameras: the work itself, without the cost of waking
    # up after each GL wait (on this VM the first NumPy call after any sleep, e.g. in
    # glFinish or a pass that waits for the previous one, takes ~60 us instead of ~2)
    hot, cams = [], [Camera(8, 8, 100, 30, -15), Camera(11, 8, 100, 37, -15)]
    for i in range(40):
        clock = GLClock()
        with clock.installed():
            c0 = time.thread_time()
            r.prepare(cams[i % 2], hours, (160, 90))
            c = time.thread_time() - c0
        hot.append(c - clock.cpu - clock.calls * _OVERHEAD[0])
    gl.finish()
    hot_ms = sorted(hot[10:])[len(hot[10:]) // 2] * 1e3
    t0 = time.perf_counter()
    reps = 20
    for _ in range(reps):
        r.geo.cull(cam.view_proj())
    cull = (time.perf_counter() - t0) / reps * 1e3
    regions = int(r.geo.cull(cam.view_proj()).size)  # (batch, region) boxes
    # one chunk replaced (an edit, a streamed chunk arriving) while all the others stay
    from typing import NamedTuple

    class Chunk(NamedTuple):
        key: tuple
        mesh: object
        light: object
    ones = []
    for i in range(21):
        k = (i % 5 - 2, i // 5 - 2)
        t0 = time.perf_counter()
        r.update_chunks([Chunk(k, tiles[(i + 1) % 4][i % 4], None)])
        gl.finish()
        ones.append((time.perf_counter() - t0) * 1e3)
    t0 = time.perf_counter()
    r.remove_chunks([(cx, cy) for cx in range(-d, d + 1) for cy in (-d, d)])
    gl.finish()
    remove_row = (time.perf_counter() - t0) * 1e3
    note = f"distance {d}: {len(meshes)} chunks, {regions} batch regions before culling"
    yield (f"render_d{d}_python_ms", sorted(pys)[len(pys) // 2], "ms",
           f"CPU outside moderngl, median of {len(pys)} frames, camera moving; {note}")
    yield (f"render_d{d}_python_wall_ms", sorted(walls)[len(walls) // 2], "ms",
           "the same as wall time (includes preemption by llvmpipe's threads)")
    yield (f"render_d{d}_python_static_ms", py_static, "ms", "camera still (no command upload)")
    yield (f"render_d{d}_python_idle_gl_ms", idle, "ms",
           "the same, camera at the sky (GL does ~nothing; median of 5)")
    yield (f"render_d{d}_cull_ms", cull, "ms", "NumPy frustum culling of the (batch, region) "
           "boxes, one matrix")
    yield (f"render_d{d}_prepare_hot_ms", hot_ms, "ms",
           "Renderer.prepare (values, culling, draw lists; camera moving) back to back, outside "
           "moderngl calls: the Python work without the wake-up cost after GL waits")
    yield ("render_glclock_overhead_ms", calls * _OVERHEAD[0] * 1e3, "ms",
           f"subtracted per frame above: {calls} moderngl calls x {_OVERHEAD[0] * 1e6:.2f} us "
           "of the measuring wrapper's own CPU time")
    yield (f"render_d{d}_frame_ms", ms, "ms", f"160x90, {st['triangles']} tris, "
           f"{st['draw_calls']} draws (llvmpipe)")
    yield (f"render_d{d}_triangles", st["triangles"], "", "per frame")
    yield (f"render_d{d}_upload_all_ms", upload_all, "ms",
           f"Renderer.set_meshes of all {len(meshes)} chunks into the empty renderer")
    yield (f"render_d{d}_update_chunk_ms", sorted(ones)[len(ones) // 2], "ms",
           f"update_chunks of one chunk with {len(meshes)} shown (median of {len(ones)}): "
           "nothing else is uploaded again")
    yield (f"render_d{d}_remove_edge_ms", remove_row, "ms",
           f"remove_chunks of two edge rows ({2 * (2 * d + 1)} chunks)")
    r.release()
