"""Levels of detail and their tiles, and which tiles a view draws.

Level L samples every s = 2**L blocks (L = 1..5: 2 to 32). A tile (L, tx, ty) covers
the blocks [tx*TILE*s, (tx+1)*TILE*s) (and the same in y) with TILE x TILE cells; its
arrays hold N = TILE + 3 samples a side: the TILE + 1 mesh vertices (the last one
is the next tile's first, so neighbours meet) and one more on each side for normals.
Sample k of a tile is the block column x = tx*TILE*s + (k - 1)*s: a point sample,
so a sample is exactly the column a chunk has there, at every level (tests check
it against generated chunks), and level L+1's samples are a subset of level L's.

A view draws a quadtree cut: from the coarsest level, a tile closer to the view
than DETAIL samples of its spacing is split into its 4 children, so a sample spans
about 1/DETAIL radians or less wherever it is drawn; tiles wholly inside the near
square (drawn as chunks) are left out.
"""
from __future__ import annotations

import math

import numpy as np

TILE = 32
N = TILE + 3
LEVELS = (1, 2, 3, 4, 5)
DETAIL = 64       # samples per unit of distance / spacing (see select)
FAR_MAX = 256     # chunks
MORPH = (0.65, 0.95)  # morph to the coarser level over these fractions of its switch distance


def spacing(level: int) -> int:
    return 1 << level


def span(level: int) -> int:
    """Blocks a tile covers along x (and y)."""
    return TILE << level


def origin(key) -> tuple[int, int]:
    level, tx, ty = key
    return tx * span(level), ty * span(level)


def columns(key) -> tuple[np.ndarray, np.ndarray]:
    """Block columns (X, Y) of the tile's N x N samples, indexed [kx, ky]."""
    x0, y0 = origin(key)
    s = spacing(key[0])
    k = (np.arange(N, dtype=np.int64) - 1) * s
    return np.meshgrid(x0 + k, y0 + k, indexing="ij")


def rect(key) -> tuple[int, int, int, int]:
    """Blocks [x0, x1) x [y0, y1) the tile's cells cover."""
    x0, y0 = origin(key)
    return x0, y0, x0 + span(key[0]), y0 + span(key[0])


def touching(cx: int, cy: int, levels=LEVELS):
    """Keys of the tiles (every level) with a sample in chunk (cx, cy)."""
    out = []
    bx0, by0 = cx * 16, cy * 16
    for level in levels:
        s, w = spacing(level), span(level)
        # samples reach one spacing beyond the cells on both sides
        for tx in range((bx0 - w) // w, (bx0 + 16 + s) // w + 1):
            if tx * w - s >= bx0 + 16 or (tx + 1) * w + s < bx0:
                continue
            for ty in range((by0 - w) // w, (by0 + 16 + s) // w + 1):
                if ty * w - s >= by0 + 16 or (ty + 1) * w + s < by0:
                    continue
                out.append((level, tx, ty))
    return out


def morph(d, level: int, detail: int = DETAIL):
    """How far a vertex of a level-`level` tile at horizontal distance d from the view
    has morphed to the next coarser level's surface (far/mesh.py): 0 near, 1 from
    MORPH[1] of the distance at which that level's tiles replace this one's (the
    far shader computes the same). The coarsest level does not morph."""
    if level >= LEVELS[-1]:
        return np.zeros_like(np.asarray(d, np.float64))
    t = np.asarray(d, np.float64) / (detail * spacing(level + 1))
    t = np.clip((t - MORPH[0]) / (MORPH[1] - MORPH[0]), 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _dist(x, y, r) -> float:
    dx = max(r[0] - x, 0.0, x - r[2])
    dy = max(r[1] - y, 0.0, y - r[3])
    return math.hypot(dx, dy)


def select(x: float, y: float, far: int, near: int = 0, detail: int = DETAIL):
    """Tiles drawing the ring around view point (x, y) (blocks) out to `far` chunks
    from the view chunk, beyond the `near` chunks drawn as chunks; nearest first.
    Returns [(key, distance in blocks)]."""
    if far <= 0:
        return []
    vcx, vcy = math.floor(x) >> 4, math.floor(y) >> 4
    outer = (16 * (vcx - far), 16 * (vcy - far), 16 * (vcx + far + 1), 16 * (vcy + far + 1))
    inner = (16 * (vcx - near), 16 * (vcy - near), 16 * (vcx + near + 1), 16 * (vcy + near + 1))
    top = LEVELS[-1]
    w = span(top)
    out = []
    stack = [(top, tx, ty) for tx in range(outer[0] // w, -(-outer[2] // w))
             for ty in range(outer[1] // w, -(-outer[3] // w))]
    while stack:
        key = stack.pop()
        r = rect(key)
        if r[2] <= outer[0] or r[0] >= outer[2] or r[3] <= outer[1] or r[1] >= outer[3]:
            continue
        if near > 0 and r[0] >= inner[0] and r[2] <= inner[2] and r[1] >= inner[1] \
                and r[3] <= inner[3]:
            continue
        d = _dist(x, y, r)
        level, tx, ty = key
        if level > LEVELS[0] and d < detail * spacing(level):
            stack += [(level - 1, 2 * tx + i, 2 * ty + j) for i in (0, 1) for j in (0, 1)]
            continue
        out.append((key, d))
    out.sort(key=lambda kd: (kd[1], kd[0]))
    return out
