"""Where the pixels' data comes from: an area of a world file or a reference scene,
as an `Area` for Renderer.set_area(ring=True)."""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..core.errors import VoxelError


class Area(NamedTuple):
    """What Renderer.set_area(blocks, light, cx0, cy0, ring=True, light_at=...) takes."""
    blocks: np.ndarray      # (16w + 2, 16h + 2, 256): the chunks plus a one-voxel ring
    light: np.ndarray       # packed light of the chunks from light_at
    cx0: int
    cy0: int
    light_at: tuple[int, int]
    data: np.ndarray | None = None     # the blocks' small data (the `color` block's colour)
    palette: np.ndarray | None = None  # the world's colours, (n, 3) uint8 (core.colors)
    models: dict | None = None         # Minecraft model quads per chunk (Renderer.set_models)


def sea_level(generator) -> int:
    """The water level of a world's generator (its `sea_level` parameter), -1 if it
    has none (render.Settings.sea_level: the sea beyond the shown area)."""
    return int(getattr(generator, "params", {}).get("sea_level", -1))


def open_sea(renderer) -> bool:
    """Whether a sea beyond an area set with set_area(ring=True) belongs there: a tenth
    of the area's edge is open water (a desert or a mountain range fades into the haze
    instead). The CLI, the bench and the golden images switch Settings.sea by it."""
    return renderer.edge_water is None or renderer.edge_water > 0.1


def scene_sea_level(name: str) -> int:
    """sea_level of a reference scene's generator (meshing.scenes)."""
    from ..meshing import scenes
    return scenes.sea_level(name)


def world_area(world, x: float, y: float, distance: int, light_radius: int = 8) -> Area:
    """The (2d+1)² chunks around the chunk holding (x, y), plus ring, and the light of
    the light window (lightvol.window) only: memory stays bounded at distance 32."""
    from .. import light as lightmod
    from .lightvol import window
    cx, cy = math.floor(x) >> 4, math.floor(y) >> 4
    cx0, cy0, cx1, cy1 = cx - distance, cy - distance, cx + distance + 1, cy + distance + 1
    wide = world.region_blocks(cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1)
    data = _small_data(world, cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1)
    lx0, ly0, lx1, ly1 = window((cx0, cy0, cx1, cy1), light_radius)
    i, j = 16 * (lx0 - cx0), 16 * (ly0 - cy0)  # wide starts one chunk before cx0
    lb = getattr(world, "light_blocks", None)   # a stack's model blocks pass light
    seen = lb(wide, data) if lb is not None else wide
    light = lightmod.region_light(seen[i:i + 16 * (lx1 - lx0 + 2), j:j + 16 * (ly1 - ly0 + 2)])
    blocks = np.asfortranarray(wide[15:-15, 15:-15])
    data = None if data is None else np.asfortranarray(data[15:-15, 15:-15])
    # with a resource stack its model blocks (air for the mesher from here on, their
    # light solved above): world.model_quads
    quads = getattr(world, "model_quads", None)
    models = quads(blocks, data, cx0, cy0) if quads is not None else None
    return Area(blocks, light, cx0, cy0, (lx0, ly0), data,
                world.colors() if hasattr(world, "colors") else None, models or None)


def _small_data(world, cx0, cy0, cx1, cy1):
    """The small data of chunks [cx0, cx1) x [cy0, cy1) as one array (the chunks
    region_blocks just loaded), or None where no chunk has any."""
    keys = [(cx, cy) for cy in range(cy0, cy1) for cx in range(cx0, cx1)]
    out = None
    for (cx, cy), c in world.load(keys).items():
        d = getattr(c, "data", None)
        if d is not None:
            if out is None:
                out = np.zeros((16 * (cx1 - cx0), 16 * (cy1 - cy0), 256), np.uint16, order="F")
            out[16 * (cx - cx0):16 * (cx - cx0 + 1), 16 * (cy - cy0):16 * (cy - cy0 + 1)] = d
    return out


def scene_area(name: str):
    """A reference scene (meshing.scenes): blocks with ring, light, origin chunk."""
    from .. import light as lightmod
    from ..meshing import scenes
    if name not in scenes.SCENES:
        raise VoxelError(f"unknown scene {name!r} (known: {', '.join(scenes.SCENES)})")
    sc = scenes.SCENES[name]
    b = scenes.blocks(name)  # area + one-voxel ring
    light = lightmod.solve(b)[1:-1, 1:-1]
    return Area(b, np.asfortranarray(light), sc.chunks[0], sc.chunks[1], sc.chunks[:2])
