"""The world live in Blender's 3D viewports (issue 12; thesis §5.3.4–5.5), drawn with
Blender's own gpu module on any backend (device.py).

`LiveView` (one per Blender: `liveview.LIVE`) owns what the view needs: the draw
handler, the feed of the shown world (feed.py, shared by every window), per window a
`Pane` (a Renderer on the shared device, the chunk versions it uploaded, the kept
frames of its regions), the regions' view state, the redraw timers and the stats the
panel and the bench read. A SpaceView3D POST_VIEW handler runs per redraw and region:

1. the feed takes the chunks that became ready within a small time budget;
2. the window's Pane uploads what changed and runs the pipeline with the region's own
   view and window matrices into its targets;
3. the frame goes into Blender's framebuffer (composite.py), depth tested, so
   Blender's objects in front hide voxels and voxels hide objects behind them;
4. `overlays` run with Blender's state back and the voxels' depth in the depth buffer
   (the edit tool's hover outline).

Blender redraws a region for many reasons while its view rests (hover, gizmos, the
UI, other areas). Once it rests the composite goes into the region's kept targets
and from there into Blender's framebuffer; a redraw where nothing that shapes the
picture changed (`look`: view, window, size, settings, time of day, uploaded chunks)
draws only the kept frame. Draft quality while moving or loading, a timer asks for
redraws while loading and for the full frame once still.

Each window gets its own Pane: framebuffers belong to one GL context, and a platform
may give each window its own (Blender 4.3/5.2 on X11 draw every window with one).
"""
from __future__ import annotations

import time
import traceback
from collections import deque
from typing import NamedTuple

import numpy as np

from ...core import trace
from ...core.errors import VoxelError
from .. import firstview, session
from . import composite, host
from .feed import Feed
from .pane import Pane
from .options import hours_of, settings_of, view_camera

DRAFT_SCALE = 0.4    # draft frames render at this fraction of the region's size
STILL_S = 0.25       # the view is still this long after its last change: full quality
BUDGET_S = 0.004     # CPU time per redraw for taking in streamed chunks
POLL_S = 0.05        # while loading: how often to look for new payloads between redraws
CHECK_S = 0.5        # a redraw looks for the world file (a stat), and for a world
                     # reopened or the file path resolved anew, at most this often


class Frame(NamedTuple):
    """One redraw of one region, as the bench reads it."""
    ms: float           # the handler's wall time
    python_ms: float    # our Python outside the GPU calls (prepare, bookkeeping): this
                        # thread's CPU time (waits for the GIL, held by the world's
                        # loader and saver threads, are not ours)
    quality: str        # "full" or "draft"
    drawn: int          # chunks drawn
    upload_ms: float    # chunks uploaded in this redraw
    reused: bool        # drawn from the kept frame
    draw_calls: int     # geometry draws of the pipeline (0 when reused)
    submit_ms: float    # issuing the passes (Python + the backend's CPU work)
    cpu_ms: float = 0.0  # the process's CPU time (all threads: llvmpipe's too)
    host_cpu_ms: float = 0.0       # bench (finish): Blender's drawing queued before ours
    composite_cpu_ms: float = 0.0  # bench (finish): the composite alone


class _Region:
    __slots__ = ("view", "changed", "quality", "cam")

    def __init__(self):
        self.view, self.changed, self.quality = None, 0.0, "full"
        self.cam = (None, None)  # (matrices and far, render.Camera): a still view's again


class LiveView:
    def __init__(self):
        self.handle = None            # the SpaceView3D draw handler
        self.feed: Feed | None = None
        self.panes: dict = {}         # window pointer -> Pane
        self.regions: dict = {}       # region pointer -> _Region
        self.windows = frozenset()    # the windows open at the last frame (pointers)
        self.lead = None              # the region whose view the stream follows
        self.error: str | None = None  # the last frame's failure, for the panel
        self.stats = {"drawn": 0, "wanted": 0, "wanted_shown": 0, "far_drawn": 0, "far_wanted": 0,
                      "ms": 0.0, "python_ms": 0.0,
                      "quality": "full", "frames": 0, "reused": 0, "draw_calls": 0}
        self.frames: deque = deque(maxlen=512)  # the last redraws (Frame), for the bench
        # f(context) after each voxel frame with Blender's state back and the voxels'
        # depth in the depth buffer (draw with gpu.state.depth_test_set("LESS_EQUAL"))
        self.overlays: list = []
        self.reuse = True             # a still region redraws from its kept frame
        self.finish = False           # bench: wait for the GPU so frame times are real (and
                                      # finish Blender's queued drawing before ours starts)
        self._timer_on = False
        self._tick_fn, self._tick_ui_fn = self._tick, self._tick_ui  # (one object each)
        # the panel's values are read again only after touch() (issue 29: ~0.08 ms of
        # RNA reads per redraw): (gen, ...) -> Settings and its values as a tuple
        self.gen = 0
        self._s = None
        self._ok = (None, 0.0)        # (path, until): the file was there, not looked for
                                      # again before
        self._world_until = 0.0       # _feed_for: the world's look-up holds until then
        self._wins_until = 0.0        # the open windows are listed again then
        self._pv = None               # (key, _panel's values)

    def touch(self) -> None:
        """The View panel's values may have changed (a property's update, undo, a
        frame change: liveview.sync's handlers): the next redraw reads them."""
        self.gen += 1

    # ------------------------------------------------------------------ status
    @staticmethod
    def warming() -> bool:
        """Whether OpenCL kernels are being built in the background (chunks come from
        NumPy meanwhile: world.build.warm)."""
        from ... import opencl
        return opencl.warming()

    def problem(self, context) -> str | None:
        """Why the view cannot run here, as one sentence, or None."""
        import os
        import bpy
        why = host.problem()
        if why:
            return why
        path = context.scene.voxel.path
        if not path or not os.path.exists(bpy.path.abspath(path)):
            return "no world open: create or open one in the World panel"
        return self.error

    # ------------------------------------------------------------------ handler
    def _draw(self):
        import bpy
        context = bpy.context
        scene = context.scene
        vv = getattr(scene, "voxel_view", None)
        if vv is None or not vv.show:
            return
        path = scene.voxel.path
        if not self.error and (path != self._ok[0] or time.perf_counter() >= self._ok[1]):
            if self.problem(context):
                return
            # (a removed file is seen by the first redraw CHECK_S after the last look;
            # the panel asks problem() itself on each of its redraws)
            self._ok = (path, time.perf_counter() + CHECK_S)
        try:
            with host.kept():
                self._frame(context, scene, vv, path)
            self.error = None
        except VoxelError as e:
            self.error = str(e)
        except Exception as e:  # keep drawing Blender; say it once in the panel and console
            said = self._file_failed(e)
            if said is None and self.error is None:
                traceback.print_exc()
            self.error = said or f"voxel view failed: {e}"
        for fn in list(self.overlays):
            fn(context)

    def _file_failed(self, e) -> str | None:
        """The shown world's file refused a read or write of the stream (a damaged
        file: let go by the session, the next frame opens it anew; a full disk) as
        one line for the panel, or None (a bug: its traceback goes to the console)."""
        from ...core.errors import explain
        f = self.feed
        said = None if f is None else session.broken(f.world, e)
        if said is None:
            err = explain(e, None if f is None else f.world.file.path, "reading or saving")
            said = None if err is None else str(err)
        return said

    def _frame(self, context, scene, vv, path):
        import gpu
        host_cpu = 0.0
        if self.finish:  # bench: Blender's own drawing of the region, queued before ours
            p = time.process_time()
            host.device().finish()
            host_cpu = time.process_time() - p
        t0, c0, p0 = time.perf_counter(), time.thread_time(), time.process_time()
        region, rv3d, window = context.region, context.region_data, context.window
        if region is None or rv3d is None or window is None:
            return
        wp = window.as_pointer()
        now = time.perf_counter()
        # a window opened: at once; one closed (its Pane released, its regions
        # forgotten): within CHECK_S (RNA reads are ~10 us each in a redraw)
        if wp not in self.windows or now >= self._wins_until:
            wins = frozenset(w.as_pointer() for w in context.window_manager.windows)
            self._wins_until = now + CHECK_S
            if wins != self.windows:
                self._prune(context, wins)
        view = tuple(map(tuple, rv3d.view_matrix))
        key = region.as_pointer()
        st = self.regions.setdefault(key, _Region())
        distance, far, quality, sky_on, hours = self._panel(scene, vv)
        if view != st.view:
            if st.view is not None or self.lead not in self.regions:
                self.lead = key  # the region being navigated leads the stream
            st.view, st.changed = view, now
        moving = now - st.changed < STILL_S
        win_m = tuple(map(tuple, rv3d.window_matrix))
        ck = (view, win_m, distance)
        if st.cam[0] != ck:  # (a linear solve and a dataclass: reused while the view rests)
            st.cam = (ck, view_camera(view, win_m, distance * 16 * 1.5 + 256.0))
        cam = st.cam[1]
        feed = self._feed_for(path, distance, now)
        # the stream follows one region (quad view: the one last navigated): the eye of a
        # perspective view, the pivot of an orthographic one (its eye is arbitrary)
        at = None
        if key == self.lead:
            at = tuple(rv3d.view_location)[:2] if cam.ortho else (cam.x, cam.y)
        feed.set_far(far)
        had = len(feed.chunks)
        loading = feed.update(at, cam.fwd(), BUDGET_S)  # (a tuple: set_view takes floats)
        # a frame that takes in new chunks is a draft too: the last streamed ones show
        # without a full frame's wait (~0.5 s on llvmpipe); the full one follows
        busy = moving or loading or len(feed.chunks) > had
        self.stats.update(wanted=feed.wanted, far_wanted=feed.far_wanted)
        # draft while moving and while chunks stream in: a full frame holds the GIL for
        # seconds on software GL and starves the stream's worker thread
        draft = quality == "draft" or (quality == "auto" and busy)
        s, s_look = self._settings(vv, draft, feed.world, cam)
        pane = self.panes.get(wp)
        if pane is None:
            pane = self.panes[wp] = Pane(host.device())
        t_py = time.thread_time() - c0
        t1 = time.perf_counter()
        drawn = pane.sync(feed)
        t_sync = time.perf_counter() - t1
        vw, vh = gpu.state.viewport_get()[2:]
        # everything the picture depends on (Blender's objects are mixed in by depth
        # on every redraw): the same again, and the kept frame is the frame
        look = (view, win_m, (vw, vh), s_look, hours, sky_on, pane.gen, draft)
        k = pane.kept.get(key)
        reused, calls, t_sub, comp_cpu = False, 0, 0.0, 0.0
        if self.reuse and k is not None and k.look == look:
            t1 = time.perf_counter()
            composite.draw_kept(pane.dev, k)
            t_sub = time.perf_counter() - t1
            reused, draft = True, k.quality == "draft"
        else:
            pane.r.s = s
            host_vp = np.array(rv3d.perspective_matrix, np.float64)
            scale = DRAFT_SCALE if draft else 1.0
            size = (max(8, int(vw * scale)), max(8, int(vh * scale)))
            c1 = time.thread_time()
            f = pane.r.prepare(cam, hours, size)
            t_py += time.thread_time() - c1
            t2 = time.perf_counter()
            pane.r.submit(f, not composite.folds(f, (vw, vh)))
            if self.finish:
                pane.dev.finish()
                pc = time.process_time()
            # kept once the view rests, and while chunks stream in by a frame that took
            # in none (each other frame then is the last): Blender redraws the view now
            # and then with no new chunk (every 1-2 s of a fresh install's kernel
            # build), a draft on llvmpipe is 150-470 ms of the GIL the NumPy workers
            # want, and a kept one ~10 ms; not by the frames that bring chunks: keeping
            # compiles two more shaders (0.2-1.2 s each on a fresh lavapipe), not to be
            # paid before the first terrain
            keep = not moving and len(feed.chunks) == had and (not loading or had > 0)
            k = pane.kept_for(key, (vw, vh)) if self.reuse and keep else None
            composite.composite(pane.dev, f, host_vp, sky_on, k, (vw, vh))
            if self.finish:
                pane.dev.finish()
                comp_cpu = time.process_time() - pc
            t_sub = time.perf_counter() - t2
            if k is not None:
                k.look, k.quality = look, "draft" if draft else "full"
            calls = f.stats["draw_calls"]
        if self.finish:
            pane.dev.finish()
        ms = (time.perf_counter() - t0) * 1e3
        q = "draft" if draft else "full"
        S = self.stats
        if (drawn, S["wanted"], q) != (S["drawn"], S["wanted_shown"], S["quality"]):
            self._panel_redraw()  # the sidebar shows progress and quality
        S.update(drawn=drawn, far_drawn=len(pane.far_versions), ms=ms, python_ms=t_py * 1e3, quality=q, frames=S["frames"] + 1,
                 wanted_shown=S["wanted"], reused=S["reused"] + reused, draw_calls=calls)
        trace.mark("frame", ms=round(ms), drawn=drawn, q=q, upload_ms=round(t_sync * 1e3))
        self.frames.append(Frame(ms, t_py * 1e3, q, drawn, t_sync * 1e3, reused, calls,
                                 t_sub * 1e3, (time.process_time() - p0) * 1e3,
                                 host_cpu * 1e3, comp_cpu * 1e3))
        st.quality = q
        if drawn < S["wanted"] or (loading and not feed.far_loading):
            # as long again as the frame took: the worker gets at least half the time;
            # and only once it has handed something new (_tick): a frame holds the GIL
            # throughout (~0.3 s on llvmpipe) and one without new chunks only slows
            # the NumPy workers of a fresh install (issue 28)
            self._want_redraw(max(0.05, ms / 1e3), news=True)
        elif loading:  # only far tiles to come: their builder needs the GIL more than
            # we, so a redraw only for FAR_NEWS of them or the ring's last (Feed.far_news);
            # a fixed 4 frames' wait left the last tiles undrawn 2-7 s under load (issue 28);
            # once it has made them all, at once
            self._want_redraw(0.05 if feed.far_made() else max(0.05, ms / 1e3), news=True)
        elif draft and quality == "auto":  # once the view is still: a full frame
            self._want_redraw(max(0.02, STILL_S - (time.perf_counter() - st.changed)))

    def _panel(self, scene, vv):
        """(distance, far, quality, sky, hours) from the View panel, read again only
        after touch()."""
        key = (self.gen, vv.as_pointer())
        c = self._pv
        if c is None or c[0] != key:
            c = self._pv = (key, (vv.distance, vv.far, vv.quality, vv.sky, hours_of(scene)))
        return c[1]

    def _settings(self, vv, draft, world, cam):
        """render.Settings for this redraw, and its values as a tuple (the kept
        frame's look): read from the panel again only after touch() (kept while
        orbiting), or for another scene, quality, world or projection."""
        key = (self._pv[0], draft, world, cam.ortho, cam.fov)  # (after _panel)
        c = self._s
        if c is not None and c[0] == key:
            return c[1], c[2]
        s = settings_of(vv, draft, world=world)
        if cam.ortho:
            # distance fog needs an eye; an orthographic view's is arbitrary (it moves with
            # the zoom), and a side view would show the far half of the area washed out
            s.fog = False
        else:
            s.fov = min(150.0, max(10.0, cam.fov))
        self._s = (key, s, tuple(vars(s).values()))
        return s, self._s[2]

    def _feed_for(self, path, distance, now) -> Feed:
        f = self.feed
        # the world is looked up by its path (a realpath, cached by session._key for a
        # second) only every CHECK_S while the path and the world stay
        if f is not None and now < self._world_until and f.path == path and \
                f.distance == distance and session.still_open(f.world):
            return f
        world = session.world(path)
        if f is None or f.world is not world or f.distance != distance:
            if f is not None:
                f.close()
            self.feed = Feed(path, world, distance)
            self.stats.update(drawn=0, wanted=0)
            firstview.shown(path)  # the first minute: views underground come up
        self._world_until = now + CHECK_S
        return self.feed

    def _prune(self, context, wins) -> None:
        """A window opened or closed: forget the regions that went, and the Pane of a
        window that is no longer open."""
        self.windows = wins
        live = {r.as_pointer() for w in context.window_manager.windows
                for a in w.screen.areas for r in a.regions}
        for k in [k for k in self.regions if k not in live]:
            del self.regions[k]
        for w in [w for w in self.panes if w not in wins]:
            self.panes.pop(w).release()

    # ------------------------------------------------------------------ redraws
    def _want_redraw(self, after: float, news: bool = False) -> None:
        """A redraw AFTER seconds; news: not before the stream has new payloads (or an
        error) for us, checked every POLL_S, and sooner than AFTER once the stream has
        made every chunk it wants (`_tick`)."""
        import bpy
        self._news = news
        self._due = time.perf_counter() + after
        if not self._timer_on:
            self._timer_on = True
            bpy.app.timers.register(self._tick_fn,
                                    first_interval=min(after, POLL_S) if news else after)

    _news = False
    _due = 0.0

    def _streamed(self) -> bool:
        """Whether the stream has every chunk it wants (no worker left to leave the
        CPU to): the last chunks are drawn at once, not a frame's time later (issue
        28: after a 0.5-1 s draft frame on llvmpipe the whole view waited as long
        again with nothing left to make)."""
        f = self.feed
        return f is not None and f.stream.error is None and f.stream.idle

    def _nothing_new(self) -> bool:
        f = self.feed
        if not self._news or f is None or f.stream.error is not None:
            return False
        if any(len(p.versions) < len(f.chunks) for p in self.panes.values()):
            return False  # a window has not drawn all we hold yet
        return not f.stream.queued and not f.far_news()

    def _panel_redraw(self) -> None:
        import bpy
        if not bpy.app.timers.is_registered(self._tick_ui_fn):
            bpy.app.timers.register(self._tick_ui_fn, first_interval=0.01)

    def _tick_ui(self):
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

    def _tick(self):
        """Redraw while chunks stream in or a region still shows a draft frame."""
        left = self._due - time.perf_counter()
        if self._news and left > 0 and not self._streamed():
            return min(left, POLL_S)  # the workers' share of the CPU (_draw)
        if self._nothing_new():
            return POLL_S  # (the timer stays on)
        self._timer_on = False
        f = self.feed  # (VOXEL_TRACE: what asked for this redraw)
        trace.mark("redraw", news=self._news, queued=f.stream.queued if f else None,
                   held=len(f.chunks) if f else None)
        redraw()
        return None

    # ------------------------------------------------------------------ life cycle
    def sync(self) -> None:
        """Install the draw handler when a scene shows the view; redraw viewports."""
        import bpy
        show = any(getattr(getattr(s, "voxel_view", None), "show", False) for s in bpy.data.scenes)
        if show and self.handle is None:
            self.handle = bpy.types.SpaceView3D.draw_handler_add(self._draw, (), "WINDOW",
                                                                 "POST_VIEW")
        self.error = None
        self.touch()  # (the View panel's properties call this on every change)
        redraw()

    def close(self) -> None:
        """Drop the world's chunks, the handler and every GPU object (a new file,
        unregister)."""
        import bpy
        if self.handle is not None:
            bpy.types.SpaceView3D.draw_handler_remove(self.handle, "WINDOW")
            self.handle = None
        if self.feed is not None:
            self.feed.close()
            self.feed = None
        self.regions.clear()
        self.windows = frozenset()
        self._s, self._pv, self._ok, self._world_until = None, None, (None, 0.0), 0.0
        self._wins_until = 0.0
        for p in self.panes.values():
            p.release()
        self.panes.clear()
        host.forget_device()
        self.stats.update(drawn=0, wanted=0)
        self.error = None

    def stop_timers(self) -> None:
        import bpy
        for fn in (self._tick_fn, self._tick_ui_fn):
            if bpy.app.timers.is_registered(fn):
                bpy.app.timers.unregister(fn)
        self._timer_on = False


def redraw() -> None:
    """Ask every 3D viewport to redraw (the view's picture changed: an edit, a setting)."""
    import bpy
    wm = bpy.context.window_manager
    for win in (wm.windows if wm else ()):
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                area.tag_redraw()
