"""A small Minecraft build written by the tests and imported with and without the
test pack as the world's resource stack (issue 30): shared by the bake, render, world
and GUI tests."""
from __future__ import annotations

import numpy as np

from ..formats import mcfiles as mc
from . import packfiles as pf

AIR = "minecraft:air"


def _joined(kind: str, cells, extra: str = "") -> dict:
    """KIND (a fence or a pane) on CELLS (x, z): each joined to its neighbours of the
    same kind, as the game stores it."""
    out = {}
    for x, z in cells:
        sides = {"east": (x + 1, z) in cells, "west": (x - 1, z) in cells,
                 "north": (x, z - 1) in cells, "south": (x, z + 1) in cells}
        props = ",".join(f"{k}={str(v).lower()}" for k, v in sorted(sides.items()))
        out[x, z] = f"minecraft:{kind}[{props}{extra}]"
    return out


FENCE = [(x, 3) for x in range(2, 6)]
PANE = [(x, 6) for x in range(2, 6)] + [(5, 7)]
SLABS = {(2, 9): "bottom", (3, 9): "top", (4, 9): "double"}
# (x, z): (facing, hinge, open)
DOORS = {(8, 3): ("south", "left", "false"), (10, 3): ("south", "left", "true")}
# x 13 from the south: flat, flat, rising north onto a stone, flat on it
RAILS = {(13, 9, 1): "north_south", (13, 8, 1): "north_south", (13, 7, 1): "ascending_north",
         (13, 6, 2): "north_south"}
TORCH = (6, 11)
LEAVES = [(x, y, z) for x in (5, 6) for y in (1, 2) for z in (12, 13)]


def build_blocks() -> np.ndarray:
    """The build's section (y, z, x) of state keys: a stone floor at y 0, grass at
    its north-west, a stair, glass, a poppy, a block the pack does not know, a fence
    and a glass pane row, slabs (bottom, top, double), a closed and an open door,
    rails rising onto a block, a torch and leaves."""
    a = np.full((16, 16, 16), AIR, object)
    a[0] = "minecraft:stone"
    a[0, 0:2, 0:2] = "minecraft:grass_block[snowy=false]"
    a[1, 5, 5] = "minecraft:oak_stairs[facing=east,half=bottom,shape=straight,waterlogged=false]"
    a[1, 7, 7] = "minecraft:glass"
    a[1, 9, 9] = "minecraft:poppy"
    a[1, 11, 11] = "minecraft:gold_block"          # not in the pack: today's look
    for (x, z), k in _joined("oak_fence", FENCE, ",waterlogged=false").items():
        a[1, z, x] = k
    for (x, z), k in _joined("glass_pane", PANE, ",waterlogged=false").items():
        a[1, z, x] = k
    for (x, z), t in SLABS.items():
        a[1, z, x] = f"minecraft:oak_slab[type={t},waterlogged=false]"
    for (x, z), (facing, hinge, opened) in DOORS.items():
        for y, half in ((1, "lower"), (2, "upper")):
            a[y, z, x] = (f"minecraft:oak_door[facing={facing},half={half},hinge={hinge},"
                          f"open={opened},powered=false]")
    for (x, z, y), shape in RAILS.items():
        a[y, z, x] = f"minecraft:rail[shape={shape},waterlogged=false]"
    a[1, 6, 13] = "minecraft:stone"
    a[1, TORCH[1], TORCH[0]] = "minecraft:torch"
    for x, y, z in LEAVES:
        a[y, z, x] = "minecraft:oak_leaves[distance=1,persistent=true,waterlogged=false]"
    return a


def save_with_build(root):
    """Chunk (0, 0): the build's section (`build_blocks`) at y 0; desert biome where
    x < 4. Nothing at the chunk's edges (the floor stands alone there)."""
    a = build_blocks()
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


TERRAIN = ["", "minecraft:stone", "minecraft:grass_block[snowy=false]",
           "minecraft:oak_leaves[distance=1,persistent=true,waterlogged=false]"]


def terrain(n: int = 64, depth: int = 256, seed: int = 0) -> np.ndarray:
    """A hilly N×N terrain in the voxel frame ((n + 2, n + 2, depth) indices into
    TERRAIN, a one-voxel ring around it): stone under grass, hills ±8 around z 128
    (y 64 with y_min −64), leaf blobs (3×3×2) standing on it here and there."""
    rng = np.random.default_rng(seed)
    x, y = np.meshgrid(np.arange(n + 2), np.arange(n + 2), indexing="ij")
    h = (128 + 5 * np.sin(x / 9.0) + 3 * np.cos(y / 11.0)).astype(int)
    z = np.arange(depth)[None, None, :]
    s = np.where(z < h[..., None], 1, 0)
    s[z[0, 0, :][None, None, :] == h[..., None] - 1] = 2
    for cx, cy in rng.integers(1, n - 2, (n * n // 64, 2)).tolist():
        top = int(h[cx:cx + 3, cy:cy + 3].max())
        s[cx:cx + 3, cy:cy + 3, top + 2:top + 4] = 3
    return s.astype(np.int32)
