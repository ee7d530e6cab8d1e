"""What a frame of the live view or a render is made with: render.Settings from the
scene's View panel, the time of day, and the camera of a region's matrices."""
from __future__ import annotations

import math

import numpy as np

VIEW_SHADOW_SIZE = 1024  # the viewport's shadow map (renders: Settings.shadow_size)
# a draft frame's grass and flowers (double-sided plants: alpha tested, no early
# depth test, a third of the G-buffer pass on llvmpipe for a sixth of its quads) out
# to this many blocks; beyond, at a draft's resolution, they are a pixel or two
DRAFT_PLANTS = 128.0
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
        s.plants_reach = DRAFT_PLANTS
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
    G-buffer's depth precision; the composite converts depth to Blender's projection.
    A region's view matrix is rigid (its rotation and distance), so the eye and the
    inverse come in closed form; the projection's part is kept per window matrix
    (orbiting changes only the view: issue 29, a redraw's Python)."""
    from ...render import Camera
    if not isinstance(view, tuple):  # (mathutils matrices)
        view, window = tuple(map(tuple, view)), tuple(map(tuple, window))
    key = (window, far)
    pj = _PROJ.get(key)
    if pj is None:
        if len(_PROJ) >= 8:
            _PROJ.clear()
        pj = _PROJ[key] = _projection(window, far)
    P, P_inv, (fov, aspect, near, far_) = pj
    (a, b, c, tx), (d, e, f, ty), (g, h, i, tz) = view[0], view[1], view[2]
    x, y, z = -(a * tx + d * ty + g * tz), -(b * tx + e * ty + h * tz), -(c * tx + f * ty + i * tz)
    k = -1.0 / math.sqrt(g * g + h * h + i * i)
    fx, fy, fz = g * k, h * k, i * k
    V = np.array(view, np.float64)
    V_inv = np.array(((a, d, g, x), (b, e, h, y), (c, f, i, z), (0.0, 0.0, 0.0, 1.0)))
    return Camera(x, y, z, math.degrees(math.atan2(fy, fx)),
                  math.degrees(math.asin(max(-1.0, min(1.0, fz)))), fov, aspect, near, far_,
                  V, P, vps=_fixed(P @ V, V_inv @ P_inv))


_PROJ: dict = {}  # (window matrix, far) -> view_camera's projection, its inverse, parameters


def _fixed(*arrays):
    """Arrays made read-only: a camera hands out the same ones on every call (and the
    frame block takes them as unchanged while they are the same objects)."""
    for a in arrays:
        a.flags.writeable = False
    return arrays


def _projection(window, far: float):
    P = np.array(window, np.float64)
    if abs(P[3, 3] - 1.0) < 1e-6:  # orthographic: the eye's plane is arbitrary, look both ways
        n, f = -far, far
        P[2, :] = (0.0, 0.0, -2 / (f - n), -(f + n) / (f - n))
        fov = 0.0
    else:
        n, f = max(float(P[2, 3] / (P[2, 2] - 1.0)), 0.05), far
        P[2, 2], P[2, 3] = (far + n) / (n - far), 2 * far * n / (n - far)
        fov = math.degrees(2 * math.atan(1 / P[1, 1]))
    return P, np.linalg.inv(P), (fov, float(P[1, 1] / P[0, 0]), float(n), float(f))
