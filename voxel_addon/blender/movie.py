"""Frames on disk into a video with Blender's own FFmpeg writer: a temporary scene whose
sequencer holds the frames as one image strip, rendered as an animation with the
source scene's FFmpeg settings, then removed. Python has no movie-writer API, and the
sequencer path writes exactly what a user's own Render Animation would. From the UI
the encode runs as Blender's render job (`start`, poll `running`), so the window
stays responsive and Esc stops it (Esc sets Blender's break flag, which the job reads);
scripts encode blocking (`run`)."""
from __future__ import annotations

import os
import shutil

import bpy

from ..core.errors import VoxelError
from . import compat


def check() -> None:
    """VoxelError when this Blender cannot write video."""
    if not bpy.app.build_options.codec_ffmpeg:
        raise VoxelError("this Blender was built without FFmpeg: choose an image format "
                         "(e.g. PNG) as the output")


def dest(scene) -> str:
    """The movie file Blender names for the scene's output path and frame range."""
    return bpy.path.abspath(scene.render.frame_path())


def _copy(src, dst, skip=()):
    for p in src.bl_rna.properties:
        if p.is_readonly or p.identifier in skip or p.type in {"POINTER", "COLLECTION"}:
            continue
        try:
            setattr(dst, p.identifier, getattr(src, p.identifier))
        except (TypeError, AttributeError, ValueError):  # not valid for this codec
            pass


class Encoder:
    """One encode of FRAMES (PNG paths, all the same size) into the movie of SCENE.
    The file appears at `dest(scene)` only once complete; `close()` always removes the
    temporary scene and any partial file."""

    def __init__(self, scene, frames: list[str], size: tuple[int, int]):
        check()
        self.src, self.frames, self.size = scene, frames, size
        self.dest = dest(scene)
        self.sc = None
        self.out = None
        self.complete = False

    def _scene(self):
        src, (w, h) = self.src.render, self.size
        sc = self.sc = bpy.data.scenes.new("voxel_encode")
        r = sc.render
        r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
        r.pixel_aspect_x, r.pixel_aspect_y = src.pixel_aspect_x, src.pixel_aspect_y
        r.fps, r.fps_base = src.fps, src.fps_base
        sc.frame_start, sc.frame_end, sc.frame_step = 1, len(self.frames), 1
        im = r.image_settings
        compat.video_output(im)
        _copy(src.image_settings, im, skip={"media_type", "file_format"})
        _copy(src.ffmpeg, r.ffmpeg)
        r.ffmpeg.audio_codec = "NONE"  # the frames have no sound
        # the frames are display-ready sRGB: pass them through untouched
        sc.display_settings.display_device = "sRGB"
        vs = sc.view_settings
        vs.view_transform, vs.look, vs.exposure, vs.gamma = "Standard", "None", 0.0, 1.0
        sc.sequencer_colorspace_settings.name = "sRGB"
        r.use_file_extension = src.use_file_extension
        r.filepath = os.path.join(os.path.dirname(self.frames[0]), "movie")
        se = sc.sequence_editor_create()
        s = compat.strips(se).new_image("frames", self.frames[0], 1, 1)
        for f in self.frames[1:]:
            s.elements.append(os.path.basename(f))
        return sc

    def run(self) -> str:
        """Encode blocking (scripts, background mode); the movie's path."""
        sc = self._scene()
        self.out = bpy.path.abspath(sc.render.frame_path())
        try:
            res = bpy.ops.render.render(animation=True, scene=sc.name)
        except RuntimeError as e:  # the writer's report, e.g. a codec this build lacks
            raise VoxelError(f"the video could not be written: {str(e).strip()}") from None
        if res != {"FINISHED"}:
            raise VoxelError("the video could not be written")
        return self._keep()

    def start(self) -> None:
        """Encode as Blender's render job (UI: Blender stays responsive, its status bar
        shows the job, Esc stops it); poll `running()`, then `result()`."""
        sc = self._scene()
        self.out = bpy.path.abspath(sc.render.frame_path())
        self.complete = False
        bpy.app.handlers.render_complete.append(self._completed)
        view = bpy.context.preferences.view
        shown = view.render_display_type
        view.render_display_type = "NONE"  # no render window for the frames we show
        try:
            res = bpy.ops.render.render("INVOKE_DEFAULT", animation=True, scene=sc.name)
        except RuntimeError as e:
            raise VoxelError(f"the video could not be written: {str(e).strip()}") from None
        finally:
            view.render_display_type = shown
        if "RUNNING_MODAL" not in res:
            raise VoxelError("the video could not be written")

    def _completed(self, scene, *_):
        if self.sc is not None and getattr(scene, "name", None) == self.sc.name:
            self.complete = True

    def running(self) -> bool:
        return self.sc is not None and bpy.app.is_job_running("RENDER")

    def frame(self) -> int:
        """The frame the job is at (1-based)."""
        return self.sc.frame_current if self.sc is not None else 0

    def result(self) -> str:
        """After the job: the movie's path; VoxelError when it stopped or failed."""
        if not self.complete:
            raise VoxelError("the video was stopped or failed before its end: no file written")
        return self._keep()

    def _keep(self) -> str:
        if not self.out or not os.path.isfile(self.out):
            raise VoxelError(f"the video could not be written with "
                             f"{self.src.render.ffmpeg.format}/{self.src.render.ffmpeg.codec}")
        os.makedirs(os.path.dirname(self.dest) or ".", exist_ok=True)
        shutil.move(self.out, self.dest)
        self.out = None
        return self.dest

    def close(self):
        """Never while the job runs (its thread reads the scene)."""
        hs = bpy.app.handlers.render_complete
        while self._completed in hs:
            hs.remove(self._completed)
        if self.sc is not None:
            bpy.data.scenes.remove(self.sc)
            self.sc = None
        if self.out and os.path.exists(self.out):
            os.remove(self.out)
