"""Biome tints: grass and foliage from the stack's colormaps (`colormap/grass.png`,
`foliage.png`) at the biome's temperature and downfall, as the game indexes them;
water from the biome; the game's fixed colours (spruce and birch leaves, lily pads,
stems, redstone by power) and biome modifiers (swamp, dark forest, badlands)."""
from __future__ import annotations

import numpy as np

# name: (temperature, downfall, water, grass override, foliage override); None: from the map
_B = {}


def _add(names, t, d, water=0x3F76E4, grass=None, foliage=None):
    for n in names.split():
        _B[n] = (t, d, water, grass, foliage)


_add("plains sunflower_plains beach dripstone_caves deep_dark", 0.8, 0.4)
_add("snowy_plains ice_spikes", 0.0, 0.5)
_add("desert savanna savanna_plateau windswept_savanna nether_wastes soul_sand_valley "
     "crimson_forest warped_forest basalt_deltas", 2.0, 0.0)
_add("badlands eroded_badlands wooded_badlands", 2.0, 0.0, grass=0x90814D, foliage=0x9E814D)
_add("swamp", 0.8, 0.9, water=0x617B64, grass=0x6A7039, foliage=0x6A7039)
_add("mangrove_swamp", 0.8, 0.9, water=0x3A7A6A, grass=0x6A7039, foliage=0x8DB127)
_add("forest flower_forest dark_forest", 0.7, 0.8)
_add("pale_garden", 0.7, 0.8, water=0x76889D, grass=0x778272, foliage=0x878D76)
_add("birch_forest old_growth_birch_forest", 0.6, 0.6)
_add("old_growth_pine_taiga", 0.3, 0.8)
_add("taiga old_growth_spruce_taiga", 0.25, 0.8)
_add("snowy_taiga", -0.5, 0.4, water=0x3D57D6)
_add("windswept_hills windswept_gravelly_hills windswept_forest stony_shore", 0.2, 0.3)
_add("jungle bamboo_jungle", 0.95, 0.9)
_add("sparse_jungle", 0.95, 0.8)
_add("meadow", 0.5, 0.8, water=0x0E4ECF)
_add("cherry_grove", 0.5, 0.8, water=0x5DB7EF, grass=0xB6DB61, foliage=0xB6DB61)
_add("grove", -0.2, 0.8)
_add("snowy_slopes", -0.3, 0.9)
_add("frozen_peaks jagged_peaks", -0.7, 0.9)
_add("stony_peaks", 1.0, 0.3)
_add("river ocean deep_ocean lush_caves the_end end_highlands end_midlands small_end_islands "
     "end_barrens the_void", 0.5, 0.5)
_add("frozen_river frozen_ocean", 0.0, 0.5, water=0x3938C9)
_add("deep_frozen_ocean", 0.5, 0.5, water=0x3938C9)
_add("snowy_beach", 0.05, 0.3, water=0x3D57D6)
_add("cold_ocean deep_cold_ocean", 0.5, 0.5, water=0x3D57D6)
_add("lukewarm_ocean deep_lukewarm_ocean", 0.5, 0.5, water=0x45ADF2)
_add("warm_ocean", 0.5, 0.5, water=0x43D5EE)
_add("mushroom_fields", 0.9, 1.0)
BIOMES = dict(_B)
DEFAULT = "plains"

GRASS = frozenset("grass_block short_grass grass tall_grass fern large_fern potted_fern "
                  "sugar_cane bush".split())
FOLIAGE = frozenset("oak_leaves jungle_leaves acacia_leaves dark_oak_leaves mangrove_leaves "
                    "vine".split())
WATER = frozenset("water bubble_column water_cauldron".split())
FIXED = {"spruce_leaves": 0x619961, "birch_leaves": 0x80A755, "lily_pad": 0x208030,
         "attached_melon_stem": 0xE0C71C, "attached_pumpkin_stem": 0xE0C71C}
FALLBACK = {"grass": 0x91BD59, "foliage": 0x77AB2F}    # plains, when the stack has no map


def rgb(c: int) -> tuple[int, int, int]:
    return (c >> 16) & 255, (c >> 8) & 255, c & 255


def climate(biome: str) -> tuple:
    b = biome.rpartition(":")[2]
    return BIOMES.get(b, BIOMES[DEFAULT])


def from_map(colormap: np.ndarray | None, temperature: float, downfall: float, fallback: int) -> int:
    """The game's colormap look-up (GrassColor.get): x from temperature, y from
    temperature × downfall, both clamped to 0..1; the biome keeps them as Java floats,
    widened to double (so plains' 0.8 lands on column 50, not 51)."""
    if colormap is None or colormap.shape[:2] != (256, 256):
        return fallback
    t = float(np.float32(min(max(temperature, 0.0), 1.0)))
    d = float(np.float32(min(max(downfall, 0.0), 1.0))) * t
    x, y = int((1.0 - t) * 255.0), int((1.0 - d) * 255.0)
    r, g, b = (int(v) for v in colormap[y, x, :3])
    return r << 16 | g << 8 | b


def colour(resources, block: str, props: dict | None, biome: str) -> tuple[int, int, int] | None:
    """The tint of BLOCK's tinted faces (tintindex ≥ 0) in BIOME, or None (untinted)."""
    name = block.rpartition(":")[2]
    props = props or {}
    if name in FIXED:
        return rgb(FIXED[name])
    if name == "redstone_wire":
        f = int(props.get("power", 0)) / 15.0
        r = f * 0.6 + (0.4 if f > 0 else 0.3)
        return (round(255 * r), round(255 * min(max(f * f * 0.7 - 0.5, 0), 1)),
                round(255 * min(max(f * f * 0.6 - 0.7, 0), 1)))
    if name in ("melon_stem", "pumpkin_stem"):
        a = int(props.get("age", 0))
        return a * 32, 255 - a * 8, a * 4
    t, d, water, grass, foliage = climate(biome)
    bname = biome.rpartition(":")[2]
    if name in WATER:
        return rgb(water)
    if name in GRASS:
        if grass is not None:
            return rgb(grass)
        tex = resources.texture("minecraft:colormap/grass") if resources else None
        c = from_map(None if tex is None else tex.rgba, t, d, FALLBACK["grass"])
        if bname == "dark_forest":
            c = ((c & 0xFEFEFE) + 0x28340A) >> 1
        return rgb(c)
    if name in FOLIAGE:
        if foliage is not None:
            return rgb(foliage)
        tex = resources.texture("minecraft:colormap/foliage") if resources else None
        return rgb(from_map(None if tex is None else tex.rgba, t, d, FALLBACK["foliage"]))
    return None
