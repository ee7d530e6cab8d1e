"""The test pack's textures: 16×16 patterns drawn by code (seeded, so every run writes
the same pixels), enough like the game's that a picture reads as Minecraft: planks
with grain and seams, cobbled stone, grey grass and leaves for the biome tint, leaves
with holes (cutout), glass with a frame (translucent), a torch, a poppy, a door, a
rail. None is symmetric, so a test can tell which way up a face shows one."""
from __future__ import annotations

import numpy as np


def _rgba(rgb, alpha=255) -> np.ndarray:
    a = np.empty((*rgb.shape[:2], 4), np.uint8)
    a[..., :3] = np.clip(rgb, 0, 255)
    a[..., 3] = alpha
    return a


def _noise(seed: int, amp: float) -> np.ndarray:
    return np.random.default_rng(seed).normal(0, amp, (16, 16, 1))


def stone(seed=1) -> np.ndarray:
    """Grey with darker cracks around lighter lumps."""
    rng = np.random.default_rng(seed)
    base = np.full((16, 16, 3), 125.0) + _noise(seed, 7)
    for _ in range(7):                      # lumps
        y, x, r = rng.integers(0, 16), rng.integers(0, 16), rng.integers(2, 4)
        yy, xx = np.mgrid[0:16, 0:16]
        d = np.hypot((yy - y + 8) % 16 - 8, (xx - x + 8) % 16 - 8)
        base[d < r] += 14
        base[(d >= r) & (d < r + 0.9)] -= 15
    return _rgba(base)


def planks(rgb=(162, 130, 78), seed=2) -> np.ndarray:
    """Four boards of four rows: a dark seam under each, grain along them, the
    boards' ends staggered."""
    rng = np.random.default_rng(seed)
    a = np.tile(np.asarray(rgb, float), (16, 16, 1)) + _noise(seed, 4)
    for row in range(16):
        a[row, rng.integers(0, 16, 3)] -= 18            # grain
    for b in range(4):
        a[4 * b + 3] -= 40                              # the seam under a board
        end = (5 + 7 * b) % 16
        a[4 * b:4 * b + 3, end] -= 35                   # where two boards meet
    return _rgba(a)


def dirt(seed=3) -> np.ndarray:
    a = np.tile(np.array([134.0, 96, 67]), (16, 16, 1)) + _noise(seed, 10)
    rng = np.random.default_rng(seed)
    for _ in range(10):
        a[rng.integers(0, 16), rng.integers(0, 16)] = (98, 70, 48)
    return _rgba(a)


def grass_top(seed=4) -> np.ndarray:
    """Grey: the biome's grass colour multiplies it."""
    return _rgba(np.full((16, 16, 3), 165.0) + _noise(seed, 14))


def grass_side(seed=5) -> np.ndarray:
    """Dirt: the tinted overlay lays the grass over its top rows."""
    return dirt(seed)


def grass_overlay(seed=6) -> np.ndarray:
    """A grey fringe over the top rows, ragged below; clear elsewhere (cutout)."""
    rng = np.random.default_rng(seed)
    a = _rgba(np.full((16, 16, 3), 160.0) + _noise(seed, 12), 0)
    for col, depth in enumerate(rng.integers(2, 6, 16)):
        a[:depth, col, 3] = 255
    return a


def leaves(seed=7) -> np.ndarray:
    """Grey leaves (the foliage colour multiplies them) with holes."""
    rng = np.random.default_rng(seed)
    a = _rgba(np.full((16, 16, 3), 150.0) + _noise(seed, 22))
    a[rng.random((16, 16)) < 0.12, 3] = 0
    return a


def glass() -> np.ndarray:
    """A light frame and a few streaks, almost clear inside (translucent)."""
    a = _rgba(np.full((16, 16, 3), (215.0, 235, 245)), 40)
    a[[0, 15], :, 3] = a[:, [0, 15], 3] = 230
    a[[0, 15], :, :3] = a[:, [0, 15], :3] = (175, 205, 220)
    for i in range(3):                  # streaks from the top-left
        a[2 + i, 3 + i, 3] = a[3 + i, 3 + i, 3] = 150
    a[10, 11, 3] = a[11, 12, 3] = 150
    return a


def pane_top() -> np.ndarray:
    """A pane's edge: the frame's colour."""
    return _rgba(np.full((16, 16, 3), (175.0, 205, 220)) + _noise(8, 5), 230)


def torch() -> np.ndarray:
    """A stick in columns 7..8 below a flame (cutout)."""
    a = np.zeros((16, 16, 4), np.uint8)
    a[8:16, 7:9] = (110, 80, 45, 255)
    a[6:8, 7:9] = (255, 210, 60, 255)
    a[6, 7] = (255, 250, 180, 255)
    return a


def poppy() -> np.ndarray:
    """A stem, two leaves and a red bloom (cutout)."""
    a = np.zeros((16, 16, 4), np.uint8)
    a[7:16, 7:9] = (40, 110, 30, 255)
    a[11, 4:7] = a[10, 9:12] = (50, 130, 35, 255)
    yy, xx = np.mgrid[0:16, 0:16]
    bloom = np.hypot(yy - 5.0, (xx - 7.5) * 0.8) < 5.0
    a[bloom] = (220, 30, 30, 255)
    a[4:6, 7:9] = (90, 25, 20, 255)
    return a


def door(top: bool) -> np.ndarray:
    """Planks standing up; the top half has a four-pane window (holes: cutout)."""
    a = planks((150, 115, 65), seed=9).transpose(1, 0, 2).copy()
    a[:, [0, 15], :3] = (95, 70, 40)
    if top:
        a[3:8, 3:7, 3] = a[3:8, 9:13, 3] = a[9:14, 3:7, 3] = a[9:14, 9:13, 3] = 0
    else:
        a[[0, 15], :, :3] = (95, 70, 40)
        a[8, 12:14, :3] = (60, 60, 60)                  # the handle
    return a


def rail() -> np.ndarray:
    """Two iron rails on wooden ties, clear between them (cutout)."""
    a = np.zeros((16, 16, 4), np.uint8)
    for row in range(1, 16, 4):
        a[row:row + 2, 1:15] = (110, 85, 55, 255)
    a[:, 2:4] = a[:, 12:14] = (150, 150, 155, 255)
    a[:, 3] = a[:, 13] = (105, 105, 110, 255)
    return a


def mirrored(a: np.ndarray) -> np.ndarray:
    return a[:, ::-1].copy()


def all_textures() -> dict[str, np.ndarray]:
    s = stone()
    return {"stone": s, "stone_mirrored": mirrored(s), "oak_planks": planks(), "dirt": dirt(),
            "grass_block_top": grass_top(), "grass_block_side": grass_side(),
            "grass_block_side_overlay": grass_overlay(), "oak_leaves": leaves(),
            "glass": glass(), "glass_pane_top": pane_top(), "torch": torch(),
            "poppy": poppy(), "oak_door_top": door(True), "oak_door_bottom": door(False),
            "rail": rail()}
