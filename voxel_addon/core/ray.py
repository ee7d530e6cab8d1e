"""A ray through the voxel grid: which voxel face the mouse points at (issue 13).

Amanatides & Woo's walk, cell by cell, over chunk columns that the caller hands out
one at a time (`chunk(cx, cy)` -> the (16, 16, 256) block array, or None when the
chunk is not loaded). Chunks not loaded *before* the ray first meets a loaded one
are skipped whole (nothing is drawn there, e.g. between a far orthographic eye and
the terrain); one met after that ends the walk as "unloaded": what lies behind it is
unknown, so nothing may be edited there.
"""
from __future__ import annotations

import math
from typing import Callable, NamedTuple

import numpy as np

from .chunk import HEIGHT, SIZE

HIT, SKY, BELOW, UNLOADED = "hit", "sky", "below", "unloaded"


class Hit(NamedTuple):
    status: str                        # HIT, SKY (nothing up to max_dist), BELOW, UNLOADED
    cell: tuple | None = None          # the voxel hit
    normal: tuple | None = None        # the face entered, e.g. (0, 0, 1) = its top; (0, 0, 0) when inside
    t: float = math.inf                # distance along the (unit) direction
    block: int = 0

    @property
    def before(self) -> tuple | None:
        """The empty cell in front of the face: where a placed block goes."""
        if self.status != HIT or self.normal == (0, 0, 0):
            return None
        return tuple(c + n for c, n in zip(self.cell, self.normal))


def _slab(o: float, d: float, lo: float, hi: float) -> tuple[float, float]:
    """Parameter interval where o + t d lies in [lo, hi]."""
    if d == 0.0:
        return (-math.inf, math.inf) if lo <= o <= hi else (math.inf, -math.inf)
    a, b = (lo - o) / d, (hi - o) / d
    return (a, b) if a <= b else (b, a)


def cast(origin, direction, chunk: Callable, *, max_dist: float = 2000.0,
         solid: np.ndarray | None = None, ignore=frozenset()) -> Hit:
    """The first voxel hit by origin + t * direction, 0 <= t <= max_dist.

    `solid` is a bool table by block id (default: every block but air); `ignore` a set
    of (x, y, z) cells treated as air (a paint stroke skips what it placed itself).
    """
    o = [float(v) for v in origin]
    d = [float(v) for v in direction]
    n = math.sqrt(sum(v * v for v in d))
    if n == 0.0:
        raise ValueError("ray direction is zero")
    d = [v / n for v in d]
    if solid is None:
        from .blocks import REGISTRY
        solid = np.arange(len(REGISTRY)) != 0
    z0, z1 = _slab(o[2], d[2], 0.0, float(HEIGHT))
    t, t_end = max(z0, 0.0), min(z1, max_dist)
    if t > t_end:  # the ray never crosses the world's height
        return Hit(BELOW if o[2] < 0.0 or (o[2] <= HEIGHT and d[2] < 0) else SKY)
    # Outer walk over chunk columns (2-D), inner walk over cells of a loaded one.
    seen = False
    step = [1 if v > 0 else -1 if v < 0 else 0 for v in d]
    while t <= t_end:
        p = [o[i] + d[i] * t for i in range(3)]
        key = (_cell(p[0], d[0]) >> 4, _cell(p[1], d[1]) >> 4)
        cx0, cy0 = key[0] * SIZE, key[1] * SIZE
        a0, a1 = _slab(o[0], d[0], cx0, cx0 + SIZE)
        b0, b1 = _slab(o[1], d[1], cy0, cy0 + SIZE)
        t_out = min(a1, b1, t_end)
        blocks = chunk(*key)
        if blocks is None:
            if seen:
                return Hit(UNLOADED, t=t)
        else:
            seen = True
            h = _walk(o, d, step, t, t_out, key, blocks, solid, ignore, t == 0.0)
            if h is not None:
                return h
        if t_out >= t_end:
            break
        t = _next_t(t_out, t)
    if t_end == max_dist:
        return Hit(SKY)
    return Hit(BELOW if d[2] < 0 else SKY)


def _next_t(t_out: float, t: float) -> float:
    """A t just past a chunk's exit, so the next column is the one beyond it."""
    return t_out + max(1e-9, abs(t_out) * 1e-12) if t_out > t else t + 1e-9


def _cell(p: float, d: float) -> int:
    """The cell a ray at coordinate p moving by d is in just after this instant."""
    f = math.floor(p)
    return f - 1 if d < 0 and f == p else f


def _walk(o, d, step, t, t_out, key, blocks, solid, ignore, at_origin) -> Hit | None:
    """Cells of one chunk column from t to t_out (the inner DDA)."""
    p = [o[i] + d[i] * t for i in range(3)]
    lo = (key[0] * SIZE, key[1] * SIZE, 0)
    hi = (lo[0] + SIZE - 1, lo[1] + SIZE - 1, HEIGHT - 1)
    c = [min(max(_cell(p[i], d[i]), lo[i]), hi[i]) for i in range(3)]
    # t at which the ray crosses the next cell boundary on each axis, and per cell.
    nxt, delta = [0.0] * 3, [0.0] * 3
    for i in range(3):
        if step[i] == 0:
            nxt[i], delta[i] = math.inf, math.inf
        else:
            edge = c[i] + (1 if step[i] > 0 else 0)
            nxt[i] = (edge - o[i]) / d[i]
            delta[i] = abs(1.0 / d[i])
    # The face we came in through: the axis whose boundary lies at t (the largest entry).
    normal = (0, 0, 0)
    if not at_origin:
        ent = [((c[i] + (0 if step[i] > 0 else 1)) - o[i]) / d[i] if step[i] else -math.inf
               for i in range(3)]
        ax = max(range(3), key=lambda i: ent[i])
        normal = tuple(-step[ax] if i == ax else 0 for i in range(3))
    while True:
        b = int(blocks[c[0] - lo[0], c[1] - lo[1], c[2]])
        if solid[b] and tuple(c) not in ignore:
            return Hit(HIT, tuple(c), normal, max(t, 0.0), b)
        ax = 0 if nxt[0] <= nxt[1] and nxt[0] <= nxt[2] else (1 if nxt[1] <= nxt[2] else 2)
        t = nxt[ax]
        if t > t_out:
            return None
        c[ax] += step[ax]
        if not lo[ax] <= c[ax] <= hi[ax]:
            return None
        nxt[ax] += delta[ax]
        normal = tuple(-step[ax] if i == ax else 0 for i in range(3))
