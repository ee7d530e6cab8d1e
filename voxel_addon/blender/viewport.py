"""The world live in Blender's 3D viewports (issue 12; thesis §5.3.4–5.5).

A SpaceView3D POST_VIEW draw handler: Blender has drawn its scene and bound the
overlay framebuffer that holds the viewport's depth. Per redraw and region:

1. the CPU side (`_Feed`, one per world, shared by every window) takes the chunks
   that became ready within a small time budget;
2. the GPU side of the current GL context (viewgpu.Gpu: a moderngl context attached to
   Blender's, a Renderer, the composite program; VAOs and framebuffers are not shared
   between contexts, so a second window gets its own) uploads what changed and renders
   the pipeline with the region's own view and window matrices into its targets;
3. a full-screen pass (shaders/viewport.frag) writes the frame's colour and its depth
   converted to Blender's projection into Blender's framebuffer with the depth test
   LEQUAL: Blender's objects in front hide voxels, voxels in front hide objects; the
   sky only where Blender drew nothing (far plane);
4. `OVERLAYS` callbacks run with Blender's state back and the voxels' depth in the
   depth buffer (the edit tool's hover outline draws there with the gpu module).

Blender redraws a region for many reasons while its view rests (hover, gizmos, the
UI, other areas). Once it rests, the composite goes into the region's kept targets
(viewgpu.Kept: colour, depth already in Blender's projection) and from there into Blender's
framebuffer; a redraw where nothing that shapes the picture changed (`look`: view,
window, size, settings, time of day, uploaded chunks, Blender's depth setup) draws
only the kept frame (shaders/viewport_kept.frag): Blender's objects still mix by
depth on every redraw. (It needs neither the frame's uniform block nor the G-buffer,
which glstate.reset() unbinds and another region's frame overwrites.)

Everything GL runs inside glstate.kept(): Blender caches its bindings, the pipeline
wants a fresh context's state. While chunks stream in, or after a draft frame, a timer
asks for another redraw. shutdown() removes handlers, timer, GL objects and threads.
"""
from __future__ import annotations

import time
import traceback
from collections import deque
from dataclasses import astuple

import numpy as np

from ..core.errors import VoxelError
from .viewgpu import Gpu

# What the panel shows (the last frame of any region).
STATUS = {"drawn": 0, "wanted": 0, "wanted_shown": 0, "ms": 0.0, "python_ms": 0.0, "quality": "full",
          "error": None, "frames": 0, "reused": 0}
# The last frames: (ms, python_ms, quality, drawn, upload_ms, reused), for the bench.
FRAMES: deque = deque(maxlen=512)
# Callables f(context) run after each voxel frame with Blender's GL state and the
# voxels' depth in the depth buffer (draw with gpu.state.depth_test_set("LESS_EQUAL")).
OVERLAYS: list = []

DRAFT_SCALE = 0.5    # draft frames render at this fraction of the region's size
STILL_S = 0.25       # the view is still this long after its last change: full quality
BUDGET_S = 0.004     # CPU time per redraw for taking in streamed chunks
REUSE = True         # a still region redraws from its kept frame (off: the pipeline every time)

_handle = None
_timer_on = False
_gpus: dict = {}      # native GL context -> viewgpu.Gpu
_windows = frozenset()  # the windows open at the last frame (pointers)
_regions: dict = {}   # region pointer -> _Region
_lead = None          # the region whose view the stream follows
_feed = None          # _Feed of the shown world


# ---------------------------------------------------------------------- settings
VIEW_SHADOW_SIZE = 1024  # the viewport's shadow map (renders: Settings.shadow_size)


def settings_of(vv, draft: bool = False, render: bool = False):
    """render.Settings from scene.voxel_view; draft drops the expensive passes. A
    render (Render Voxel View, Render Animation) keeps the CLI's MSAA and shadow map:
    the viewport's cheaper ones are for redraws."""
    from ..render.settings import EFFECTS, Settings
    s = Settings(distance=vv.distance, light_radius=min(8, vv.distance))
    for e in EFFECTS:
        setattr(s, e, bool(getattr(vv, e)))
    if render:
        return _common(s, vv)
    s.msaa = 2 if vv.msaa else 1
    # the map covers ~100 blocks up to the shadow fade: at 1024 a texel is still a tenth
    # of a block (frames equal to 2048's within 16 levels, mean 0.00) at half the pass
    # cost (clear + raster of 4M texels: 78 -> 34 ms at distance 16 on llvmpipe)
    s.shadow_size = VIEW_SHADOW_SIZE
    _common(s, vv)
    if draft:
        s.shadows = s.ssao = s.dof = s.godrays = False
        s.msaa, s.per_sample = 1, False
        s.peel_layers = min(s.peel_layers, 1)
    return s


def _common(s, vv):
    s.transparency = vv.transparency
    s.debug = vv.debug_view or "none"
    s.exposure, s.haze, s.cloud_cover = vv.exposure, vv.haze, vv.cloud_cover
    s.sea_level = _sea_level(vv.id_data)
    return s


def _sea_level(scene) -> int:
    """The open world's water level (render.source.sea_level), -1 without one."""
    from . import session
    from ..core.errors import VoxelError
    from ..render import source
    try:
        return source.sea_level(session.world(scene.voxel.path).generator)
    except (VoxelError, AttributeError, OSError):
        return -1


def problem(context) -> str | None:
    """Why the view cannot run here, as one sentence, or None."""
    import os
    import bpy
    import gpu
    try:
        b = gpu.platform.backend_type_get()
    except SystemError:
        return "the viewport needs Blender's window (no GPU in background mode)"
    if b != "OPENGL":
        return f"the voxel view needs the OpenGL backend, not {b} (Preferences > System)"
    path = context.scene.voxel.path
    if not path or not os.path.exists(bpy.path.abspath(path)):
        return "no world open: create or open one in the World panel"
    if STATUS["error"]:
        return STATUS["error"]
    return None


# ---------------------------------------------------------------------- camera
def view_camera(view, window, far: float):
    """render.Camera for Blender's region matrices with the window's x/y rows but
    our own near/far: Blender's clip range (0.01..1000 by default) would spoil the
    G-buffer's depth precision; the composite converts depth to Blender's projection."""
    from ..render import Camera
    P = np.array(window, np.float64)
    if abs(P[3, 3] - 1.0) < 1e-6:  # orthographic: the eye's plane is arbitrary, look both ways
        n, f = -far, far
        P[2, :] = (0.0, 0.0, -2 / (f - n), -(f + n) / (f - n))
    else:
        n = max(float(P[2, 3] / (P[2, 2] - 1.0)), 0.05)
        P[2, 2], P[2, 3] = (far + n) / (n - far), 2 * far * n / (n - far)
    return Camera.from_matrices(np.array(view, np.float64), P)


# ---------------------------------------------------------------------- CPU side
class _Feed:
    """The chunks of one world to show, shared by every GL context: payloads from a
    world.Stream (nearest first, made in its background thread)."""

    def __init__(self, path, world, distance):
        from ..world import Stream
        self.path, self.world, self.distance = path, world, distance
        self.chunks: dict = {}   # key -> Payload (.key, .mesh, .light, .version)
        self.stream = Stream(world, distance)

    def update(self, at, direction, budget):
        """Take in what is ready (at: (x, y) of the view point, or None to keep it);
        returns whether more is on its way."""
        if at is not None:
            self.stream.set_view(at[0], at[1], direction)
        ready, gone = self.stream.drain(budget)
        for p in ready:
            self.chunks[p.key] = _packed(p)
        for k in gone:
            self.chunks.pop(k, None)
        if self.stream.error is not None:
            raise self.stream.error
        wanted = self.stream.counts[0]
        STATUS["wanted"] = wanted
        return len(self.chunks) < wanted

    def close(self):
        self.stream.close()
        self.chunks.clear()


def _packed(p):
    """The payload with its light as its non-uniform layers (core.chunk.pack_layers,
    ~0.1 ms): the feed and the renderers keep it for every shown chunk, while the
    world keeps its own copy packed too; full arrays were ~130 MB at distance 16."""
    from ..core.chunk import pack_layers
    if p.light is None or isinstance(p.light, tuple):
        return p
    return p._replace(light=pack_layers(p.light))


def _feed_for(scene):
    global _feed
    from . import session
    vv = scene.voxel_view
    world = session.world(scene.voxel.path)
    if _feed is None or _feed.world is not world or _feed.distance != vv.distance:
        if _feed is not None:
            _feed.close()
        _feed = _Feed(scene.voxel.path, world, vv.distance)
        STATUS.update(drawn=0, wanted=0)
    return _feed


class _Region:
    __slots__ = ("view", "changed", "quality")

    def __init__(self):
        self.view, self.changed, self.quality = None, 0.0, "full"


# ---------------------------------------------------------------------- handler
def _draw():
    import bpy
    context = bpy.context
    scene = context.scene
    vv = getattr(scene, "voxel_view", None)
    if vv is None or not vv.show:
        return
    if problem(context) and not STATUS["error"]:
        return
    try:
        _frame(context, scene, vv)
        STATUS["error"] = None
    except VoxelError as e:
        STATUS["error"] = str(e)
    except Exception as e:  # keep drawing Blender; say it once in the panel and console
        if STATUS["error"] is None:
            traceback.print_exc()
        STATUS["error"] = f"voxel view failed: {e}"
    for fn in list(OVERLAYS):
        fn(context)


def _frame(context, scene, vv):
    from ..render import glstate
    from .offscreen import _native
    t0 = time.perf_counter()
    region, rv3d = context.region, context.region_data
    if region is None or rv3d is None:
        return
    wins = frozenset(w.as_pointer() for w in context.window_manager.windows)
    if wins != _windows:
        _prune(context, wins)
    view = [tuple(r) for r in rv3d.view_matrix]
    st = _regions.setdefault(region.as_pointer(), _Region())
    now = time.perf_counter()
    global _lead
    key = region.as_pointer()
    if view != st.view:
        if st.view is not None or _lead not in _regions:
            _lead = key  # the region being navigated leads the stream
        st.view, st.changed = view, now
    moving = now - st.changed < STILL_S
    cam = view_camera(rv3d.view_matrix, rv3d.window_matrix, vv.distance * 16 * 1.5 + 256.0)
    feed = _feed_for(scene)
    # the stream follows one region (quad view: the one last navigated): the eye of a
    # perspective view, the pivot of an orthographic one (its eye is arbitrary)
    at = None
    if key == _lead:
        at = tuple(rv3d.view_location)[:2] if cam.ortho else (cam.x, cam.y)
    loading = feed.update(at, cam.forward, BUDGET_S)
    # draft while moving and while chunks stream in: a full frame holds the GIL for
    # seconds on software GL and starves the stream's worker thread
    draft = vv.quality == "draft" or (vv.quality == "auto" and (moving or loading))
    s = settings_of(vv, draft)
    if cam.ortho:
        # distance fog needs an eye; an orthographic view's is arbitrary (it moves with
        # the zoom), and a side view would show the far half of the area washed out
        s.fog = False
    else:
        s.fov = min(150.0, max(10.0, cam.fov))
    native = _native()
    host_vp = np.array(rv3d.perspective_matrix, np.float64)
    hours = hours_of(scene)
    t_py = time.perf_counter() - t0
    reused = False
    with glstate.kept() as host:
        g = _gpus.get(native)
        if g is None:
            g = _gpus[native] = Gpu(native)
        if context.window is not None:
            g.windows.add(context.window.as_pointer())
        t1 = time.perf_counter()
        drawn = g.sync(feed)
        t_sync = time.perf_counter() - t1
        vw, vh = host["viewport"][2], host["viewport"][3]
        # everything the picture depends on (Blender's objects are mixed in by depth
        # on every redraw): the same again, and the kept frame is the frame
        look = (tuple(view), tuple(map(tuple, rv3d.window_matrix)), (vw, vh), astuple(s), hours,
                vv.sky, tuple(host["depth_range"]), host["clip"], g.gen)
        k = g.kept.get(key)
        if REUSE and k is not None and k.look == look:
            g.draw_kept(k, host)
            reused, draft = True, k.quality == "draft"
        else:
            g.r.s = s
            scale = DRAFT_SCALE if draft else 1.0
            size = (max(8, int(vw * scale)), max(8, int(vh * scale)))
            t1 = time.perf_counter()
            f = g.r.prepare(cam, hours, size)
            t_py += time.perf_counter() - t1
            g.r.submit(f)
            # kept only once the view rests: a frame while moving or loading is the last
            k = g.kept_for(key, (vw, vh)) if REUSE and not (moving or loading) else None
            g.composite(f, host, host_vp, vv.sky, k)
            if k is not None:
                k.look, k.quality = look, "draft" if draft else "full"
        g.ctx.finish() if _SYNC else None
    ms = (time.perf_counter() - t0) * 1e3
    q = "draft" if draft else "full"
    if (drawn, STATUS["wanted"], q) != (STATUS["drawn"], STATUS["wanted_shown"], STATUS["quality"]):
        _panel_redraw()  # the sidebar shows progress and quality
    STATUS.update(drawn=drawn, ms=ms, python_ms=t_py * 1e3, quality=q,
                  frames=STATUS["frames"] + 1, wanted_shown=STATUS["wanted"],
                  reused=STATUS["reused"] + reused)
    FRAMES.append((ms, t_py * 1e3, q, drawn, t_sync * 1e3, reused))
    st.quality = q
    if loading or drawn < STATUS["wanted"]:
        # as long again as the frame took: the worker gets at least half the time
        _want_redraw(max(0.05, ms / 1e3))
    elif draft and vv.quality == "auto":  # once the view is still: a full frame
        _want_redraw(max(0.02, STILL_S - (time.perf_counter() - st.changed)))


_SYNC = False  # bench: wait for the GPU so frame times are real


def _prune(context, wins):
    """A window opened or closed: forget the regions that went, and the GPU set of a
    GL context no open window drew with (one context per window on some platforms:
    it went with its window; a handle the driver hands out again must not find it)."""
    from .offscreen import _native
    global _windows
    _windows = wins
    live = {r.as_pointer() for w in context.window_manager.windows
            for a in w.screen.areas for r in a.regions}
    for k in [k for k in _regions if k not in live]:
        del _regions[k]
    native = _native()
    for key, g in list(_gpus.items()):
        g.windows &= wins
        if not g.windows:
            _drop_gpu(key, native)


def _drop_gpu(key, native):
    """Container objects (VAOs, framebuffers) are per context: free everything only
    on its own; another window's context gets its shared objects freed."""
    from ..render import glstate
    g = _gpus.pop(key)
    if key == native:
        with glstate.kept():
            g.release()
    else:
        g.orphan()


def _want_redraw(after: float):
    global _timer_on
    import bpy
    if not _timer_on:
        _timer_on = True
        bpy.app.timers.register(_tick, first_interval=after)


def _panel_redraw():
    import bpy
    if not bpy.app.timers.is_registered(_tick_ui):
        bpy.app.timers.register(_tick_ui, first_interval=0.01)


def _tick_ui():
    """Redraw the sidebars (not from inside a draw handler: that would loop)."""
    import bpy
    wm = bpy.context.window_manager
    for win in (wm.windows if wm else ()):
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                for r in area.regions:
                    if r.type == "UI":
                        r.tag_redraw()
    return None


def _tick():
    """Redraw while chunks stream in or a region still shows a draft frame."""
    global _timer_on
    _timer_on = False
    _tag_redraw()
    return None


def _tag_redraw():
    import bpy
    wm = bpy.context.window_manager
    for win in (wm.windows if wm else ()):
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()


# ---------------------------------------------------------------------- life cycle
def sync(context=None) -> None:
    """Install the draw handler when a scene shows the view; redraw viewports."""
    global _handle
    import bpy
    show = any(getattr(getattr(s, "voxel_view", None), "show", False) for s in bpy.data.scenes)
    if show and _handle is None:
        _handle = bpy.types.SpaceView3D.draw_handler_add(_draw, (), "WINDOW", "POST_VIEW")
        if _load_pre not in bpy.app.handlers.load_pre:
            bpy.app.handlers.load_pre.append(bpy.app.handlers.persistent(_load_pre))
    STATUS["error"] = None
    _tag_redraw()


def _load_pre(*_):
    """File › New / Open: drop the world's chunks and this file's state; the handler
    comes back when the new file shows the view (load_post)."""
    import bpy
    _close_data()
    if _load_post not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(bpy.app.handlers.persistent(_load_post))


def _load_post(*_):
    import bpy
    if _load_post in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(_load_post)
    sync()


def _close_data():
    global _feed, _handle, _windows
    import bpy
    from .offscreen import _native
    if _handle is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    if _feed is not None:
        _feed.close()
        _feed = None
    _regions.clear()
    _windows = frozenset()
    native = _native()
    for key in list(_gpus):
        _drop_gpu(key, native)
    STATUS.update(drawn=0, wanted=0, error=None)


def shutdown() -> None:
    """Unregister: every handler, timer, thread (the stream's) and GL object goes."""
    global _timer_on
    import bpy
    _close_data()
    for hs, fn in ((bpy.app.handlers.load_pre, _load_pre), (bpy.app.handlers.load_post, _load_post)):
        while fn in hs:
            hs.remove(fn)
    for fn in (_tick, _tick_ui):
        if bpy.app.timers.is_registered(fn):
            bpy.app.timers.unregister(fn)
    _timer_on = False
    OVERLAYS.clear()


def hours_of(scene) -> float:
    """The view's time of day: the property, or when following the timeline the
    property at the scene's first frame plus a day per frames_per_day frames."""
    v = scene.voxel_view
    if v.follow_timeline:
        days = (scene.frame_current - scene.frame_start) / v.frames_per_day
        return (v.hours + 24.0 * days) % 24.0
    return v.hours
