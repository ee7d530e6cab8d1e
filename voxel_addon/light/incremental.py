"""Incremental relight after one block edit (issue 4 §2); equals a full `solve`.

Why the box is enough: only the start values of the edited voxel p and of its column
below p can change, and a changed value travels at most 14 steps. So light can only
change within horizontal distance 14 of column (x, y) and between 14 below the lowest
changed start value and 14 above p. Everything outside that box is the old (exact)
light, so the box is re-solved from scratch with its 1-voxel rim held fixed: a path
from outside enters the box through the rim, whose values already account for it.
"""
from __future__ import annotations

import numpy as np

from ..core import chunk
from . import model

R = model.MAX - 1  # reach of a change


def _column_day(col: np.ndarray) -> np.ndarray:
    _, att, opaque, _, _, _ = model.tables()
    a = att[col].astype(np.int16)[::-1]
    blocked = np.maximum.accumulate(opaque[col][::-1]).astype(bool)
    return np.where(blocked, 0, np.clip(model.MAX - np.cumsum(a), 0, model.MAX))[::-1]


def update(blocks: np.ndarray, light: np.ndarray, x: int, y: int, z: int, old: int):
    """Fix `light` (the exact `solve` of the array before the edit) in place after
    blocks[x, y, z] changed from block id `old` to its current value.

    Returns the modified box as slices (sx, sy, sz) of the array."""
    new = int(blocks[x, y, z])
    w, h, zs = blocks.shape
    col = np.array(blocks[x, y, :z + 1])
    now = _column_day(np.append(col, blocks[x, y, z + 1:]))[:z + 1]
    col[z] = old
    before = _column_day(np.append(col, blocks[x, y, z + 1:]))[:z + 1]
    diff = np.flatnonzero(now != before)
    zc = int(diff[0]) if diff.size else z
    if old == new:
        return (slice(x, x), slice(y, y), slice(z, z))
    sx = slice(max(x - R, 0), min(x + R + 1, w))
    sy = slice(max(y - R, 0), min(y + R + 1, h))
    sz = slice(max(zc - R, 0), min(z + R + 1, zs))
    # Start values of the box: emission and the column pass (carry from the top).
    above = np.flatnonzero(blocks[sx, sy, sz.stop:].any(axis=(0, 1)))
    top = sz.stop + (int(above[-1]) + 1 if above.size else 0)
    lanes = model.start(blocks[sx, sy, sz.start:top].T)[:sz.stop - sz.start]
    # Padded with the fixed rim from the current light (0 outside the array).
    ex = slice(max(sx.start - 1, 0), min(sx.stop + 1, w))
    ey = slice(max(sy.start - 1, 0), min(sy.stop + 1, h))
    ez = slice(max(sz.start - 1, 0), min(sz.stop + 1, zs))
    p = np.zeros((sz.stop - sz.start + 2, sy.stop - sy.start + 2, sx.stop - sx.start + 2, 4),
                 np.uint8)
    ox, oy, oz = 1 - (sx.start - ex.start), 1 - (sy.start - ey.start), 1 - (sz.start - ez.start)
    p[oz:oz + ez.stop - ez.start, oy:oy + ey.stop - ey.start, ox:ox + ex.stop - ex.start] = \
        model.unpack(light[ex, ey, ez].T)
    p[1:-1, 1:-1, 1:-1] = lanes
    model.relax_padded(p, model.tables()[0][blocks[sx, sy, sz].T])
    light[sx, sy, sz] = model.pack(p[1:-1, 1:-1, 1:-1]).T
    return sx, sy, sz


def edit(blocks: np.ndarray, light: np.ndarray, x: int, y: int, z: int, block: int):
    """Set blocks[x, y, z] = block and relight incrementally; returns the changed box."""
    chunk.check_z(z)
    old = int(blocks[x, y, z])
    blocks[x, y, z] = block
    return update(blocks, light, x, y, z, old)
