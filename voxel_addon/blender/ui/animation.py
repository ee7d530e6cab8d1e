"""Render Animation: the scene's frame range from the scene camera through the voxel
pipeline into scene.render.filepath, one PNG per frame (camera animation and the
day cycle of the View panel honoured); when the output format is a movie (FFmpeg),
the frames go to a temporary folder and are encoded into the movie file Blender
names for that path (blender/movie.py). Invoked from the UI it runs modal (a frame
per timer tick, progress in the status bar, Esc stops and leaves no partial movie);
exec renders all at once (scripts, background mode)."""
from __future__ import annotations

import math
import os
import shutil
import tempfile

import bpy


class _Job:
    """The frames left to render, and the View (GPU objects) they share."""

    def __init__(self, scene, job: bool = False):
        from .. import session
        from ..liveview import settings_of
        from ..liveview.still import Still
        from ...core.errors import VoxelError
        if scene.camera is None or scene.camera.type != "CAMERA":
            raise VoxelError("the scene has no camera")
        self.scene = scene
        self.world = session.world(scene.voxel.path)
        self.settings = settings_of(scene.voxel_view, render=True)
        self.movie = scene.render.is_movie_format
        if self.movie:
            from .. import movie
            movie.check()
        self.view = Still(self.settings)
        self._far = None   # far.Builder while far terrain is on (tiles follow the camera)
        self.frames = list(range(scene.frame_start, scene.frame_end + 1, scene.frame_step))
        self.done = 0
        self.centre = None
        self.paths: list[str] = []
        self.result = None  # the movie's path once encoded
        self._restore = scene.frame_current
        self._tmp = tempfile.mkdtemp(prefix="voxel_anim_") if self.movie else None
        self._enc = None
        self._job = job  # encode as Blender's render job (modal UI), else blocking

    @property
    def encoding(self) -> bool:
        """Every frame is rendered and the movie is next."""
        return self.movie and self.done >= len(self.frames) and self.result is None

    def step(self) -> bool:
        """Render the next frame; False when none is left."""
        from ...render import source
        from ...textures import png_bytes
        from ..liveview import hours_of
        from .view import camera_of
        import numpy as np
        if self.encoding:
            return self._encode()
        if self.done >= len(self.frames):
            return False
        sc, f = self.scene, self.frames[self.done]
        sc.frame_set(f)
        cam, fov = camera_of(sc.camera)
        self.settings.fov = fov
        c = (math.floor(cam.x) >> 4, math.floor(cam.y) >> 4)
        if c != self.centre:  # the camera entered another chunk: the area around it
            s = self.settings
            self.view.set_area(source.world_area(self.world, cam.x, cam.y, s.distance,
                                                 s.light_radius))
            self.centre = c
            if s.far:
                self._far_ring(cam, s)
        r = sc.render
        w = max(8, r.resolution_x * r.resolution_percentage // 100)
        h = max(8, r.resolution_y * r.resolution_percentage // 100)
        img = self.view.render(cam, hours_of(sc), (w, h))
        if self.movie:
            path = os.path.join(self._tmp, f"{self.done:06d}.png")
        else:
            path = os.path.splitext(bpy.path.abspath(r.frame_path(frame=f)))[0] + ".png"
        os.makedirs(os.path.dirname(path) or ".", exist_ok=True)
        rgba = np.dstack([img, np.full(img.shape[:2], 255, np.uint8)])
        with open(path, "wb") as fh:
            fh.write(png_bytes(rgba))
        self.paths.append(path)
        self.size = (w, h)
        self.done += 1
        return True

    def _far_ring(self, cam, s) -> None:
        """Far tiles for the camera's chunk, waited for (kept in the file: a second
        render of the same path loads them)."""
        from ...core.errors import VoxelError
        from ...far import Builder
        if self._far is None:
            self._far = Builder.of(self.world)
        b = self._far
        b.set_view(cam.x, cam.y, s.far, s.distance)
        if not b.wait_ready(600.0):
            raise VoxelError("far terrain not built within 600 s")
        ready, gone = b.drain(1e9)
        self.view.r.remove_far(gone)
        self.view.r.update_far(ready)

    def _encode(self) -> bool:
        from .. import movie
        if self._enc is None:
            self.view.release()  # no GPU objects needed any more
            self._enc = movie.Encoder(self.scene, self.paths, self.size)
            if not self._job:
                self.result = self._enc.run()
                return False
            self._enc.start()
            return True
        if self._enc.running():
            return True
        self.result = self._enc.result()
        return False

    def busy(self) -> bool:
        """Blender's render job is encoding (it must end before the scene goes)."""
        return self._enc is not None and self._enc.running()

    def encoded(self) -> int:
        return self._enc.frame() if self._enc is not None else 0

    def finish(self):
        """Always (done, stopped or failed): GPU objects, the frame, temporary files."""
        if self._far is not None:
            self._far.close()
            self._far = None
        self.view.release()
        self.scene.frame_set(self._restore)
        if self._enc is not None:
            self._enc.close()
        if self._tmp:
            shutil.rmtree(self._tmp, ignore_errors=True)

    def summary(self) -> str:
        if self.result:
            return f"rendered {self.done} frames into {self.result}"
        return f"rendered {self.done} frames"


class VOXEL_OT_render_animation(bpy.types.Operator):
    bl_idname = "voxel.render_animation"
    bl_label = "Render Voxel Animation"
    bl_description = ("Render the scene's frame range from the scene camera with the voxel "
                      "pipeline into the output path (image frames, or a video when the output "
                      "format is FFmpeg; Esc stops)")

    _job = None
    _timer = None
    _stop = False  # Esc came while Blender's render job encodes: end once it has

    def _start(self, context, modal=False):
        from ...core.errors import VoxelError
        try:
            self._job = _Job(context.scene, job=modal)
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return False
        return True

    def execute(self, context):
        from ...core.errors import VoxelError
        if not self._start(context):
            return {"CANCELLED"}
        try:
            while self._job.step():
                pass
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        finally:
            self._job.finish()
        self.report({"INFO"}, self._job.summary())
        return {"FINISHED"}

    def invoke(self, context, event):
        if not self._start(context, modal=True):
            return {"CANCELLED"}
        wm = context.window_manager
        n = len(self._job.frames)
        wm.progress_begin(0, 2 * n if self._job.movie else n)
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        from ...core.errors import VoxelError
        job = self._job
        if event.type == "ESC":
            if job.busy():  # the job reads the temporary scene until it ends
                self._stop = True
                return {"RUNNING_MODAL"}
            return self._end(context, f"stopped after {job.done} frames", {"CANCELLED"})
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if self._stop:
            if job.busy():
                return {"RUNNING_MODAL"}
            return self._end(context, "stopped while encoding the video", {"CANCELLED"})
        try:
            more = self._job.step()
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return self._end(context, None, {"CANCELLED"})
        n = len(job.frames)
        context.window_manager.progress_update(job.done + job.encoded())
        context.workspace.status_text_set(
            f"Voxel animation: encoding frame {job.encoded()} / {n} (Esc stops)"
            if job.encoding else f"Voxel animation: frame {job.done} / {n} (Esc stops)")
        if not more:
            return self._end(context, job.summary(), {"FINISHED"})
        return {"RUNNING_MODAL"}

    def _end(self, context, msg, result):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        self._job.finish()
        if msg:
            self.report({"INFO"}, msg)
        return result


CLASSES = [VOXEL_OT_render_animation]
