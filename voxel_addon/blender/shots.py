"""What Render Voxel Animation (ui/animation.py) renders, read from a .blend for the
`animate` command: the View panel's render.Settings, the frame size and, per frame,
the scene camera (render.Camera), its vertical field of view and the time of day
(the day cycle when the view follows the timeline). bpy only here: the frames are
rendered elsewhere (cli/animate.py, on the moderngl device, maybe on a cluster)."""
from __future__ import annotations

from contextlib import contextmanager
from dataclasses import dataclass

from ..core.errors import VoxelError


@dataclass(frozen=True)
class Shot:
    frame: int
    camera: tuple  # render.Camera's (x, y, z, yaw, pitch)
    fov: float     # vertical, degrees
    hours: float


@contextmanager
def _quiet():
    """Blender's own log lines (written to the C stdout and stderr) go nowhere: the
    command's stdout is its result and its errors are one line."""
    import os
    import sys
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, 1)
        os.dup2(null, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in (*saved, null):
            os.close(fd)


def read(blend, frames=None):
    """(Settings, (w, h), [Shot]) of the .blend's scene over `frames` (first, last),
    default the scene's frame range (with its step)."""
    import bpy
    from . import register
    from .liveview import hours_of, settings_of
    from .ui.view import camera_of
    if not hasattr(bpy.types.Scene, "voxel_view"):
        bpy.ops.wm.read_factory_settings(use_empty=True)
        register()  # the add-on's scene settings, so their defaults read as in Blender
    try:
        with _quiet():
            bpy.ops.wm.open_mainfile(filepath=str(blend), load_ui=False)
    except RuntimeError as e:
        raise VoxelError(f"cannot read {blend}: {str(e).strip().splitlines()[-1]}") from None
    sc = bpy.context.scene
    if sc.camera is None or sc.camera.type != "CAMERA":
        raise VoxelError(f"the scene of {blend} has no camera")
    if frames is None:
        todo = range(sc.frame_start, sc.frame_end + 1, max(sc.frame_step, 1))
    else:
        a, b = map(int, frames)
        if b < a:
            raise VoxelError(f"--frames {a} {b}: the last frame comes before the first")
        todo = range(a, b + 1)
    s = settings_of(sc.voxel_view, render=True)
    r = sc.render
    size = (max(8, r.resolution_x * r.resolution_percentage // 100),
            max(8, r.resolution_y * r.resolution_percentage // 100))
    shots = []
    for f in todo:
        sc.frame_set(f)
        cam, fov = camera_of(sc.camera)
        shots.append(Shot(f, (cam.x, cam.y, cam.z, cam.yaw, cam.pitch), fov, hours_of(sc)))
    return s, size, shots
