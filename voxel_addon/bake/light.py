"""Splitting merged quads where the baked per-vertex light varies.

A vertex's light is light.sample at the vertex (half a voxel along the normal,
trilinear): the mean of the four voxels in front of the face around that corner,
dark solids included (the model's natural ambient occlusion). Bilinear interpolation
across a merged quad is only right when every unit-grid vertex inside it samples
the same, so other merged quads are cut back into unit quads.
"""
from __future__ import annotations

import numpy as np

# face code -> (axis, sign, tangents): X (6, 7) and # (8..11) planes sample like their sides
from ..meshing.mesh import AXIS, SIGN, T1, T2


def split_uneven(quads, light: np.ndarray, offset) -> np.ndarray:
    """Split merged quads whose vertex light is not constant into unit quads, so the
    baked per-vertex light is exact on every unit face (flat lit areas stay merged).

    `quads`: meshing.QUAD array in window coordinates; `light`: packed light array;
    `offset` = position of the window's (0, 0, 0) in `light`'s coordinates."""
    from ..light import sample
    q = quads
    big = (q["w"] > 1) | (q["h"] > 1)
    if not big.any():
        return q
    corners, owner, _, _ = _grid_points(q[big])
    face = q["face"][big][owner]
    n = np.zeros((len(face), 3), np.float32)
    n[np.arange(len(face)), AXIS[face]] = SIGN[face]
    s = sample(light, corners + np.asarray(offset, np.float32), n)
    lo = np.full((big.sum(), 4), np.inf, np.float32)
    hi = np.full((big.sum(), 4), -np.inf, np.float32)
    np.minimum.at(lo, owner, s)
    np.maximum.at(hi, owner, s)
    uneven = np.zeros(len(q), bool)
    uneven[np.flatnonzero(big)] = (hi - lo).max(1) > 1e-4
    if not uneven.any():
        return q
    return np.concatenate([q[~uneven], _unit(q[uneven])])


def _tangents(face):
    return AXIS[face], T1[face], T2[face]


def _grid_points(q):
    """Every unit-grid vertex of every quad (on its plane), the quad it belongs to
    and its grid index (a along t1, b along t2; a runs fastest)."""
    w, h = q["w"].astype(np.int64), q["h"].astype(np.int64)
    cnt = (w + 1) * (h + 1)
    owner = np.repeat(np.arange(len(q)), cnt)
    k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    a, b = k % (w[owner] + 1), k // (w[owner] + 1)
    base = np.stack([q["x"], q["y"], q["z"]], 1).astype(np.float32)[owner]
    axis, t1, t2 = _tangents(q["face"][owner])
    r = np.arange(len(owner))
    base[r, t1] += a
    base[r, t2] += b
    base[r, axis] += (SIGN[q["face"][owner]] > 0)  # +a faces lie on the far side
    return base, owner, a, b


def _unit(q):
    """Cut quads into 1×1 quads (same block, face, layer)."""
    w, h = q["w"].astype(np.int64), q["h"].astype(np.int64)
    cnt = w * h
    owner = np.repeat(np.arange(len(q)), cnt)
    k = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    a, b = k % w[owner], k // w[owner]
    out = q[owner].copy()
    axis, t1, t2 = _tangents(out["face"])
    pos = np.stack([out["x"], out["y"], out["z"]], 1).astype(np.int64)
    r = np.arange(len(out))
    pos[r, t1] += a
    pos[r, t2] += b
    out["x"], out["y"], out["z"] = pos[:, 0], pos[:, 1], pos[:, 2]
    out["w"] = 1
    out["h"] = 1
    return out
