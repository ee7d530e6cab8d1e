"""Light atlas: the baked light of merged quads in a texture on a second UV set.

Per corner, not per face, to keep the smooth look of the vertex light (its
trilinear sample is the model's ambient occlusion): every unit-grid vertex of a
w×h quad gets one texel holding light.sample at that vertex (the value the
per-vertex mode gives a unit quad there), so the quad owns a (w+1)×(h+1) patch
and its UVs sit on the corner texel centres. Linear filtering then reads exactly
the vertex light at every unit-grid vertex and interpolates bilinearly between
them, with no quad split. A plant plane (lit by its own voxel) owns one texel.

Texels: RGB block light, A daylight, 0..1; row 0 is the bottom (v = 0, Blender's
pixel order). `face` keeps each texel's face code (EMPTY where unused) so the
light can be shaded for a time of day (shade).
"""
from __future__ import annotations

import math

import numpy as np

from .light import AXIS, SIGN, _grid_points, _tangents

EMPTY = 255


def sizes(q) -> tuple[np.ndarray, np.ndarray]:
    """Patch width and height (texels) of every quad."""
    cube = q["face"] < 6
    return (np.where(cube, q["w"].astype(np.int64) + 1, 1),
            np.where(cube, q["h"].astype(np.int64) + 1, 1))


def _pow2(n: int) -> int:
    return 1 << max(0, math.ceil(math.log2(max(int(n), 1))))


def pack(w: np.ndarray, h: np.ndarray) -> tuple[np.ndarray, np.ndarray, int, int]:
    """Shelf packing, tallest first: (x, y) of every patch and the atlas (W, H),
    both powers of two (the widest patch fits)."""
    if not len(w):
        return np.zeros(0, np.int64), np.zeros(0, np.int64), 1, 1
    total = int((w * h).sum())
    W = _pow2(max(int(w.max()), math.ceil(math.sqrt(total * 1.1))))
    order = np.lexsort((-w, -h))
    px = np.zeros(len(w), np.int64)
    py = np.zeros(len(w), np.int64)
    x = y = shelf = 0
    xs, ys = px.tolist(), py.tolist()  # plain lists: a Python loop over ints is fast
    for i, a, b in zip(order.tolist(), w[order].tolist(), h[order].tolist()):
        if x + a > W:
            y, x, shelf = y + shelf, 0, 0
        xs[i], ys[i] = x, y
        x += a
        shelf = max(shelf, b)
    px[:], py[:] = xs, ys
    return px, py, W, _pow2(y + shelf)


def fill(texels: np.ndarray, face: np.ndarray, q, px, py, light, offset) -> None:
    """Sample the light of quads `q` (window coordinates; `offset` = the window's
    origin in `light`) into their patches at (px, py)."""
    from ..light import sample
    off = np.asarray(offset, np.float32)
    cube = q["face"] < 6
    if cube.any():
        qc = q[cube]
        pts, owner, a, b = _grid_points(qc)
        f = qc["face"][owner]
        n = np.zeros((len(f), 3), np.float32)
        n[np.arange(len(f)), AXIS[f]] = SIGN[f]
        row, col = py[cube][owner] + b, px[cube][owner] + a
        texels[row, col] = sample(light, pts + off, n)
        face[row, col] = f
    if (~cube).any():
        qs = q[~cube]
        cell = np.stack([qs["x"], qs["y"], qs["z"]], 1).astype(np.float32) + 0.5
        row, col = py[~cube], px[~cube]
        texels[row, col] = sample(light, cell + off, np.zeros_like(cell))
        face[row, col] = qs["face"]


def uvs(q, local: np.ndarray, px, py, W: int, H: int) -> np.ndarray:
    """(4N, 2) second-UV-set coordinates of the quads' vertices (`local`: their
    window-coordinate positions, 4 per quad): corner texel centres."""
    n = len(q)
    f = np.repeat(q["face"], 4)
    base = np.repeat(np.stack([q["x"], q["y"], q["z"]], 1).astype(np.float32), 4, 0)
    axis, t1, t2 = _tangents(f)
    r = np.arange(4 * n)
    cube = f < 6
    a = np.where(cube, np.rint(local[r, t1] - base[r, t1]), 0)
    b = np.where(cube, np.rint(local[r, t2] - base[r, t2]), 0)
    u = (np.repeat(px, 4) + a + 0.5) / W
    v = (np.repeat(py, 4) + b + 0.5) / H
    return np.stack([u, v], 1).astype(np.float32)


def read(texels: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear lookup (texel centres at (i + 0.5) / size, as GPUs filter): the
    value a Linear image texture gives at `uv` (N, 2)."""
    H, W = texels.shape[:2]
    x = np.asarray(uv[:, 0], np.float64) * W - 0.5
    y = np.asarray(uv[:, 1], np.float64) * H - 0.5
    x0, y0 = np.floor(x).astype(np.int64), np.floor(y).astype(np.int64)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x1, y1 = np.clip(x0 + 1, 0, W - 1), np.clip(y0 + 1, 0, H - 1)
    x0, y0 = np.clip(x0, 0, W - 1), np.clip(y0, 0, H - 1)
    return ((1 - fy) * ((1 - fx) * texels[y0, x0] + fx * texels[y0, x1])
            + fy * ((1 - fx) * texels[y1, x0] + fx * texels[y1, x1]))


def shade(texels: np.ndarray, face: np.ndarray, hours: float) -> np.ndarray:
    """(H, W, 3) light factor of eq. 4.1 at `hours` per texel (white albedo, no glow),
    clipped to 0..1; unused texels 0."""
    from ..light import daytime, shade as eq41
    from ..meshing.mesh import NORMALS
    used = face != EMPTY
    t = texels[used]
    out = np.zeros(face.shape + (3,), np.float32)
    out[used] = eq41(np.ones((len(t), 3), np.float32), t[:, :3], np.zeros(len(t)), t[:, 3],
                     NORMALS[face[used]], daytime.at(hours))
    return np.clip(out, 0.0, 1.0)
