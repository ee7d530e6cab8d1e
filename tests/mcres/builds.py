"""A small Minecraft build written by the tests and imported with and without the
test pack as the world's resource stack (issue 30): shared by the bake, render, world
and GUI tests."""
from __future__ import annotations

import numpy as np

from ..formats import mcfiles as mc
from . import packfiles as pf

AIR = "minecraft:air"


def save_with_build(root):
    """Chunk (0, 0): a stone floor at y 0, grass at its north-west, a stair, glass,
    a poppy, a block the pack does not know; desert biome where x < 4."""
    a = np.full((16, 16, 16), AIR, object)
    a[0] = "minecraft:stone"
    a[0, 0:2, 0:2] = "minecraft:grass_block[snowy=false]"
    a[1, 5, 5] = "minecraft:oak_stairs[facing=east,half=bottom,shape=straight,waterlogged=false]"
    a[1, 7, 7] = "minecraft:glass"
    a[1, 9, 9] = "minecraft:poppy"
    a[1, 11, 11] = "minecraft:gold_block"          # not in the pack: today's look
    cells = np.zeros((4, 4, 4), int)
    cells[:, :, 0] = 1
    mc.write_region(root / "save" / "region", {(0, 0): mc.chunk_nbt(0, 0, {0: a}, biomes={
        0: (["minecraft:forest", "minecraft:desert"], cells.reshape(-1))})})
    return root / "save"


def imported(root):
    """({"with": world imported with the test pack as its stack, "without": the same
    build without one}, the pack's jar)."""
    from voxel_addon.cli import main
    jar = pf.write(root / "client.jar", jar=True)
    save = save_with_build(root)
    out = {}
    for name, extra in (("with", ["--resources", str(jar)]), ("without", [])):
        out[name] = root / f"{name}.sqlite"
        assert main(["import", "--world", str(out[name]), "--from", str(save), *extra]) == 0
    return out, jar
