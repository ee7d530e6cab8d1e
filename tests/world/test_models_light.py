"""An edit's incremental relight in a world with a resource stack sees the blocks the
full solve sees (world/models.light_blocks: a rail, a door, a slab pass light): after
each stroke near the build's model blocks, the chunks' light equals a full NumPy
solve of the same blocks and states."""
from __future__ import annotations

import shutil

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY

from ..mcres.builds import imported
from .test_edit_oracles import snapshot

CX0, CY0, CX1, CY1 = -1, -2, 2, 1      # the 3x3 around the build's chunk (0, -1)
PLANKS, STONE, LAMP = (REGISTRY.id(n) for n in ("planks", "stone", "lamp_red"))


def vox(x, y, z):
    """Minecraft block (x, y, z) of the build → world voxel."""
    return x, -1 - z, y + 64


@pytest.fixture(scope="module")
def worlds(tmp_path_factory):
    return imported(tmp_path_factory.mktemp("mclight"))[0]


def stale(E):
    """Garble the edit's scratch light window: the layers a stroke does not gather
    (edit._light_layers) must be ones its relight never reads."""
    buf = getattr(E._scratch, "light", None)
    if buf is not None:
        buf[...] = 0x7777


def check_full(w):
    """Every lit chunk of the 3x3 holds the full solve of what the light sees."""
    from voxel_addon import light
    b, d = snapshot(w, CX0 - 1, CY0 - 1, CX1 + 1, CY1 + 1)
    full = light.region_light(w.light_blocks(b, d), backend="numpy")
    for cy in range(CY0, CY1):
        for cx in range(CX0, CX1):
            c = w.chunks[(cx, cy)]
            i, j = 16 * (cx - CX0), 16 * (cy - CY0)
            bad = np.argwhere(c.light != full[i:i + 16, j:j + 16])
            assert not bad.size, ((cx, cy), bad[:3].tolist())


def test_edits_near_model_blocks_relight_as_the_full_solve(worlds, tmp_path):
    from voxel_addon.storage import minecraft as mcfile
    from voxel_addon.world import World, build
    from voxel_addon.world import edit as E
    from voxel_addon.world.edit import edit, undo
    path = tmp_path / "w.sqlite"
    shutil.copy(worlds["with"], path)
    with World.open(path, loader=False) as w:
        build.light_and_mesh(w, CX0, CY0, CX1, CY1)
        palette = mcfile.kept(w.file.meta)[1]
        rail = palette.index("minecraft:rail[shape=north_south,waterlogged=false]")
        flat = vox(13, 1, 9)
        assert int(w.chunk_at(0, -1).blocks[13, 15 - 9, 65]) == PLANKS   # the stand-in
        # the light passes the rail already (the batch's solve): not a planks cube
        assert int(w.chunks[(0, -1)].light[13, 15 - 9, 65]) >> 12 == 15
        strokes = [
            [(*vox(13, 2, 9), STONE)],                 # a roof over the flat rail
            [(*vox(13, 0, 8), 0)],                     # dig the floor under a rail
            [(*vox(13, 1, 6), 0)],                     # the block the rail rises onto
            [(*vox(8, 0, 3), 0)],                      # the floor under a door...
            [(*vox(8, 20, 3), STONE)],                 # ... and a roof high over it
            [(*vox(9, 1, 3), LAMP)],                   # a lamp between the doors
            [(*vox(9, 2, 3), STONE), (*vox(9, 1, 2), STONE), (*vox(9, 1, 4), STONE)],
            [(*vox(3, 2, 9), STONE), (*vox(2, 2, 9), STONE)],   # over the slabs
            [(*flat, PLANKS, 0)],                      # the rail's state only: a cube now
            [(*vox(11, 1, 13), PLANKS, rail)],         # a cube's state only: a rail now
            [(*vox(11, 2, 13), STONE), (*vox(12, 1, 13), PLANKS)],
        ]
        recs = []
        for s in strokes:
            stale(E)
            recs.append(edit(w, s)[1])
            check_full(w)
        # under the new rail at (11, 1, 13) the floor is lit through it, not dark
        light = w.chunks[(0, -1)].light
        assert int(light[11, 15 - 13, 65]) >> 12 > 0
        for r in reversed(recs[-3:]):
            undo(w, r)
            check_full(w)
        assert int(w.chunks[(0, -1)].light[13, 15 - 9, 65]) >> 12 < 15   # under the roof


def test_without_a_stack_the_edit_sees_the_planks(worlds, tmp_path):
    """The same build imported without a stack: the rail is a planks cube to the
    light, before and after an edit beside it."""
    from voxel_addon.world import World, build
    from voxel_addon.world.edit import edit
    path = tmp_path / "w.sqlite"
    shutil.copy(worlds["without"], path)
    with World.open(path, loader=False) as w:
        build.light_and_mesh(w, CX0, CY0, CX1, CY1)
        edit(w, (*vox(12, 1, 9), LAMP))
        check_full(w)
        assert int(w.chunks[(0, -1)].light[13, 15 - 9, 65]) == 0     # opaque, unlit
