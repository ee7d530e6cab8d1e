"""Minecraft block names -> the world's block types (issue 21).

`lookup(name)` -> (block name, rgb or None, how): `how` is "exact" (the table),
"class" (a rule on the name: *_planks, *_log, *_wool, …) or "fallback" (nothing
matched: stone, never air, so a build keeps its shape). Block states do not change the type:
stairs, slabs and walls become their material's full block (their state is kept beside,
formats/mcstate.py, for a resource stack to draw). The 16 dye colours of
wool, concrete, terracotta, glass and carpets become the `color` block with that
colour (one texture, tinted) rather than 48 textures. Results are cached per name.
"""
from __future__ import annotations

from functools import lru_cache

DYES = {  # Minecraft's dye colours (DyeColor)
    "white": (249, 255, 254), "orange": (249, 128, 29), "magenta": (199, 78, 189),
    "light_blue": (58, 179, 218), "yellow": (254, 216, 61), "lime": (128, 199, 31),
    "pink": (243, 139, 170), "gray": (71, 79, 82), "light_gray": (157, 157, 151),
    "cyan": (22, 156, 156), "purple": (137, 50, 184), "blue": (60, 68, 170),
    "brown": (131, 84, 50), "green": (94, 124, 22), "red": (176, 46, 38),
    "black": (29, 29, 33),
}
TERRACOTTA = (152, 94, 67)

AIR = {"air", "cave_air", "void_air", "barrier", "light", "structure_void", "moving_piston"}

EXACT = {
    "stone": "stone", "smooth_stone": "stone", "andesite": "stone", "diorite": "stone",
    "granite": "stone", "tuff": "stone", "calcite": "stone", "dripstone_block": "stone",
    "bedrock": "obsidian", "polished_andesite": "stone", "polished_diorite": "stone",
    "polished_granite": "stone",
    "dirt": "dirt", "coarse_dirt": "dirt", "rooted_dirt": "dirt", "podzol": "dirt",
    "mud": "dirt", "farmland": "dirt", "dirt_path": "dirt", "mycelium": "dirt",
    "grass_block": "grass", "moss_block": "grass",
    "snow_block": "snow", "snow": "snow", "powder_snow": "snow",
    "ice": "glass", "packed_ice": "glass", "blue_ice": "glass",
    "sand": "sand", "red_sand": "sand", "suspicious_sand": "sand",
    "gravel": "gravel", "suspicious_gravel": "gravel", "clay": "clay",
    "sandstone": "sandstone", "red_sandstone": "sandstone", "cut_sandstone": "sandstone",
    "smooth_sandstone": "sandstone", "chiseled_sandstone": "sandstone",
    "cobblestone": "cobblestone", "mossy_cobblestone": "cobblestone",
    "cobbled_deepslate": "deepslate", "deepslate": "deepslate",
    "stone_bricks": "stone_bricks", "mossy_stone_bricks": "stone_bricks",
    "cracked_stone_bricks": "stone_bricks", "chiseled_stone_bricks": "stone_bricks",
    "bricks": "bricks", "mud_bricks": "bricks", "nether_bricks": "bricks",
    "red_nether_bricks": "bricks", "netherrack": "bricks",
    "obsidian": "obsidian", "crying_obsidian": "obsidian",
    "water": "water", "bubble_column": "water", "kelp": "water", "kelp_plant": "water",
    "seagrass": "water", "tall_seagrass": "water",
    "lava": "lava", "magma_block": "lava",
    "glass": "glass", "glass_pane": "glass", "tinted_glass": "glass",
    "torch": "torch", "wall_torch": "torch", "soul_torch": "torch", "soul_wall_torch": "torch",
    "redstone_torch": "torch", "redstone_wall_torch": "torch",
    "lantern": "lamp_yellow", "soul_lantern": "lamp_blue", "glowstone": "lamp_yellow",
    "sea_lantern": "lamp_white", "shroomlight": "lamp_yellow", "redstone_lamp": "lamp_yellow",
    "jack_o_lantern": "lamp_yellow", "froglight": "lamp_white", "campfire": "lava",
    "end_rod": "lamp_white",
    "short_grass": "tall_grass", "grass": "tall_grass", "tall_grass": "tall_grass",
    "fern": "tall_grass", "large_fern": "tall_grass", "dead_bush": "tall_grass",
    "sugar_cane": "tall_grass",
    "wheat": "wheat", "carrots": "wheat", "potatoes": "wheat", "beetroots": "wheat",
    "cactus": "cactus",
    "brown_mushroom": "mushroom", "red_mushroom": "mushroom",
    "glow_lichen": "glowing_mushroom",
    "terracotta": ("color", TERRACOTTA), "quartz_block": ("color", (236, 230, 223)),
    "smooth_quartz": ("color", (236, 230, 223)), "iron_block": ("color", (220, 220, 220)),
    "gold_block": ("color", (246, 208, 61)), "diamond_block": ("color", (98, 237, 228)),
    "emerald_block": ("color", (42, 203, 87)), "lapis_block": ("color", (31, 67, 140)),
    "redstone_block": ("color", (175, 24, 5)), "coal_block": ("color", (16, 15, 15)),
    "copper_block": ("color", (192, 107, 79)), "prismarine": ("color", (99, 156, 151)),
    "purpur_block": ("color", (169, 125, 169)), "end_stone": ("color", (219, 222, 158)),
    "hay_block": ("color", (166, 136, 38)), "bookshelf": "planks", "crafting_table": "planks",
    "chest": "planks", "barrel": "planks", "pumpkin": ("color", (198, 118, 24)),
    "melon": ("color", (111, 145, 30)), "sponge": ("color", (195, 192, 74)),
    "bone_block": ("color", (229, 225, 207)), "slime_block": ("color", (111, 192, 91)),
    "honey_block": ("color", (251, 185, 52)), "amethyst_block": ("color", (133, 97, 191)),
    "furnace": "cobblestone", "dispenser": "cobblestone", "dropper": "cobblestone",
}

# (substring, target) tried in order on names the table does not hold
CLASSES = (
    ("_wool", "dye"), ("_carpet", "dye"), ("_concrete_powder", "dye"), ("_concrete", "dye"),
    ("_glazed_terracotta", "dye"), ("_terracotta", "dye"), ("_stained_glass", "glass"),
    ("_bed", "dye"), ("_banner", "dye"), ("_candle", "torch"), ("_shulker_box", "dye"),
    ("_ore", "ore"), ("_leaves", "leaves"), ("_log", "log"), ("_wood", "log"), ("_stem", "log"),
    ("_hyphae", "log"), ("_planks", "planks"), ("_door", "planks"), ("_trapdoor", "planks"),
    ("_fence", "planks"), ("_sign", "planks"), ("_pressure_plate", "planks"),
    ("_button", "planks"), ("bamboo", "planks"), ("_sapling", "tall_grass"),
    ("_tulip", "flowers"), ("flower", "flowers"), ("poppy", "flowers"), ("dandelion", "flowers"),
    ("orchid", "flowers"), ("allium", "flowers"), ("azure_bluet", "flowers"),
    ("daisy", "flowers"), ("cornflower", "flowers"), ("lily", "flowers"), ("lilac", "flowers"),
    ("rose", "flowers"), ("peony", "flowers"), ("vine", "leaves"), ("coral", "flowers"),
    ("mushroom", "mushroom"), ("deepslate", "deepslate"), ("cobblestone", "cobblestone"),
    ("stone_brick", "stone_bricks"), ("brick", "bricks"), ("sandstone", "sandstone"),
    ("blackstone", "deepslate"), ("basalt", "deepslate"), ("quartz", "quartz_block"),
    ("purpur", "purpur_block"), ("prismarine", "prismarine"), ("copper", "copper_block"),
    ("glass", "glass"), ("lantern", "lamp_yellow"), ("torch", "torch"), ("lamp", "lamp_yellow"),
    ("ice", "glass"), ("snow", "snow"), ("sand", "sand"), ("dirt", "dirt"), ("mud", "dirt"),
    ("grass", "tall_grass"), ("stone", "stone"), ("andesite", "stone"), ("diorite", "stone"),
    ("granite", "stone"), ("tuff", "stone"), ("slab", "stone"), ("stairs", "stone"),
    ("wall", "stone"), ("rail", "planks"), ("ladder", "planks"), ("lectern", "planks"),
    ("anvil", "obsidian"), ("cauldron", "obsidian"), ("iron", "iron_block"),
    ("gold", "gold_block"),
)
_WOODS = ("oak", "spruce", "birch", "jungle", "acacia", "dark_oak", "mangrove", "cherry",
          "crimson", "warped", "pale_oak")


def _resolve(target, name):
    """A table target -> (block, rgb)."""
    if isinstance(target, tuple):
        return target
    if target == "dye":
        for dye in sorted(DYES, key=len, reverse=True):  # light_blue before blue
            if name.startswith(dye + "_"):
                rgb = DYES[dye]
                if "terracotta" in name and "glazed" not in name:
                    rgb = tuple(int(0.55 * c + 0.45 * t) for c, t in zip(rgb, TERRACOTTA))
                return "color", rgb
        return "color", DYES["white"]
    if isinstance(EXACT.get(target), tuple):  # a coloured name of the table (quartz_block, …)
        return EXACT[target]
    return target, None


@lru_cache(maxsize=None)
def lookup(name: str) -> tuple[str, tuple | None, str]:
    """(block name, rgb for the `color` block or None, how it was mapped)."""
    base = name.split(":", 1)[1] if ":" in name else name
    if base in AIR:
        return "air", None, "exact"
    if base in EXACT:
        return (*_resolve(EXACT[base], base), "exact")
    if any(base.startswith(w + "_") for w in _WOODS) and \
            any(s in base for s in ("_slab", "_stairs", "_fence", "_door", "_sign", "_button",
                                    "_pressure_plate", "_planks", "_trapdoor")):
        return "planks", None, "class"
    for sub, target in CLASSES:
        if sub in base:
            return (*_resolve(target, base), "class")
    return "stone", None, "fallback"
