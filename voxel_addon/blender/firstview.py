"""The first minute with a world: where the 3D views look when it is first shown, and
Frame World (issue 18).

Blender's default view sits a few units above z 0 looking at the origin; a generated
world's ground lies near z 62, so Show in Viewport would leave that view inside the
rock, seeing only what the caves let through. When a world is first shown in this
session (`shown`, called once by the live view), every 3D view that is underground
or far from the world (`lost`) is brought to the surface around the world's origin
(`frame`); Frame World does the same for one view on request. Everything here reads
and moves the view only (region_3d), never the world's blocks.
"""
from __future__ import annotations

import math

import numpy as np

PITCH = 30.0     # degrees the framed view looks down
YAW = 45.0       # ... from the south-west, towards +x +y
REACH = 48.0     # blocks from the pivot to the eye (the live view shows 128 and more)
MARGIN = 2.0     # the eye counts as underground this far below the surface

_done: set = set()  # world paths already shown in this session


def ground(world, x: float, y: float) -> int:
    """The z just above the highest block of column (x, y) (loads or generates its
    chunk); 0 for an empty column."""
    from ..core.blocks import AIR
    xi, yi = math.floor(x), math.floor(y)
    col = world.chunk_at(xi >> 4, yi >> 4).blocks[xi & 15, yi & 15, :]
    solid = np.nonzero(col != AIR)[0]
    return int(solid[-1]) + 1 if len(solid) else 0


def eye_of(rv3d) -> tuple[float, float, float]:
    """Where a region's view looks from (perspective: the eye; orthographic: the
    pivot, whose eye is arbitrary)."""
    if not rv3d.is_perspective:
        return tuple(rv3d.view_location)
    return tuple(rv3d.view_matrix.inverted().translation)


def centre(world) -> tuple[float, float]:
    """The world's origin: the middle of block column (0, 0)."""
    return 0.5, 0.5


def far(world, rv3d, reach_blocks: float) -> bool:
    """Whether the view is farther than REACH_BLOCKS from every chunk the file holds
    (from the origin when it holds none): the live view would show nothing there."""
    x, y, _ = eye_of(rv3d)
    keys = world.file.chunk_keys()
    if keys:
        k = np.asarray(keys, np.float64) * 16 + 8
        d = np.hypot(k[:, 0] - x, k[:, 1] - y).min() - 8 * math.sqrt(2)
    else:
        ox, oy = centre(world)
        d = math.hypot(x - ox, y - oy)
    return d > reach_blocks


def underground(world, rv3d) -> bool:
    x, y, z = eye_of(rv3d)
    if not 0 <= z < 256:
        return False
    return z < ground(world, x, y) - MARGIN


def lost(world, rv3d, reach_blocks: float) -> bool:
    """Whether a view shows the world badly: underground, or far from it."""
    return far(world, rv3d, reach_blocks) or underground(world, rv3d)


def frame(world, rv3d, at: tuple[float, float] | None = None) -> None:
    """Look at the surface around AT (default the origin) from above and the
    south-west, in perspective, REACH blocks away."""
    from mathutils import Euler, Vector
    x, y = at or centre(world)
    rot = Euler((math.radians(90.0 - PITCH), 0.0, math.radians(YAW - 90.0))).to_quaternion()
    back = rot @ Vector((0.0, 0.0, REACH))  # from the pivot to the eye
    z = float(ground(world, x, y))
    # a hill between the pivot and the eye: lift both until the eye clears it
    z = max(z, ground(world, x + back.x, y + back.y) + 2.0 - back.z)
    rv3d.view_perspective = "PERSP"
    rv3d.view_rotation = rot
    rv3d.view_location = (x, y, z)
    rv3d.view_distance = REACH


def views(context):
    """(area, region_3d) of every 3D viewport in every window."""
    for win in context.window_manager.windows:
        for area in win.screen.areas:
            if area.type == "VIEW_3D":
                yield area, area.spaces.active.region_3d


def arrive(context, world, reach_blocks: float) -> int:
    """Frame every lost 3D view on the world; how many were moved."""
    moved = 0
    for area, rv3d in views(context):
        if rv3d is not None and lost(world, rv3d, reach_blocks):
            frame(world, rv3d)
            area.tag_redraw()
            moved += 1
    return moved


def shown(path: str) -> None:
    """The live view shows the world at PATH (call when its stream starts): once per
    world and session, bring lost views to its surface. Runs from a timer, so a call
    from inside a draw handler does not move the view mid-frame."""
    import os
    key = os.path.realpath(path)
    if key in _done:
        return
    _done.add(key)
    import bpy

    def later():
        from . import session
        ctx = bpy.context
        sc = ctx.scene
        if session.is_open(path) and getattr(sc, "voxel_view", None) is not None:
            arrive(ctx, session.world(path), sc.voxel_view.distance * 16.0)
        return None

    bpy.app.timers.register(later, first_interval=0.0)


def forget() -> None:
    """A new file or unregister: the next show is a first show again."""
    _done.clear()
