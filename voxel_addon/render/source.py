"""Where the pixels' data comes from: an area of a world file or a reference scene,
as (blocks with a one-voxel ring, light, cx0, cy0) for Renderer.set_area(ring=True)."""
from __future__ import annotations

import math

import numpy as np

from ..core.errors import VoxelError


def context():
    """A standalone moderngl context (EGL, headless) for the CLI, tests and bench."""
    import moderngl
    try:
        return moderngl.create_standalone_context(backend="egl")
    except Exception as e:  # no EGL/GL here: a clear one-liner beats a C traceback
        raise VoxelError(f"cannot open an OpenGL context (EGL): {e}") from None


def world_area(world, x: float, y: float, distance: int):
    """The (2d+1)² chunks around the chunk holding (x, y), plus ring and light."""
    from .. import light as lightmod
    cx, cy = math.floor(x) >> 4, math.floor(y) >> 4
    cx0, cy0, cx1, cy1 = cx - distance, cy - distance, cx + distance + 1, cy + distance + 1
    wide = world.region_blocks(cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1)
    light = lightmod.region_light(wide)
    return np.asfortranarray(wide[15:-15, 15:-15]), light, cx0, cy0


def scene_area(name: str):
    """A reference scene (meshing.scenes): blocks with ring, light, origin chunk."""
    from .. import light as lightmod
    from ..meshing import scenes
    if name not in scenes.SCENES:
        raise VoxelError(f"unknown scene {name!r} (known: {', '.join(scenes.SCENES)})")
    sc = scenes.SCENES[name]
    b = scenes.blocks(name)  # area + one-voxel ring
    light = lightmod.solve(b)[1:-1, 1:-1]
    return b, np.asfortranarray(light), sc.chunks[0], sc.chunks[1]
