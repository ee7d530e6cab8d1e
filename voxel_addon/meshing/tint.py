"""Coloured voxels (the `color` block, issue 21): its colour is the voxel's small data
(an index into the world's palette, core.colors), so two faces of it may only merge
when their colours agree. The mesher merges by block id; `split` then cuts each
`color` rect into strips of one colour (runs along its first tangent, one row high)
and gives every rect a `color` column (0 for other blocks). Works on the rect columns
of either backend, so NumPy and OpenCL stay equal."""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY
from .mesh import T1, T2

COLOR = REGISTRY.id("color")


def split(r: dict, data, tile: tuple, nx: int) -> dict:
    """Rect columns `r` (faces.COLS, tile-local) of area P with small data `data`
    (P's shape: the window plus its ring, or None) -> the same columns plus `color`,
    `color` rects cut into single-colour strips."""
    n = len(r["t"])
    sel = (r["block"] == COLOR) if data is not None else np.zeros(n, bool)
    if not sel.any():
        return {**r, "color": np.zeros(n, np.uint16)}
    keep = {c: v[~sel] for c, v in r.items()}
    keep["color"] = np.zeros(len(keep["t"]), np.uint16)
    c = {k: v[sel].astype(np.int64) for k, v in r.items()}
    w, h = c["w"], c["h"]
    cells = w * h
    idx = np.repeat(np.arange(len(w)), cells)
    k = np.arange(cells.sum()) - np.repeat(np.cumsum(cells) - cells, cells)
    i, j = k % w[idx], k // w[idx]
    face = c["face"][idx]
    t1, t2 = T1[face], T2[face]
    # window position of each cell: tile origin + ring + rect origin + i t1 + j t2
    pos = np.stack([c["x"][idx], c["y"][idx], c["z"][idx]], 1)
    pos[:, 0] += tile[0] * (c["t"][idx] % nx) + 1
    pos[:, 1] += tile[1] * (c["t"][idx] // nx) + 1
    rows = np.arange(len(idx))
    pos[rows, t1] += i
    pos[rows, t2] += j
    col = np.asarray(data)[pos[:, 0], pos[:, 1], pos[:, 2]].astype(np.int64)
    # a strip starts at each row start and wherever the colour changes along the row
    start = (i == 0) | np.r_[True, col[1:] != col[:-1]]
    s = np.flatnonzero(start)
    length = np.diff(np.r_[s, len(idx)])
    out = {key: v[idx[s]].astype(r[key].dtype) for key, v in c.items()}
    base = np.stack([c["x"], c["y"], c["z"]], 1)[idx[s]]
    base[np.arange(len(s)), t1[s]] += i[s]
    base[np.arange(len(s)), t2[s]] += j[s]
    for a, name in enumerate("xyz"):
        out[name] = base[:, a].astype(r[name].dtype)
    out["w"] = length.astype(r["w"].dtype)
    out["h"] = np.ones(len(s), r["h"].dtype)
    out["color"] = col[s].astype(np.uint16)
    return {key: np.concatenate([keep[key], out[key]]) for key in keep}
