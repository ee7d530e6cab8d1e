"""Synthetic generated-like terrain for light tests and the light bench.

Hills, caves with entrances, a sea with water, trees (log + leaves), ore and glowing
mushrooms — every light-relevant block class — from a seed, in NumPy only, so the
light code can be exercised without waiting for the Overworld generator. Columns are
a function of world (x, y) so windows of one terrain agree where they overlap.
"""
from __future__ import annotations

import numpy as np

from ..core import chunk
from ..core.blocks import REGISTRY as R


def terrain(w: int, h: int, seed: int = 0, x0: int = 0, y0: int = 0) -> np.ndarray:
    """(w, h, 256) uint16 Fortran block array of the terrain at world origin (x0, y0)."""
    rng = np.random.default_rng(seed)
    x = (np.arange(w) + x0)[:, None, None].astype(np.float32)
    y = (np.arange(h) + y0)[None, :, None].astype(np.float32)
    z = np.arange(chunk.HEIGHT)[None, None, :].astype(np.float32)

    def waves(n, scale, *axes):
        f = 0.0
        for _ in range(n):
            k = rng.uniform(0.5, 1.5, len(axes)) / scale
            p = rng.uniform(0, 2 * np.pi, len(axes))
            t = 1.0
            for a, kk, pp in zip(axes, k, p):
                t = t * np.sin(a * kk + pp)
            f = f + t
        return f / n

    hgt = (64 + 22 * waves(4, 18.0, x[..., 0], y[..., 0])
           + 5 * waves(3, 5.0, x[..., 0], y[..., 0])).astype(np.int32)[..., None]
    b = np.where(z < hgt - 4, R.id("stone"), 0).astype(np.uint16)
    b[(z >= hgt - 4) & (z < hgt - 1)] = R.id("dirt")
    b[z == hgt - 1] = R.id("grass")
    sea = 60
    b[(z >= hgt) & (z < sea)] = R.id("water")
    b[(z == hgt - 1) & (hgt <= sea + 1)] = R.id("sand")
    cave = np.abs(waves(3, 9.0, x, y, z)) < 0.06
    cave &= (z > 4) & (z < hgt - 1 + 3 * (waves(2, 20.0, x, y, z) > 0.2))
    b[cave] = 0
    solid = b == R.id("stone")
    cell = rng.random(b.shape)
    b[solid & (cell < 0.01) & (z < 50)] = R.id("ore")
    below = np.zeros_like(solid)
    below[..., 1:] = solid[..., :-1]
    b[(b == 0) & below & (cell < 0.02) & (z < hgt - 6)] = R.id("glowing_mushroom")
    # Trees on a grid of world coordinates: log of 5, a leaf ball above.
    xi, yi = (np.arange(w) + x0), (np.arange(h) + y0)
    for tx in xi[(xi % 11) == 3]:
        for ty in yi[(yi % 13) == 5]:
            i, j = tx - x0, ty - y0
            g = int(hgt[i, j, 0])
            if g <= sea + 1 or g + 9 >= chunk.HEIGHT:
                continue
            lo_x, hi_x, lo_y, hi_y = max(i - 2, 0), min(i + 3, w), max(j - 2, 0), min(j + 3, h)
            crown = b[lo_x:hi_x, lo_y:hi_y, g + 3:g + 8]
            crown[crown == 0] = R.id("leaves")
            b[i, j, g:g + 6] = R.id("log")
    return np.asfortranarray(b)
