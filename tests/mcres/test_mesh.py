"""Voxels with states → model quads (mcres.mesh): culling by cullface against whole
cubes (checked against a brute-force count), same see-through states, the project's
own opaque voxels; tints by the column's biome; voxels the stack does not know are
left to the project's own look; the Minecraft position of a voxel."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.mcres import Resources, Stack
from voxel_addon.mcres.mesh import LAYERS, OFFSETS, build, to_minecraft

from . import packfiles as pf

PALETTE = ["", "minecraft:stone", "minecraft:oak_stairs[facing=east,half=bottom,shape=straight]",
           "minecraft:glass", "minecraft:grass_block[snowy=false]", "minecraft:mystery_block",
           "minecraft:poppy", "minecraft:chest[facing=north]"]
STONE, STAIR, GLASS, GRASS, MYSTERY, POPPY, CHEST = range(1, 8)


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    r = Resources(Stack.open([pf.write(tmp_path_factory.mktemp("p") / "c.jar", jar=True)]))
    yield r
    r.close()


def scene():
    s = np.zeros((5, 5, 4), np.int32)
    s[:, :, 0] = STONE
    s[1, 1, 1] = STAIR
    s[2, 1, 1] = STONE                 # east of the stair: its step's east face is hidden
    s[0, 3, 1] = s[0, 4, 1] = GLASS    # two glass blocks side by side
    s[4, 4, 0] = GRASS
    s[3, 3, 1] = MYSTERY               # unknown to the stack: the project's own look
    s[2, 3, 1] = POPPY
    s[1, 3, 1] = CHEST                 # no elements (drawn by code in the game): our look
    opaque = np.zeros(s.shape, bool)
    opaque[4, 0, 1] = True             # a voxel of the project's own
    opaque[3, 3, 1] = True             # the mystery block, drawn the project's way
    biomes = np.zeros((5, 5), np.uint8)
    biomes[4, 4] = 1
    return s, opaque, biomes


def quads_of(m, voxel):
    return np.flatnonzero((m.voxel == voxel).all(axis=1))


def test_whole_cubes_show_only_faces_toward_open_space(res):
    """Brute force: a stone voxel's face is drawn iff the neighbour there is not a
    stone, nor grass, nor an opaque voxel of the project's own."""
    s, opaque, biomes = scene()
    m = build(res, PALETTE, s, opaque, biomes=biomes, biome_names=["minecraft:plains",
                                                                    "minecraft:desert"])
    hides = (s == STONE) | (s == GRASS) | opaque
    # an east-facing bottom stair covers its bottom (-z) and its east side (+x) whole
    covers = {STAIR: {4, 1}}
    want = 0
    for x, y, z in np.argwhere(s == STONE):
        for d, (dx, dy, dz) in enumerate(OFFSETS):
            nx, ny, nz = x + dx, y + dy, z + dz
            inside = 0 <= nx < 5 and 0 <= ny < 5 and 0 <= nz < 4
            hidden = inside and (hides[nx, ny, nz] or (d ^ 1) in covers.get(s[nx, ny, nz], ()))
            want += not hidden
    got = sum(len(quads_of(m, v)) for v in np.argwhere(s == STONE))
    assert got == want
    assert not m.drawn[3, 3, 1] and m.drawn[1, 1, 1] and not m.drawn[4, 0, 1]
    assert len(quads_of(m, (3, 3, 1))) == 0
    assert not m.drawn[1, 3, 1] and len(quads_of(m, (1, 3, 1))) == 0


def test_a_stair_loses_the_faces_against_whole_neighbours(res):
    s, opaque, biomes = scene()
    m = build(res, PALETTE, s, opaque)
    q = quads_of(m, (1, 1, 1))
    pos = m.positions.reshape(-1, 4, 3)[q] - (1, 1, 1)
    nrm = m.normals.reshape(-1, 4, 3)[q, 0]
    # the bottom against the stone floor: gone
    assert not any(np.allclose(p[:, 2], 0) and n[2] < 0 for p, n in zip(pos, nrm))
    # facing +x: the slab's and the step's east faces are both against the stone: gone
    assert not any(np.allclose(p[:, 0], 1) for p, n in zip(pos, nrm) if n[0] > 0)
    # the west face toward open air stays
    assert any(np.allclose(p[:, 0], 0) for p, n in zip(pos, nrm) if n[0] < 0)
    # 11 quads in the model (6 + 5): the bottom and the two east faces culled
    assert len(q) == 11 - 2 - 1


@pytest.mark.parametrize("facing, half, sides", [
    ("east", "bottom", {"-z", "+x"}), ("north", "bottom", {"-z", "+y"}),
    ("west", "top", {"+z", "-x"}), ("south", "top", {"+z", "-y"})])
def test_the_sides_a_stair_covers(res, facing, half, sides):
    """A stair hides the faces against its flat bottom (top) and back, nothing else."""
    sh = res.shape("oak_stairs", {"facing": facing, "half": half, "shape": "straight"})
    names = ("-x", "+x", "-y", "+y", "-z", "+z")
    assert {names[d] for d in range(6) if sh.faces[d]} == sides
    assert all(res.shape("stone").faces) and not any(res.shape("glass").faces)
    assert not any(res.shape("poppy").faces)


def test_glass_beside_glass_and_layers(res):
    s, opaque, _ = scene()
    m = build(res, PALETTE, s, opaque)
    a, b = quads_of(m, (0, 3, 1)), quads_of(m, (0, 4, 1))
    assert len(a) == len(b) == 4        # no face between them, none on the stone below
    assert {LAYERS[i] for i in m.layer[a]} == {"translucent"}
    poppy = quads_of(m, (2, 3, 1))
    assert len(poppy) == 4 and not m.shade[poppy].any()


def test_grass_takes_its_columns_biome(res):
    s, opaque, biomes = scene()
    m = build(res, PALETTE, s, opaque, biomes=biomes,
              biome_names=["minecraft:plains", "minecraft:desert"])
    q = quads_of(m, (4, 4, 0))
    top = [i for i in q if m.normals[4 * i, 2] > 0.5]
    assert [tuple(m.tint[i]) for i in top] == [(0, 255, 7)]          # the desert's pixel
    bottom = [i for i in q if m.normals[4 * i, 2] < -0.5]
    assert [tuple(m.tint[i]) for i in bottom] == [(255, 255, 255)]
    assert "minecraft:block/grass_block_top" in [m.sprites[i] for i in m.sprite[top]]
    # in plains the same grass is plains' colour
    m2 = build(res, PALETTE, s, opaque)
    top2 = [i for i in quads_of(m2, (4, 4, 0)) if m2.normals[4 * i, 2] > 0.5]
    assert [tuple(m2.tint[i]) for i in top2] == [(50, 173, 7)]


def test_inner_voxels_cost_nothing(res):
    s = np.full((3, 3, 3), STONE, np.int32)
    m = build(res, PALETTE, s, np.zeros(s.shape, bool))
    assert len(quads_of(m, (1, 1, 1))) == 0 and m.quads == 6 * 9
    # a flower walled in on every side still has its planes (no cullface)
    s[1, 1, 1] = POPPY
    m = build(res, PALETTE, s, np.zeros(s.shape, bool))
    assert len(quads_of(m, (1, 1, 1))) == 4


def test_the_minecraft_position_of_a_voxel():
    """The inverse of the import's block (x, y, z) → voxel (x, −1−z, y − y_min)."""
    for x, y, z in [(0, 0, 0), (5, -64, -3), (-17, 100, 40)]:
        v = (x, -1 - z, y + 64)
        assert to_minecraft(*v, y_min=-64) == (x, y, z)


def test_positions_carry_the_origin(res):
    s = np.zeros((1, 1, 1), np.int32)
    s[0, 0, 0] = STONE
    m = build(res, PALETTE, s, np.zeros(s.shape, bool), origin=(10, -20, 5))
    assert m.positions.min(axis=0).tolist() == [10, -20, 5]
    assert m.positions.max(axis=0).tolist() == [11, -19, 6]


@pytest.mark.parametrize("key, inner", [
    ("minecraft:oak_leaves[distance=1,persistent=true,waterlogged=false]", True),
    ("minecraft:glass", False)])
def test_a_blob_of_leaves_keeps_its_inner_faces_glass_does_not(res, key, inner):
    """A 2x2x2 blob: leaves draw their faces against each other (the game's fancy
    leaves: a tree shows leaves inside, not the floor through the holes), glass hides
    the faces between glass (HalfTransparentBlock). Brute force: a face toward
    another blob voxel is drawn iff INNER; every face toward open air is."""
    s = np.zeros((4, 4, 4), np.int32)
    s[1:3, 1:3, 1:3] = 1
    m = build(res, ["", key], s, np.zeros(s.shape, bool))
    want = 0
    for v in np.argwhere(s == 1):
        for d in OFFSETS:
            want += inner or not s[tuple(v + d)]
    assert m.quads == want == (48 if inner else 24)
    nrm = m.normals.reshape(-1, 4, 3)[:, 0]
    # the faces between the blob's voxels, seen from either side
    between = sum(1 for v, n in zip(m.voxel, nrm) if s[tuple(v + np.rint(n).astype(int))])
    assert between == (24 if inner else 0)


def test_which_blocks_hide_faces_against_themselves():
    from voxel_addon.mcres.mesh import hides_itself
    yes = ["minecraft:glass", "minecraft:red_stained_glass", "minecraft:tinted_glass",
           "minecraft:glass_pane", "minecraft:lime_stained_glass_pane", "minecraft:iron_bars",
           "minecraft:ice", "minecraft:blue_ice", "minecraft:slime_block",
           "minecraft:waxed_oxidized_copper_grate", "minecraft:powder_snow"]
    no = ["minecraft:oak_leaves", "minecraft:azalea_leaves", "minecraft:stone",
          "minecraft:dice", "mymod:crystal"]
    assert [n for n in yes if not hides_itself(n)] == []
    assert [n for n in no if hides_itself(n)] == []
