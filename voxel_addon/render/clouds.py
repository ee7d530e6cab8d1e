"""NumPy twin of the sky's noise and cloud cover (shaders/include/noise.glsl, clouds.glsl):
the reference tests/render/test_clouds.py compares the shader with. The noise is the
generators' (generation.noise: lowbias32 hash, Perlin's fade and 2D gradients), with
the corner gradients taken from the hash instead of a permutation table."""
from __future__ import annotations

import numpy as np

from ..generation import noise as N

SCALE = 420.0          # clouds.glsl's CLOUD_SCALE
SEED = 0x2545F491      # CLOUD_SEED
ROT = np.array([[0.8, -0.6], [0.6, 0.8]])  # noise.glsl's per-octave rotation (mat2 columns)


def gnoise2(x, y, s: int):
    """Gradient noise of float arrays x, y with seed s (noise.glsl's gnoise2)."""
    x, y = np.asarray(x, np.float64), np.asarray(y, np.float64)
    ix, iy = np.floor(x), np.floor(y)
    fx, fy = x - ix, y - iy
    cx, cy = ix.astype(np.int64), iy.astype(np.int64)
    fade = lambda t: t * t * t * (t * (t * 6.0 - 15.0) + 10.0)  # noqa: E731
    u, v = fade(fx), fade(fy)

    def corner(dx, dy):
        h = N.hash2((cx + dx).astype(np.int32), (cy + dy).astype(np.int32), s & 0xFFFFFFFF)
        return N.grad2(h, fx - dx, fy - dy)
    n00, n10, n01, n11 = corner(0, 0), corner(1, 0), corner(0, 1), corner(1, 1)
    return (n00 + (n10 - n00) * u) * (1 - v) + (n01 + (n11 - n01) * u) * v


def fbm2(x, y, s: int, n: int):
    """Octaves of gnoise2: lacunarity 2, gain 0.5 from 0.5, rotated by ROT each octave."""
    total, a = 0.0, 0.5
    p = np.stack([np.asarray(x, np.float64), np.asarray(y, np.float64)])
    for o in range(n):
        total = total + a * gnoise2(p[0], p[1], s + o)
        p = np.tensordot(ROT, p, 1) * 2.0
        a *= 0.5
    return total


def density(x, y, cover: float, drift=(0.0, 0.0), n: int = 5):
    """Cloud cover 0..1 at world (x, y) (clouds.glsl's cloud_density)."""
    dx, dy = drift
    px, py = (np.asarray(x) + dx) / SCALE, (np.asarray(y) + dy) / SCALE
    qx = (np.asarray(x) + dx * 0.6 - dy * 0.25) / (SCALE * 0.45)
    qy = (np.asarray(y) + dy * 0.6 + dx * 0.25) / (SCALE * 0.45)
    f = fbm2(px, py, SEED, n) + 0.3 * fbm2(qx, qy, SEED + 16, max(n - 3, 1))
    t = 0.35 + (-0.4 - 0.35) * cover
    k = np.clip((f - t) / 0.25, 0.0, 1.0)
    return k * k * (3.0 - 2.0 * k)
