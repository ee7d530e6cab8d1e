"""Top-down pictures of block regions and of biome factors (the `map` command and
the bench). Pure NumPy: arrays in, (H, W, 3) uint8 RGB out, north (+y) up."""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY

# Map colour per block name (an overview palette, not the textures).
PALETTE = {
    "stone": (125, 125, 125), "dirt": (134, 96, 67), "grass": (95, 159, 53),
    "snow": (240, 245, 250), "sand": (219, 207, 142), "ore": (190, 120, 60),
    "log": (102, 81, 50), "leaves": (48, 110, 30), "flowers": (220, 80, 140),
    "tall_grass": (85, 150, 48), "wheat": (200, 180, 70), "mushroom": (180, 60, 50),
    "glowing_mushroom": (80, 160, 255), "cactus": (60, 130, 40), "glass": (200, 230, 240),
    "water": (40, 90, 200),
}


def palette() -> np.ndarray:
    pal = np.zeros((len(REGISTRY), 3), np.float32)
    for i, n in enumerate(REGISTRY.names()):
        pal[i] = PALETTE.get(n, (255, 200, 60) if n.startswith("lamp") else (255, 0, 255))
    return pal


def surface(blocks: np.ndarray):
    """(W, H, 256) ids -> (top id, its z) per column; top = highest non-air block."""
    solid = blocks != 0
    z = blocks.shape[2] - 1 - np.argmax(solid[:, :, ::-1], axis=2)
    z = np.where(solid.any(axis=2), z, 0)
    top = np.take_along_axis(blocks, z[:, :, None], axis=2)[:, :, 0]
    return top, z


# Not terrain: ignored for the relief, so forests and lakes do not hide the hills.
NOT_GROUND = ("water", "leaves", "log", "flowers", "tall_grass", "wheat", "mushroom",
              "glowing_mushroom", "cactus")


def summary(blocks: np.ndarray):
    """(top id, top z, ground z) per column of a (W, H, 256) array; ground is the
    highest terrain block (under water, trees and plants)."""
    top, z = surface(blocks)
    skip = np.zeros(len(REGISTRY), bool)
    skip[[REGISTRY.id(n) for n in NOT_GROUND if n in REGISTRY.names()]] = True
    ground = np.where(skip[blocks], 0, blocks)
    return top, z, surface(ground)[1]


def terrain_rgb(blocks: np.ndarray, sea: int = 62) -> np.ndarray:
    """Colour of the top block, hill-shaded, water tinted by depth."""
    return shade(*summary(blocks), sea=sea)


def hillshade(h: np.ndarray, exaggerate: float = 1.5) -> np.ndarray:
    """Lambert shading of a height field [x, y] lit from the north-west, 1 on flat
    ground, brighter on slopes facing the light, darker on the others."""
    dx, dy = np.gradient(h.astype(np.float32) * exaggerate)
    light = np.array([-1.0, 1.0, 1.4], np.float32)
    light /= np.linalg.norm(light)
    lam = (-dx * light[0] - dy * light[1] + light[2]) / np.sqrt(dx * dx + dy * dy + 1)
    return lam / light[2]


def shade(top, z, gz, sea: int = 62, known=None) -> np.ndarray:
    """RGB image from `summary` arrays; columns where known is False are black.
    Relief: hillshading of the ground (not the tree tops), brighter with height, and
    faint contour lines every 16 blocks on land, so mountains and valleys read."""
    water = top == REGISTRY.id("water")
    rgb = palette()[top]
    g = gz.astype(np.float32)
    s = np.clip(hillshade(g), 0.35, 1.6)
    s *= 0.85 + 0.15 * np.clip((g - sea) / 80.0, -1, 1)
    zf = z.astype(np.float32)  # a little canopy texture from the tree tops
    s *= np.clip(1.0 + (zf - np.roll(zf, 1, 0)) * 0.02, 0.9, 1.1)
    band = np.floor(g / 16.0)
    edge = (band != np.roll(band, 1, 0)) | (band != np.roll(band, 1, 1))
    gx, gy = np.gradient(g)
    gentle = gx * gx + gy * gy < 2.0  # on cliffs the lines would merge into black
    s = np.where(edge & gentle & ~water & (g > sea + 2), s * 0.85, s)
    rgb = rgb * np.where(water, 1.0, s)[:, :, None]
    depth = np.clip((sea - gz) / 30.0, 0, 1)[:, :, None]
    rgb = np.where(water[:, :, None], rgb * (1.1 - 0.6 * depth), rgb)
    if known is not None:
        rgb = rgb * known[:, :, None]
    return _image(rgb)


BIOME_COLOURS = {"ocean": (30, 70, 170), "desert": (225, 200, 120),
                 "mountain": (130, 110, 100), "treeRate": (30, 110, 40),
                 "hills": (150, 170, 70), "river": (60, 140, 230)}


def biome_rgb(fields: dict) -> np.ndarray:
    """Blend of biome colours by factor: fields are (W, H) arrays from a generator."""
    shape = next(iter(fields.values())).shape
    rgb = np.full(shape + (3,), (170, 200, 110), np.float32)  # plains
    for name in ("hills", "treeRate", "desert", "mountain"):
        if name in fields:
            w = np.clip(fields[name], 0, 1)[:, :, None]
            rgb = rgb * (1 - w) + np.array(BIOME_COLOURS[name], np.float32) * w
    if "ocean" in fields:
        rgb = np.where((fields["ocean"] > 0)[:, :, None], BIOME_COLOURS["ocean"], rgb)
    if "river" in fields:
        w = (np.clip(fields["river"], 0, 1) > 0)[:, :, None]
        rgb = np.where(w, BIOME_COLOURS["river"], rgb)
    return _image(rgb)


def _image(rgb):
    # [x, y] arrays -> image rows from north (high y) down
    return np.clip(rgb, 0, 255).astype(np.uint8).transpose(1, 0, 2)[::-1]
