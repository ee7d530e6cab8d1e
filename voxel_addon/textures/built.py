"""Painters of the building materials that Minecraft imports need (issue 21): planks,
cobblestone, bricks, deepslate, … and `color`, the neutral tile of the coloured
block (its colour comes from the voxel's data). Same rules as paint.py."""
from __future__ import annotations

import numpy as np

from .paint import N, STONE, _xx, _yy, clear, fbm, hexes, no_glow, noise, put, ramp, rgba

PLANK = hexes("8a6a3e", "9d7a48", "af8a53", "bf9a60")
BRICK = hexes("7e3a2c", "8f4433", "a1503b", "b05c45")
MORTAR = hexes("a9a59c")[0]
DEEP = hexes("36363d", "404048", "4a4a52", "55555d")
GRAVEL = hexes("6d6866", "7f7a77", "928c88", "a49e99", "5a5654")
CLAY = hexes("8f95a3", "9aa0ae", "a4aab8")
SANDSTONE = hexes("c9b37a", "d4bf88", "dcc994", "e3d2a2")
OBSIDIAN = hexes("140f1f", "1e1530", "2a1d44", "3b2a5c")
LAVA = hexes("b8360a", "d9520f", "ef7a12", "fbab2a", "ffd75a")


def planks(rng):
    v = 0.6 * noise(rng, 16)[:, :1].repeat(N, 1).T + 0.4 * fbm(rng)
    rgb = ramp(v, PLANK)
    rgb[_yy % 4 == 3] = PLANK[0] * 0.75            # gaps between boards
    for row in range(4):                           # a butt joint per board
        x = (int(rng.integers(0, N)) + 8 * (row % 2)) % N
        rgb[4 * row:4 * row + 3, x] = PLANK[0] * 0.8
    return rgba(rgb), no_glow()


def cobblestone(rng):
    # cells around random seeds, dark mortar where two cells meet
    seeds = rng.random((9, 2)) * N
    d = [np.minimum(np.abs(_xx - sx), N - np.abs(_xx - sx)) ** 2
         + np.minimum(np.abs(_yy - sy), N - np.abs(_yy - sy)) ** 2 for sy, sx in seeds]
    d = np.sort(np.stack(d), 0)
    edge = np.sqrt(d[1]) - np.sqrt(d[0]) < 1.0
    rgb = ramp(0.5 * fbm(rng) + 0.5 * (1 - np.sqrt(d[0]) / 6).clip(0, 1), STONE)
    rgb[edge] = STONE[0] * 0.7
    return rgba(rgb), no_glow()


def stone_bricks(rng):
    rgb = ramp(0.7 * fbm(rng) + 0.3, STONE)
    rgb[(_yy % 8 == 7) | ((_xx + 8 * (_yy // 8)) % 16 == 15)] = STONE[0] * 0.65
    return rgba(rgb), no_glow()


def bricks(rng):
    rgb = ramp(fbm(rng), BRICK)
    rgb[(_yy % 4 == 3) | ((_xx + 4 * (_yy // 4 % 2)) % 8 == 7)] = MORTAR
    return rgba(rgb), no_glow()


def deepslate(rng):
    v = 0.5 * noise(rng, 8)[:1].repeat(N, 0) + 0.5 * fbm(rng)   # horizontal layering
    return rgba(ramp(v, DEEP)), no_glow()


def gravel(rng):
    return rgba(ramp(rng.random((N, N)) * 0.6 + 0.4 * fbm(rng), GRAVEL)), no_glow()


def clay(rng):
    return rgba(ramp(fbm(rng, amps=(0.5, 0.3, 0.1, 0.1)), CLAY)), no_glow()


def sandstone(rng):
    v = 0.6 * noise(rng, 4)[:, :1].repeat(N, 1) + 0.4 * fbm(rng)
    rgb = ramp(v, SANDSTONE)
    rgb[_yy % 16 == 0] = SANDSTONE[0] * 0.9
    return rgba(rgb), no_glow()


def obsidian(rng):
    v = fbm(rng)
    rgb = ramp(v ** 1.5, OBSIDIAN)
    glint = rng.random((N, N)) > 0.97
    rgb[glint] = hexes("6b4fa0")[0]
    return rgba(rgb), no_glow()


def lava(rng):
    v = 0.6 * fbm(rng) + 0.4 * (0.5 + 0.5 * np.sin((_xx + _yy + 4 * noise(rng, 2)) * np.pi / 5))
    rgb = ramp(v, LAVA)
    glow = np.clip(160 + 95 * v, 0, 255).astype(np.uint8)
    return rgba(rgb), glow


def torch(rng):
    img, glow = clear(), no_glow()
    for y in range(6, N):
        put(img, y, 7, hexes("6b4a2a")[0])
        put(img, y, 8, hexes("7d5832")[0])
    flame = hexes("ffd75a", "ffb12a", "ff7a12")
    for y, x, k in ((3, 7, 2), (3, 8, 1), (4, 7, 0), (4, 8, 0), (5, 7, 1), (5, 8, 0), (2, 8, 2)):
        put(img, y, x, flame[k])
        glow[y, x] = 255
    return img, glow


def color(rng):
    # near-white with a faint grain: the voxel's colour multiplies it
    return rgba(230 + 25 * fbm(rng)[..., None].repeat(3, 2)), no_glow()


PAINTERS = {"planks": planks, "cobblestone": cobblestone, "stone_bricks": stone_bricks,
            "bricks": bricks, "deepslate": deepslate, "gravel": gravel, "clay": clay,
            "sandstone": sandstone, "obsidian": obsidian, "lava": lava, "torch": torch,
            "color": color}
