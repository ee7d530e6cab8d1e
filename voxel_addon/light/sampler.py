"""Light sampling (thesis §4.3, fig. 4.4-4.6) and eq. 4.1 shading, in NumPy.

`sample` is the reference for shaders/include/light.glsl (light_sample): offset the
surface point half a voxel along the face normal, then interpolate trilinearly
between the 8 nearest voxel centres (centre of voxel (x, y, z) is (x+.5, y+.5, z+.5)),
per component. Indices outside the array clamp to its edge. Result: float32 (N, 4)
R, G, B, D in 0..1 (level / 15). The offset is what gives the model its natural
ambient occlusion: in a concave corner the offset point still sits next to the dark
centres of the two solid blocks.
"""
from __future__ import annotations

import numpy as np

from . import model


def sample(light: np.ndarray, points, normals, origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """light: packed (W, H, Z) array whose voxel [0, 0, 0] sits at world `origin`;
    points, normals: (N, 3) world coordinates -> (N, 4) float32 in 0..1."""
    lanes = model.unpack(light).astype(np.float32) / model.MAX  # (W, H, Z, 4)
    q = (np.asarray(points, np.float64) + 0.5 * np.asarray(normals, np.float64)
         - np.asarray(origin, np.float64) - 0.5)
    i0 = np.floor(q).astype(np.int64)
    f = (q - i0).astype(np.float32)
    hi = np.array(light.shape) - 1
    out = np.zeros((len(q), 4), np.float32)
    for dx in (0, 1):
        for dy in (0, 1):
            for dz in (0, 1):
                i = np.clip(i0 + (dx, dy, dz), 0, hi)
                w = (np.where(dx, f[:, 0], 1 - f[:, 0]) * np.where(dy, f[:, 1], 1 - f[:, 1])
                     * np.where(dz, f[:, 2], 1 - f[:, 2]))
                out += w[:, None] * lanes[i[:, 0], i[:, 1], i[:, 2]]
    return out


def shade(albedo, light_rgb, glow, day, normal, params) -> np.ndarray:
    """Eq. 4.1: albedo * ((rgb + glow)(1 - u*day) + day*(ambient + max(0, n.l)*direct)).

    light_rgb (N, 3) and day (N,) in 0..1 as `sample` returns; glow (N,) 0..1;
    params: a daytime.DayParams (its light_dir is the sun by day, the moon by night)."""
    albedo = np.asarray(albedo, np.float32)
    day = np.asarray(day, np.float32)[..., None]
    glow = np.asarray(glow, np.float32)[..., None]
    ndl = np.maximum(0.0, np.asarray(normal, np.float32) @ np.asarray(params.light_dir, np.float32))
    sky = np.asarray(params.ambient, np.float32) + ndl[..., None] * np.asarray(params.direct, np.float32)
    return albedo * ((np.asarray(light_rgb, np.float32) + glow) * (1.0 - params.u * day) + day * sky)
