"""A big region baked tile by tile, each tile on its own (one .glb per tile, cluster
workers): the client cuts each tile's input from the world, a worker bakes it.

    plan(x0, y0, x1, y1) -> [(name, tx0, ty0, tx1, ty1)]   # tile_X_Y, 64×64 blocks
    cut(world, region, tile) -> dict of bytes and ints (picklable, no file needed)
    bake(cut_dict, **bake_kw) -> Bake                        # one part: the tile

A tile's input is its blocks plus a RING of context columns (clipped to the region:
beyond it is air, as in the region's own bake). Light travels less than 16 columns
(bake.REACH), so the tile's light, and so its part, equals that tile's part of the
whole region's bake (per="tile"); only the light atlas is the tile's own.
"""
from __future__ import annotations

import zlib

import numpy as np

from . import REACH, bake_blocks, check_region, colors_of, region_of

TILE = 64
RING = REACH  # columns of context around a tile: its light is exact


def plan(x0, y0, x1, y1, tile: int = TILE) -> list[tuple[str, int, int, int, int]]:
    """The region's tiles as (name, tx0, ty0, tx1, ty1), named by their first block column
    like bake.windows' "tile" parts."""
    x0, y0, x1, y1 = check_region(x0, y0, x1, y1)
    return [(f"tile_{x}_{y}", x, y, min(x + tile, x1), min(y + tile, y1))
            for y in range(y0, y1, tile) for x in range(x0, x1, tile)]


def _pack(a) -> bytes:
    return zlib.compress(np.asfortranarray(a, np.uint16).tobytes(order="F"), 1)


def _unpack(b: bytes, shape) -> np.ndarray:
    return np.frombuffer(zlib.decompress(b), np.uint16).reshape(shape, order="F")


def cut(world, region, tile) -> dict:
    """What a worker needs to bake `tile` (a plan() entry) of `region`: its blocks with
    RING columns around them (inside the region), their small data and the palette."""
    x0, y0, x1, y1 = region
    name, tx0, ty0, tx1, ty1 = tile
    ax0, ay0 = max(tx0 - RING, x0), max(ty0 - RING, y0)
    ax1, ay1 = min(tx1 + RING, x1), min(ty1 + RING, y1)
    blocks = region_of(world, ax0, ay0, ax1, ay1)
    data, palette = colors_of(world, ax0, ay0, ax1, ay1)
    return {"name": name, "origin": (ax0, ay0), "shape": tuple(blocks.shape),
            "window": (tx0 - ax0, ty0 - ay0, tx1 - tx0, ty1 - ty0),
            "blocks": _pack(blocks), "data": None if data is None else _pack(data),
            "palette": None if palette is None else np.asarray(palette, np.uint8).tolist(),
            "empty": not blocks[tx0 - ax0:tx1 - ax0, ty0 - ay0:ty1 - ay0].any()}


def bake(c: dict, **kw):
    """The Bake of one cut() tile: one part named like the tile (none when it is empty)."""
    shape = tuple(c["shape"])
    data = None if c["data"] is None else _unpack(c["data"], shape)
    pal = None if c["palette"] is None else np.asarray(c["palette"], np.uint8)
    w = c["window"]
    return bake_blocks(_unpack(c["blocks"], shape), origin=(*c["origin"], 0), per="tile",
                       tile=max(w[2], w[3]), window=w, data=data, palette=pal, **kw)
