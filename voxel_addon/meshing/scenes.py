"""The four reference scenes of thesis table 6.3 (ocean, desert, landscape, cave) as fixed
presets, shared by the meshing bench, tests and the renderer.

Each preset is a seed plus an area of chunks and a camera. `blocks(name)` builds the area
(+ a one-voxel ring) deterministically with a small NumPy terrain sketch, so the scenes do not
change when the Overworld generator is retuned; `blocks(name, source="overworld")` uses the
real generator instead when it exists.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.blocks import REGISTRY
from ..core.errors import VoxelError

SEA = 62


@dataclass(frozen=True)
class Scene:
    seed: int
    chunks: tuple[int, int, int, int]   # cx0, cy0, cx1, cy1 (half-open)
    camera: tuple[float, float, float, float, float]  # x, y, z, yaw, pitch (CLI `render`)
    time: str
    note: str


SCENES = {
    "ocean": Scene(11, (0, 0, 4, 4), (32, -8, 90, 90, -25), "10:00", "many transparent blocks"),
    "desert": Scene(22, (0, 0, 4, 4), (32, -8, 95, 90, -20), "14:00", "mostly cubes, no transparency"),
    "landscape": Scene(33, (0, 0, 4, 4), (32, -8, 100, 90, -25), "09:00",
                       "vegetation and leaves (alpha test), inner leaf faces drawn"),
    "cave": Scene(44, (0, 0, 4, 4), (23.5, 14.5, 46.5, 90, -8), "12:00",
                  "inside a cave lit by glowing mushrooms and ore, no transparency"),
}


def _smooth(rng, shape, cell):
    """Value noise: a random grid every `cell` voxels, bilinearly interpolated to shape."""
    gx, gy = shape[0] // cell + 2, shape[1] // cell + 2
    g = rng.random((gx, gy))
    x = np.arange(shape[0]) / cell
    y = np.arange(shape[1]) / cell
    i, j = x.astype(int), y.astype(int)
    fx, fy = (x - i)[:, None], (y - j)[None, :]
    fx, fy = fx * fx * (3 - 2 * fx), fy * fy * (3 - 2 * fy)
    a = g[i][:, j] * (1 - fx) + g[i + 1][:, j] * fx
    b = g[i][:, j + 1] * (1 - fx) + g[i + 1][:, j + 1] * fx
    return a * (1 - fy) + b * fy


def _heights(rng, shape, base, amp):
    n = _smooth(rng, shape, 32) * 0.6 + _smooth(rng, shape, 12) * 0.3 + _smooth(rng, shape, 5) * 0.1
    return (base + amp * (n - 0.5) * 2).astype(int)


def _column_fill(shape, top, fill, surface):
    b = np.zeros(shape + (256,), np.uint16, order="F")
    z = np.arange(256)[None, None, :]
    b[z <= top[..., None]] = REGISTRY.id(fill)
    b[z == top[..., None]] = REGISTRY.id(surface)
    return b


def _sketch(name: str, scene: Scene) -> np.ndarray:
    cx0, cy0, cx1, cy1 = scene.chunks
    shape = (16 * (cx1 - cx0) + 2, 16 * (cy1 - cy0) + 2)
    rng = np.random.default_rng(scene.seed)
    R = REGISTRY.id
    z = np.arange(256)[None, None, :]
    if name == "ocean":
        top = _heights(rng, shape, 52, 14)
        b = _column_fill(shape, top, "stone", "sand")
        b[(z > top[..., None]) & (z <= SEA)] = R("water")
        return b
    if name == "desert":
        top = _heights(rng, shape, 70, 10)
        b = _column_fill(shape, top, "stone", "sand")
        for k in range(1, 4):
            b[z == (top - k)[..., None]] = R("sand")
        xs, ys = np.nonzero(rng.random(shape) < 0.004)
        for x, y in zip(xs, ys):
            b[x, y, top[x, y] + 1:top[x, y] + 4] = R("cactus")
        return b
    if name == "landscape":
        top = _heights(rng, shape, 68, 12)
        b = _column_fill(shape, top, "stone", "grass")
        for k in range(1, 4):
            b[z == (top - k)[..., None]] = R("dirt")
        b[(z > top[..., None]) & (z <= SEA)] = R("water")
        dry = top > SEA
        veg = rng.random(shape)
        for kind, lo, hi in (("tall_grass", 0, 0.12), ("flowers", 0.12, 0.15), ("wheat", 0.15, 0.17)):
            xs, ys = np.nonzero(dry & (veg >= lo) & (veg < hi))
            b[xs, ys, top[xs, ys] + 1] = R(kind)
        xs, ys = np.nonzero(dry & (rng.random(shape) < 0.006))
        for x, y in zip(xs, ys):
            t = top[x, y]
            h = 4 + (x * 7 + y * 3) % 3
            b[max(x - 2, 0):x + 3, max(y - 2, 0):y + 3, t + h - 1:t + h + 2] = R("leaves")
            b[max(x - 1, 0):x + 2, max(y - 1, 0):y + 2, t + h + 2] = R("leaves")
            b[x, y, t + 1:t + h + 1] = R("log")
        return b
    if name == "cave":
        top = _heights(rng, shape, 75, 8)
        b = _column_fill(shape, top, "stone", "grass")
        # caves: two smooth 2D fields per 8-layer band, carved where both are near 0.5
        for z0 in range(8, 64, 6):
            f = _smooth(rng, shape, 10)
            g = _smooth(rng, shape, 14)
            hole = (np.abs(f - 0.5) < 0.08) | (np.abs(g - 0.5) < 0.05)
            b[hole, z0:z0 + 5] = 0
        stone = b[:, :, :60] == R("stone")
        ore = rng.random(stone.shape) < 0.01
        b[:, :, :60][stone & ore] = R("ore")
        # glowing mushrooms on cave floors light the render preset's view (§6 cave scene)
        floor = (b[:, :, :63] == R("stone")) & (b[:, :, 1:64] == 0)
        xs, ys, zs = np.nonzero(floor & (rng.random(floor.shape) < 0.06))
        b[xs, ys, zs + 1] = R("glowing_mushroom")
        return b
    raise VoxelError(f"unknown scene {name!r} (known: {', '.join(SCENES)})")


def blocks(name: str, source: str = "sketch") -> np.ndarray:
    """The scene's area plus a one-voxel ring: (16*nx + 2, 16*ny + 2, 256) uint16."""
    if name not in SCENES:
        raise VoxelError(f"unknown scene {name!r} (known: {', '.join(SCENES)})")
    scene = SCENES[name]
    if source == "sketch":
        return _sketch(name, scene)
    from ..generation import make_generator
    gen = make_generator(source, scene.seed)
    cx0, cy0, cx1, cy1 = scene.chunks
    keys = [(cx, cy) for cy in range(cy0 - 1, cy1 + 1) for cx in range(cx0 - 1, cx1 + 1)]
    arrs = gen.generate(keys)
    nx, ny = cx1 - cx0 + 2, cy1 - cy0 + 2
    full = np.zeros((16 * nx, 16 * ny, 256), np.uint16, order="F")
    for (cx, cy), a in zip(keys, arrs):
        full[16 * (cx - cx0 + 1):16 * (cx - cx0 + 2), 16 * (cy - cy0 + 1):16 * (cy - cy0 + 2)] = a
    return np.asfortranarray(full[15:-15, 15:-15])


def chunk_windows(area: np.ndarray):
    """Yield ((i, j), (18, 18, 256) window) for every chunk of a scene area."""
    nx, ny = (area.shape[0] - 2) // 16, (area.shape[1] - 2) // 16
    for j in range(ny):
        for i in range(nx):
            yield (i, j), area[16 * i:16 * i + 18, 16 * j:16 * j + 18]
