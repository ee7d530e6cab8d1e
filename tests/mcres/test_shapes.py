"""Slabs, glass panes, doors, torches and rails from the test pack (laid out as the
game's own files) against what the game does: the boxes of its block shapes
(SlabBlock, DoorBlock.getShape, IronBarsBlock's arms, the rails' rise), which sides
they hide, and panes joining in a row (mcres.mesh). Geometry in the voxel frame
(x east, y north, z up); Minecraft boxes (x east, y up, z south) are turned into it."""
from __future__ import annotations

import itertools

import numpy as np
import pytest

from voxel_addon.mcres import Resources, Stack
from voxel_addon.mcres.mesh import build

from . import packfiles as pf

NAMES = ("-x", "+x", "-y", "+y", "-z", "+z")


@pytest.fixture(scope="module")
def res(tmp_path_factory):
    r = Resources(Stack.open([pf.write(tmp_path_factory.mktemp("p") / "c.jar", jar=True)]))
    yield r
    r.close()


def mc_box(f, t):
    """A Minecraft box (1/16, x y z) → (lo, hi) in the voxel frame."""
    f, t = np.asarray(f, float) / 16, np.asarray(t, float) / 16
    return [f[0], 1 - t[2], f[1]], [t[0], 1 - f[2], t[1]]


def box(quads):
    p = np.concatenate([q.pos for q in quads])
    return np.round(p.min(axis=0), 4).tolist(), np.round(p.max(axis=0), 4).tolist()


# ---- slabs ------------------------------------------------------------------------
SLAB = {"bottom": ([0, 0, 0], [16, 8, 16]), "top": ([0, 8, 0], [16, 16, 16]),
        "double": ([0, 0, 0], [16, 16, 16])}        # SlabBlock's shapes


@pytest.mark.parametrize("kind", SLAB)
def test_slabs_fill_their_half(res, kind):
    s = res.shape("oak_slab", {"type": kind, "waterlogged": "false"})
    lo, hi = mc_box(*SLAB[kind])
    assert box(s.quads) == (lo, hi)
    assert s.full == (kind == "double")
    # a side is hidden behind it where its box reaches that side whole
    reach = {"-z": lo[2] == 0, "+z": hi[2] == 1}
    assert {NAMES[d] for d in range(6) if s.faces[d]} == (
        set(NAMES) if kind == "double" else {k for k, v in reach.items() if v})
    assert {q.sprite for q in s.quads} == {"minecraft:block/oak_planks"}


PALETTE = ["", "minecraft:stone", "minecraft:oak_slab[type=bottom]", "minecraft:oak_slab[type=top]",
           "minecraft:glass_pane[east=false,north=false,south=false,west=false]"]


def faces_of(m, voxel):
    return [tuple(m.normals[4 * i]) for i in np.flatnonzero((m.voxel == voxel).all(axis=1))]


@pytest.mark.parametrize("slab, hidden", [(2, False), (3, True)])
def test_a_stone_on_a_slab_keeps_its_bottom_only_over_a_bottom_slab(res, slab, hidden):
    """The stone above: its bottom is hidden by a top slab (its box reaches the top
    whole), not by a bottom slab; the stone below loses its top under a bottom slab."""
    s = np.zeros((1, 1, 3), np.int32)
    s[0, 0, 0], s[0, 0, 1], s[0, 0, 2] = 1, slab, 1
    m = build(res, PALETTE, s, np.zeros(s.shape, bool))
    assert ((0, 0, -1) not in faces_of(m, (0, 0, 2))) == hidden
    assert ((0, 0, 1) not in faces_of(m, (0, 0, 0))) == (not hidden)
    # the slab's own face toward the stone: the one against it is culled
    slab_faces = faces_of(m, (0, 0, 1))
    assert ((0, 0, -1) in slab_faces) == hidden and ((0, 0, 1) in slab_faces) == (not hidden)


# ---- glass panes ------------------------------------------------------------------
def pane(**sides):
    return {d: str(sides.get(d, False)).lower() for d in ("north", "east", "south", "west")}


ARM_END = {"north": ("+y", 1), "south": ("-y", 0), "west": ("-x", 0), "east": ("+x", 1)}


@pytest.mark.parametrize("sides", list(itertools.product([False, True], repeat=4)))
def test_a_pane_reaches_the_sides_it_joins(res, sides):
    """IronBarsBlock: a 2/16 post in the middle, an arm to each joined side; where it
    does not join, the post shows its glass toward that side."""
    joined = dict(zip(("north", "east", "south", "west"), sides))
    s = res.shape("glass_pane", pane(**joined))
    p = np.concatenate([q.pos for q in s.quads])
    for side, on in joined.items():
        axis, end = ("xy".index(ARM_END[side][0][1]), ARM_END[side][1])
        reached = np.isclose(p[:, axis], end).any()
        assert reached == on, (side, joined)
        d = NAMES.index(ARM_END[side][0])
        # at the arm's end: the edge, culled by a whole block there; else the post's glass
        ends = [q for q in s.quads if q.face == d]
        assert ends, (side, joined)
        if on:
            assert {q.sprite for q in ends if np.allclose(q.pos[:, axis], end)} == \
                {"minecraft:block/glass_pane_top"}
            assert all(q.cull == d for q in ends if np.allclose(q.pos[:, axis], end))
        else:
            assert all(q.cull == -1 and q.sprite == "minecraft:block/glass" for q in ends)
            assert all(np.allclose(q.pos[:, axis], 7 / 16 if end == 0 else 9 / 16) for q in ends)
    # always the post's 2/16 square from bottom to top
    assert np.isclose(p[:, 2].min(), 0) and np.isclose(p[:, 2].max(), 1)
    assert s.layer == "translucent" and not any(s.faces) and not s.full


def test_panes_in_a_row_hide_the_ends_between_them(res):
    """Three panes west to east (the game stores each one's joins): the middle one has
    both arms; no arm's end face stands between two panes, the row's ends keep theirs."""
    pal = ["", "minecraft:glass_pane[east=true,north=false,south=false,west=false]",
           "minecraft:glass_pane[east=true,north=false,south=false,west=true]",
           "minecraft:glass_pane[east=false,north=false,south=false,west=true]"]
    s = np.array([1, 2, 3], np.int32).reshape(3, 1, 1)
    m = build(res, pal, s, np.zeros(s.shape, bool))
    pos = m.positions.reshape(-1, 4, 3)
    n = m.normals.reshape(-1, 4, 3)[:, 0]
    # every quad facing ±x with all corners on a block boundary x = 1 or 2 (between panes)
    between = [i for i in range(m.quads) if abs(n[i, 0]) > 0.5
               and np.isin(np.round(pos[i, :, 0], 5), (1.0, 2.0)).all()]
    assert between == []
    mid = np.flatnonzero(m.voxel[:, 0] == 1)
    span = pos[mid].reshape(-1, 3)[:, 0]
    assert np.isclose(span.min(), 1) and np.isclose(span.max(), 2)
    # the post's glass toward north and south where nothing joins: on all three
    for x in range(3):
        q = np.flatnonzero(m.voxel[:, 0] == x)
        assert {tuple(np.round(n[i], 3)) for i in q} >= {(0, 1, 0), (0, -1, 0)}


# ---- doors ------------------------------------------------------------------------
DOOR_BOX = {"north": ([0, 0, 13], [16, 16, 16]), "south": ([0, 0, 0], [16, 16, 3]),
            "west": ([13, 0, 0], [16, 16, 16]), "east": ([0, 0, 0], [3, 16, 16])}
CW = {"north": "east", "east": "south", "south": "west", "west": "north"}


def door_box(facing, hinge, opened):
    """DoorBlock.getShape: the facing's box when closed; open, a quarter clockwise
    (left hinge) or anticlockwise (right hinge)."""
    if opened:
        ccw = {v: k for k, v in CW.items()}
        facing = ccw[facing] if hinge == "right" else CW[facing]
    return mc_box(*DOOR_BOX[facing])


@pytest.mark.parametrize("facing", ["north", "east", "south", "west"])
@pytest.mark.parametrize("hinge", ["left", "right"])
@pytest.mark.parametrize("opened", [False, True])
def test_a_door_is_the_games_box(res, facing, hinge, opened):
    for half, tex in (("lower", "bottom"), ("upper", "top")):
        s = res.shape("oak_door", {"facing": facing, "half": half, "hinge": hinge,
                                   "open": str(opened).lower(), "powered": "false"})
        lo, hi = door_box(facing, hinge, opened)
        assert box(s.quads) == (lo, hi), (half, facing, hinge, opened)
        assert {q.sprite for q in s.quads} == {f"minecraft:block/oak_door_{tex}"}
        # the lower half has a bottom and no top, the upper one the other way round
        caps = {NAMES[q.face] for q in s.quads if q.face in (4, 5)}
        assert caps == ({"-z"} if half == "lower" else {"+z"})


def test_an_open_doors_box_is_turned(res):
    shut = res.shape("oak_door", {"facing": "south", "half": "lower", "hinge": "left", "open": "false"})
    opened = res.shape("oak_door", {"facing": "south", "half": "lower", "hinge": "left", "open": "true"})
    (lo0, hi0), (lo1, hi1) = box(shut.quads), box(opened.quads)
    # shut: thin along y (against the north side); open: thin along x (the east side)
    assert hi0[1] - lo0[1] == 3 / 16 and hi0[0] - lo0[0] == 1
    assert hi1[0] - lo1[0] == 3 / 16 and hi1[1] - lo1[1] == 1 and lo1[0] == 13 / 16


# ---- rails and torches ------------------------------------------------------------
RISE = {"ascending_north": (1, +1), "ascending_south": (1, -1),
        "ascending_east": (0, +1), "ascending_west": (0, -1)}


@pytest.mark.parametrize("shape", ["north_south", "east_west", *RISE])
def test_rails_lie_flat_or_rise_toward_their_side(res, shape):
    s = res.shape("rail", {"shape": shape})
    assert s.layer == "cutout" and len(s.quads) == 2 and not any(s.faces)
    for q in s.quads:
        p = q.pos
        assert np.allclose(p[:, :2].min(axis=0), 0) and np.allclose(p[:, :2].max(axis=0), 1)
        if shape not in RISE:
            assert np.allclose(p[:, 2], 1 / 16)
            continue
        axis, sign = RISE[shape]
        # height grows by one block across it toward the named side: 1/16 .. 17/16
        t = p[:, axis] if sign > 0 else 1 - p[:, axis]
        assert np.allclose(p[:, 2], 1 / 16 + t), (shape, p)
    up = [q for q in s.quads if np.cross(q.pos[1] - q.pos[0], q.pos[2] - q.pos[0])[2] > 0]
    assert len(up) == 1 and up[0].sprite == "minecraft:block/rail"


def test_a_standing_torch(res):
    s = res.shape("torch")
    assert s.layer == "cutout" and not s.ao and not any(s.faces)
    assert all(q.cull == -1 and not q.shade for q in s.quads)
    # the stick's top at 10/16, within 7/16..9/16
    top = [q for q in s.quads if q.face == 5]
    assert len(top) == 1 and np.allclose(top[0].pos[:, 2], 10 / 16)
    assert box(top) == ([7 / 16, 7 / 16, 10 / 16], [9 / 16, 9 / 16, 10 / 16])
    # its planes cross in the middle of the block
    planes = [q for q in s.quads if q.face < 4]
    assert len(planes) == 4 and all(
        np.allclose(q.pos[:, q.face // 2], 0.5, atol=1 / 16 + 1e-6) for q in planes)
