"""The world's colour palette: the `color` block's small data is an index into it.

Kept in the world file's meta as `colors`, a JSON list of "rrggbb" strings; index 0
is white so a `color` voxel without data is white. Exact colours (not RGB565), so a
.vox keeps its colours through import and export. Up to 65,536 entries.
"""
from __future__ import annotations

import json

import numpy as np

from .errors import VoxelError

KEY = "colors"
LIMIT = 1 << 16


def parse(meta: dict) -> np.ndarray:
    """(n, 3) uint8 palette of a world's meta (white alone when it has none)."""
    raw = meta.get(KEY)
    if not raw:
        return np.array([[255, 255, 255]], np.uint8)
    try:
        items = json.loads(raw)
        out = np.array([[int(c[i:i + 2], 16) for i in (0, 2, 4)] for c in items], np.uint8)
    except (ValueError, TypeError, IndexError):
        raise VoxelError("the world's colour palette (meta 'colors') is damaged") from None
    if out.ndim != 2 or not 1 <= len(out) <= LIMIT:
        raise VoxelError("the world's colour palette (meta 'colors') is damaged")
    return out


def dump(palette) -> str:
    return json.dumps(["%02x%02x%02x" % tuple(int(v) for v in c) for c in palette])


def add(palette: np.ndarray, rgb) -> tuple[np.ndarray, np.ndarray]:
    """(new palette, index of each colour of `rgb` (k, 3)): known colours keep their
    index, new ones are appended."""
    rgb = np.asarray(rgb, np.uint8).reshape(-1, 3)
    code = lambda a: (a[:, 0].astype(np.int64) << 16) | (a[:, 1].astype(np.int64) << 8) | a[:, 2]
    have = {int(c): i for i, c in enumerate(code(palette))}
    out = list(palette)
    idx = np.empty(len(rgb), np.int64)
    for i, c in enumerate(code(rgb).tolist()):
        j = have.get(c)
        if j is None:
            j = have[c] = len(out)
            out.append(rgb[i])
        idx[i] = j
    if len(out) > LIMIT:
        raise VoxelError(f"a world holds at most {LIMIT} colours")
    return np.array(out, np.uint8).reshape(-1, 3), idx
