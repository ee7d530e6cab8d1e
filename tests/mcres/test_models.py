"""Blockstates and models from the test pack into quads: parent chains, variants with
rotations and uvlock, weighted variants drawn as the game draws them, multipart
conditions, rotated and rescaled elements, cullfaces after rotation, layers, tints and
pixels. Geometry is checked in the voxel frame (x east, y north, z up)."""
from __future__ import annotations

import json

import numpy as np
import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.mcres import Resources, Stack, tints
from voxel_addon.mcres.geometry import default_uv
from voxel_addon.mcres.states import JavaRandom, position_seed

from . import packfiles as pf

FACES = {"-x": 0, "+x": 1, "-y": 2, "+y": 3, "-z": 4, "+z": 5}


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    root = tmp_path_factory.mktemp("pack")
    r = Resources(Stack.open([pf.write(root / "client.jar", jar=True)]))
    yield r
    r.close()


def box(quads):
    p = np.concatenate([q.pos for q in quads])
    return np.round(p.min(axis=0), 4).tolist(), np.round(p.max(axis=0), 4).tolist()


def upper(shape):
    """The quads above the bottom half (a stair's step; not the slab's top at 0.5)."""
    return [q for q in shape.quads if q.pos[:, 2].min() >= 0.5 - 1e-6 and q.pos[:, 2].max() > 0.5 + 1e-6]


def test_a_parent_chain_gives_textures_down_and_elements_up(res):
    m = res.model("block/stone")
    assert len(m.elements) == 1 and m.ao
    assert {f["sprite"] for f in m.elements[0]["faces"].values()} == {"minecraft:block/stone"}
    s = res.shape("stone", {}, (0, 0, 0))
    assert s.full and s.layer == "solid" and len(s.quads) == 6
    assert sorted(q.cull for q in s.quads) == list(range(6))
    # a child's texture variable wins over its parent's
    top = res.model("block/stone_dirt_top").elements[0]["faces"]
    assert top["up"]["sprite"] == "minecraft:block/dirt"
    assert top["down"]["sprite"] == "minecraft:block/stone"
    assert res.model("block/cross").ao is False and res.model("block/poppy").ao is False


@pytest.mark.parametrize("facing, side", [("east", (0.5, 1, 0, 1)), ("west", (0, 0.5, 0, 1)),
                                          ("north", (0, 1, 0.5, 1)), ("south", (0, 1, 0, 0.5))])
def test_stairs_turn_their_step_to_the_facing(res, facing, side):
    """North is +y in the voxel frame, so a north-facing stair's step is at y 0.5..1."""
    s = res.shape("oak_stairs", {"facing": facing, "half": "bottom", "shape": "straight"})
    lo, hi = box(upper(s))
    assert (lo[0], hi[0], lo[1], hi[1]) == side and (lo[2], hi[2]) == (0.5, 1)
    assert box(s.quads) == ([0, 0, 0], [1, 1, 1]) and not s.full
    # cullfaces turn with the model: the step's top is culled by the block above, its
    # back by the block behind it
    step_back = [q for q in upper(s) if q.cull not in (-1, FACES["+z"])]
    back = {"east": "+x", "west": "-x", "north": "+y", "south": "-y"}[facing]
    assert FACES[back] in {q.cull for q in step_back}
    assert all(q.face == q.cull for q in s.quads if q.cull >= 0)


@pytest.mark.parametrize("facing, side", [("east", (0.5, 1, 0, 1)), ("west", (0, 0.5, 0, 1)),
                                          ("north", (0, 1, 0.5, 1)), ("south", (0, 1, 0, 0.5))])
def test_a_top_half_stair_is_upside_down(res, facing, side):
    """x = 180 first, then y: the step hangs below, still on the facing side."""
    s = res.shape("oak_stairs", {"facing": facing, "half": "top", "shape": "straight"})
    low = [q for q in s.quads if q.pos[:, 2].max() <= 0.5 + 1e-6 and q.pos[:, 2].min() < 0.5 - 1e-6]
    lo, hi = box(low)
    assert (lo[0], hi[0], lo[1], hi[1]) == side
    bottom = [q for q in s.quads if q.cull == FACES["-z"]]
    assert bottom and all(np.allclose(q.pos[:, 2], 0) for q in bottom)


def test_uvlock_keeps_the_texture_still_in_the_world(res):
    """Rotated 90°, a side face's uv still comes from its place in the world: the
    north side of a south-facing stair shows the texture's lower half only where the
    block is low (v > 0.5 below z = 0.5)."""
    for facing in ("east", "south", "west", "north"):
        s = res.shape("oak_stairs", {"facing": facing, "half": "bottom", "shape": "straight"})
        for q in s.quads:
            if q.face in (FACES["-z"], FACES["+z"]):
                continue
            # v runs down the world: v = 1 - z for every vertical face
            assert np.allclose(q.uv[:, 1], 1 - q.pos[:, 2]), (facing, q.face)


def test_the_default_uv_is_the_games(res):
    """FaceBakery's defaults for an element from (2,3,4) to (10,12,14)."""
    want = {"down": [2, 2, 10, 12], "up": [2, 4, 10, 14], "north": [6, 4, 14, 13],
            "south": [2, 4, 10, 13], "west": [4, 4, 14, 13], "east": [2, 4, 12, 13]}
    for d, uv in want.items():
        assert default_uv(d, (2, 3, 4), (10, 12, 14)) == uv, d


def test_face_corners_and_uv_corners_as_the_game(res):
    """The stone's south face (voxel -y) seen from outside: top-left corner first,
    counter-clockwise, texture (0,0) at the top-left: the pack's pixels as written."""
    q = next(q for q in res.shape("stone").quads if q.face == FACES["-y"])
    assert q.pos.tolist() == [[0, 0, 1], [0, 0, 0], [1, 0, 0], [1, 0, 1]]
    assert q.uv.tolist() == [[0, 0], [0, 1], [1, 1], [1, 0]]
    n = np.cross(q.pos[1] - q.pos[0], q.pos[2] - q.pos[0])
    assert n[1] < 0                            # counter-clockwise from outside: normal out
    tex = res.texture(q.sprite)
    assert np.array_equal(tex.rgba, pf.texture("stone"))


def test_java_random_is_javas():
    """Values of java.util.Random from its specification (new Random(0).nextLong(),
    new Random(42).nextInt())."""
    assert JavaRandom(0).next_long() == -4962768465676381896
    assert JavaRandom(42).next(32) == -1170105035
    assert position_seed(0, 0, 0) == 0


def test_weighted_variants_follow_their_weights_and_the_position(res):
    """stone: [stone ×3, stone_mirrored ×1, stone y=90 ×1]: over many positions each
    is drawn about as often as its weight says, the same position always the same."""
    counts = {}
    for x in range(40):
        for z in range(25):
            s = res.shape("stone", {}, (x, 64, z))
            top = next(q for q in s.quads if q.face == FACES["+z"])
            corner = int(np.argmin(top.pos[:, 0] + top.pos[:, 1]))    # the south-west one
            key = (top.sprite, tuple(top.uv[corner].tolist()))
            counts[key] = counts.get(key, 0) + 1
            assert res.shape("stone", {}, (x, 64, z)) is s
    mirrored = sum(v for k, v in counts.items() if "mirrored" in k[0])
    assert len(counts) == 3 and 140 < mirrored < 260
    assert sum(counts.values()) == 1000


def fence(**sides):
    props = {d: "false" for d in ("north", "east", "south", "west")}
    props.update({k: str(v).lower() for k, v in sides.items()})
    return props


def arms(shape):
    """Which sides an arm reaches (an arm ends at the block's edge)."""
    p = np.concatenate([q.pos for q in shape.quads if q.pos[:, 2].max() < 1])
    out = set()
    out |= {"west"} if p[:, 0].min() == 0 else set()
    out |= {"east"} if p[:, 0].max() == 1 else set()
    out |= {"south"} if p[:, 1].min() == 0 else set()
    out |= {"north"} if p[:, 1].max() == 1 else set()
    return out


def caps(shape):
    return sorted(round(float(q.pos[:, 2].mean()), 4) for q in shape.quads
                  if q.sprite == "minecraft:block/torch")


def test_a_multipart_fence(res):
    assert arms(res.shape("oak_fence", fence())) == set()
    assert len(res.shape("oak_fence", fence()).quads) == 6
    for side in ("north", "east", "south", "west"):
        assert arms(res.shape("oak_fence", fence(**{side: True}))) == {side}
    assert arms(res.shape("oak_fence", fence(north=True, west=True))) == {"north", "west"}
    # OR: both north and south, or waterlogged
    assert caps(res.shape("oak_fence", fence(north=True, south=True))) == [17 / 16]
    assert caps(res.shape("oak_fence", fence(north=True))) == []
    assert caps(res.shape("oak_fence", {**fence(), "waterlogged": True})) == [17 / 16]
    # AND of "!false" and "true|maybe": east anything but false, west true or maybe
    assert caps(res.shape("oak_fence", fence(east=True, west="maybe"))) == [-1 / 16]
    assert caps(res.shape("oak_fence", fence(east=True))) == []


def test_a_rescaled_45_degree_cross_reaches_the_corners(res):
    s = res.shape("poppy")
    assert len(s.quads) == 4 and s.layer == "cutout" and not s.ao and not s.full
    for q in s.quads:
        xy = q.pos[:, :2]
        # each plane runs corner to corner: from (0.05, 0.05) to (0.95, 0.95) or crossed
        d = np.abs(xy - 0.5)
        assert np.allclose(d, 0.45, atol=1e-6), xy
        assert not q.shade and q.cull == -1
    # two planes, each with both sides
    ns = {tuple(np.round(np.cross(q.pos[1] - q.pos[0], q.pos[2] - q.pos[0])[:2], 3)) for q in s.quads}
    assert len(ns) == 4


def test_a_tilted_element_and_a_rotated_face(res):
    """22.5° about x through (8,3,16): the top face tilts, its corners keep their
    distances to the origin; rotation 90 turns the uv corners."""
    s = res.shape("wall_torch", {"facing": "north"})
    (q,) = s.quads
    o = np.array([0.5, 0.0, 3 / 16])                       # (8,3,16) in the voxel frame
    before = np.array([[7, 13, 14], [7, 13, 16], [9, 13, 16], [9, 13, 14]]) / 16
    before = np.stack([before[:, 0], 1 - before[:, 2], before[:, 1]], axis=1)
    assert np.allclose(np.linalg.norm(q.pos - o, axis=1), np.linalg.norm(before - o, axis=1))
    assert not np.allclose(q.pos[:, 2], q.pos[0, 2])       # no longer flat
    assert q.uv.tolist() == (np.array([[7, 8], [9, 8], [9, 6], [7, 6]]) / 16).tolist()
    e = res.shape("wall_torch", {"facing": "east"}).quads[0]
    # y=90: (x, y) voxel → turned clockwise seen from above
    assert np.allclose(e.pos[:, 0] - 0.5, q.pos[:, 1] - 0.5)
    assert np.allclose(e.pos[:, 1] - 0.5, -(q.pos[:, 0] - 0.5))


def test_layers_and_full_blocks(res):
    leaves, glass, grass = res.shape("oak_leaves"), res.shape("glass"), res.shape("grass_block", {"snowy": "false"})
    assert leaves.layer == "cutout" and not leaves.full
    assert glass.layer == "translucent" and not glass.full
    # the grass block: a whole opaque cube (it hides its neighbours) with a cutout overlay
    assert grass.full and grass.layer == "cutout" and len(grass.quads) == 10
    assert {q.tint for q in grass.quads if q.face == FACES["+z"]} == {0}
    assert {q.tint for q in grass.quads if q.face == FACES["-z"]} == {-1}
    assert res.shape("grass_block", {"snowy": "true"}).quads[0].sprite == "minecraft:block/stone"
    # the overlay stands a little off the side under it (no z-fighting), outward
    over = [q for q in grass.quads if q.sprite == "minecraft:block/grass_block_side_overlay"]
    assert len(over) == 4
    for q in over:
        axis = q.face // 2
        edge = 1.0 if q.face % 2 else 0.0
        off = q.pos[:, axis] - edge
        assert np.allclose(np.abs(off), 1 / 512) and np.sign(off[0]) == (1 if q.face % 2 else -1)
    assert all(np.isin(q.pos[:, q.face // 2], (0, 1)).all() for q in grass.quads
               if q.sprite == "minecraft:block/grass_block_side")
    assert res.shape("no_such_block") is None


def test_the_first_animation_frame(res):
    t = res.texture("minecraft:block/sea_lantern")
    assert t.rgba.shape == (16, 16, 4) and t.rgba[8, 8, :3].tolist() == [20, 40, 90]


@pytest.mark.parametrize("biome, xy", [("plains", (50, 173)), ("desert", (0, 255)),
                                       ("snowy_plains", (255, 255)), ("jungle", (12, 36)),
                                       ("minecraft:taiga", (191, 203))])
def test_grass_and_foliage_from_the_colormaps(res, biome, xy):
    """The colormaps' pixels say where the look-up landed (red = column, green = row):
    hot and dry at the bottom-left, cold at the right. The columns and rows are the
    game's, computed in Java floats (0.8f → 50, 0.25f × 0.8f → 203)."""
    assert tints.colour(res, "grass_block", {}, biome) == (*xy, 7)
    assert tints.colour(res, "minecraft:oak_leaves", {}, biome) == (*xy, 9)


def test_fixed_and_modified_tints(res):
    assert tints.colour(res, "spruce_leaves", {}, "jungle") == (0x61, 0x99, 0x61)
    assert tints.colour(res, "birch_leaves", {}, "desert") == (0x80, 0xA7, 0x55)
    assert tints.colour(res, "water", {}, "swamp") == (0x61, 0x7B, 0x64)
    assert tints.colour(res, "water", {}, "unknown_mod_biome") == (0x3F, 0x76, 0xE4)
    assert tints.colour(res, "grass_block", {}, "badlands") == (0x90, 0x81, 0x4D)
    forest = tints.colour(res, "grass_block", {}, "forest")
    dark = tints.colour(res, "grass_block", {}, "dark_forest")
    assert dark == tuple(((a & 0xFE) + b) >> 1 for a, b in zip(forest, (0x28, 0x34, 0x0A)))
    assert tints.colour(res, "stone", {}, "plains") is None
    assert tints.colour(None, "grass_block", {}, "plains") == (0x91, 0xBD, 0x59)


def bad_pack(tmp_path, rel, obj):
    d = tmp_path / "bad"
    content = {"pack.mcmeta": b"{}", "assets/minecraft/" + rel:
               obj if isinstance(obj, bytes) else json.dumps(obj).encode()}
    return Resources(Stack.open([pf.write(d, content)] if d.mkdir() is None else []))


@pytest.mark.parametrize("rel, obj, call, msg", [
    ("blockstates/a.json", b"{nope", ("shape", "a"), "bad JSON"),
    ("blockstates/a.json", {"variants": {"": {"y": 90}}}, ("shape", "a"), "without a model"),
    ("blockstates/a.json", {"variants": {"": {"model": "m", "x": 45}}}, ("shape", "a"), "multiple of 90"),
    ("blockstates/a.json", {"nothing": 1}, ("shape", "a"), "neither"),
    ("blockstates/a.json", {"variants": {"facing": {"model": "m"}}}, ("shape", "a"), "property=value"),
    ("models/m.json", {"parent": "m"}, ("model", "m"), "parent cycle"),
    ("models/m.json", {"elements": [{"from": [0, 0], "to": [1, 1, 1]}]}, ("model", "m"), "three numbers"),
    ("models/m.json", {"elements": [{"from": [0, 0, 0], "to": [99, 1, 1]}]}, ("model", "m"), "outside"),
    ("models/m.json", {"elements": [{"from": [0, 0, 0], "to": [1, 1, 1], "faces": {
        "up": {"texture": "#a", "rotation": 45}}}]}, ("model", "m"), "face rotation"),
    ("models/m.json", {"elements": [{"from": [0, 0, 0], "to": [1, 1, 1],
                                     "rotation": {"axis": "w", "angle": 0}}]}, ("model", "m"), "rotation"),
])
def test_bad_files_are_one_line_errors(tmp_path, rel, obj, call, msg):
    r = bad_pack(tmp_path, rel, obj)
    with pytest.raises(VoxelError, match=msg):
        getattr(r, call[0])(call[1])


def test_a_texture_variable_that_loops_or_is_missing_is_none(tmp_path):
    r = bad_pack(tmp_path, "models/m.json", {"textures": {"a": "#b", "b": "#a"}, "elements": [
        {"from": [0, 0, 0], "to": [16, 16, 16], "faces": {"up": {"texture": "#a"},
                                                          "down": {"texture": "#zz"}}}]})
    assert {f["sprite"] for f in r.model("m").elements[0]["faces"].values()} == {None}
