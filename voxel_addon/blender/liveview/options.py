"""What a frame of the live view or a render is made with: render.Settings from the
scene's View panel, the time of day, and the camera of a region's matrices."""
from __future__ import annotations

import numpy as np

VIEW_SHADOW_SIZE = 1024  # the viewport's shadow map (renders: Settings.shadow_size)
# Blender's gpu module has no multisampled textures: frames in Blender are never
# multisampled, so the MSAA switches are the command line's only (the panel says so)
MSAA_ONLY = ("msaa_alpha", "per_sample")


def effects() -> list[str]:
    """The effects of render.settings that frames in Blender can switch."""
    from ...render.settings import EFFECTS
    return [e for e in EFFECTS if e not in MSAA_ONLY]


def settings_of(vv, draft: bool = False, render: bool = False, world=None):
    """render.Settings from scene.voxel_view; draft drops the expensive passes. A
    render (Render Voxel View, Render Animation) keeps the CLI's shadow map: the
    viewport's cheaper one is for redraws. (MSAA: Blender's gpu module has no
    multisampled textures, so frames in Blender are never multisampled.) world: the
    scene's open World when the caller holds it (a redraw: no look-up by path)."""
    from ...render.settings import Settings
    s = Settings(distance=vv.distance, far=vv.far, light_radius=min(8, vv.distance), msaa=1)
    for e in effects():
        setattr(s, e, bool(getattr(vv, e)))
    s.transparency = vv.transparency
    s.debug = vv.debug_view or "none"
    s.exposure, s.haze, s.cloud_cover = vv.exposure, vv.haze, vv.cloud_cover
    s.sea_level = sea_level(vv.id_data, world)
    if render:
        return s
    # the map covers ~100 blocks up to the shadow fade: at 1024 a texel is still a tenth
    # of a block (frames equal to 2048's within 16 levels, mean 0.00) at half the pass
    # cost (clear + raster of 4M texels: 78 -> 34 ms at distance 16 on llvmpipe)
    s.shadow_size = VIEW_SHADOW_SIZE
    if draft:
        s.shadows = s.ssao = s.dof = s.godrays = False
        s.per_sample = False
        s.peel_layers = min(s.peel_layers, 1)
        s.far_draft = True
    return s


def sea_level(scene, world=None) -> int:
    """The open world's water level (render.source.sea_level: the sea beyond the
    shown area), -1 without one."""
    from .. import session
    from ...core.errors import VoxelError
    from ...render import source
    try:
        return source.sea_level((session.world(scene.voxel.path) if world is None else world).generator)
    except (VoxelError, AttributeError, OSError):
        return -1


def hours_of(scene) -> float:
    """The view's time of day: the property, or when following the timeline the
    property at the scene's first frame plus a day per frames_per_day frames."""
    v = scene.voxel_view
    if v.follow_timeline:
        days = (scene.frame_current - scene.frame_start) / v.frames_per_day
        return (v.hours + 24.0 * days) % 24.0
    return v.hours


def view_camera(view, window, far: float):
    """render.Camera for Blender's region matrices with the window's x/y rows but
    our own near/far: Blender's clip range (0.01..1000 by default) would spoil the
    G-buffer's depth precision; the composite converts depth to Blender's projection."""
    from ...render import Camera
    P = np.array(window, np.float64)
    if abs(P[3, 3] - 1.0) < 1e-6:  # orthographic: the eye's plane is arbitrary, look both ways
        n, f = -far, far
        P[2, :] = (0.0, 0.0, -2 / (f - n), -(f + n) / (f - n))
    else:
        n = max(float(P[2, 3] / (P[2, 2] - 1.0)), 0.05)
        P[2, 2], P[2, 3] = (far + n) / (n - far), 2 * far * n / (n - far)
    return Camera.from_matrices(np.array(view, np.float64), P)
