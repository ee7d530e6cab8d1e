"""The incremental relight's cheap paths against a full solve: incremental._local (an
edit that changes no voxel but the edited one skips the relight box), in scenes built
so that its reasoning is wrong by one step if any of its conditions slips (a p that
rises to exactly 2, a neighbour that kept its daylight only through p, a column
below p that changes), and sparse.relight (the box path's algorithm on the
voxels it touches, for light that barely moves: leaves and water on top), with
streams of random edits that take every path."""
import numpy as np

from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import full, incremental, sparse

from . import part_edit

STONE, ORE, MUSH = R.id("stone"), R.id("ore"), R.id("glowing_mushroom")


def _rock():
    b = np.zeros((24, 24, 256), np.uint16, order="F")
    b[:, :, :60] = STONE
    return b


def _edit(b, L, p, block):
    """Edit, check against a full solve; returns which path relit it."""
    before = dict(incremental.STATS)
    incremental.edit(b, L, *p, block)
    assert np.array_equal(L, full.solve(b, "numpy")), (p, block)
    return next(k for k, n in incremental.STATS.items() if n > before[k])


def test_p_rising_to_two_lights_its_neighbour():
    """Ore (red 3) at the end of a dark tunnel: reopening the voxel next to it gives
    it red 2, which reaches the next voxel as 1 (the box path must run)."""
    b = _rock()
    b[5:16, 10, 30] = 0
    b[4, 10, 30] = ORE
    L = full.solve(b, "numpy")
    assert (L[6, 10, 30] & 15) == 1
    assert _edit(b, L, (5, 10, 30), STONE) != "local"
    assert (L[6, 10, 30] & 15) == 0
    assert _edit(b, L, (5, 10, 30), 0) != "local"
    assert (L[6, 10, 30] & 15) == 1


def test_daylight_kept_only_through_p():
    """A mushroom (blue 14, no daylight of its own) beside the bottom of a sky shaft:
    its daylight 14 comes only through p; its blue emission is no support for it.
    (A second mushroom above p keeps p's blue from mattering to the shaft.)"""
    b = _rock()
    b[10, 10, 30:] = 0
    b[11, 10, 30] = MUSH
    b[10, 10, 31] = MUSH
    L = full.solve(b, "numpy")
    assert L[11, 10, 30] >> 12 == 14
    assert _edit(b, L, (10, 10, 30), STONE) != "local"
    assert L[11, 10, 30] >> 12 == 0


def test_column_below_rising_to_one():
    """Under 14 leaves in a well the daylight is 1: digging the stone under it gives
    p daylight 1 (too faint to spread) but also the sealed air column below it."""
    b = _rock()
    b[10, 10, 46:60] = R.id("leaves")
    b[10, 10, 40:45] = 0
    L = full.solve(b, "numpy")
    assert L[10, 10, 46] >> 12 == 1 and L[10, 10, 42] >> 12 == 0
    assert _edit(b, L, (10, 10, 45), 0) != "local"
    assert L[10, 10, 42] >> 12 == 1


def test_local_edits():
    """Digging in the dark and walling off voxels that nothing depends on stay local,
    and so does a darker edit whose neighbours keep their light from elsewhere."""
    b = _rock()
    b[3:20, 3:20, 40:44] = 0  # a dark sealed cave
    b[8, 8, 41] = ORE
    b[12, 12, 50:] = 0  # a shaft with daylight
    b[11:14, 12, 50] = 0  # and a wide bottom
    L = full.solve(b, "numpy")
    assert _edit(b, L, (15, 15, 30), 0) == "local"  # dig in the rock
    assert _edit(b, L, (15, 15, 42), STONE) == "local"  # dark cave voxel walled
    assert _edit(b, L, (12, 12, 52), R.id("glass")) == "local"  # same light class
    assert _edit(b, L, (3, 3, 59), 0) == "local"  # the top block, dug in the open
    assert _edit(b, L, (3, 3, 59), STONE) == "local"  # and put back
    # the wide bottom's ends keep daylight 14 from the shaft... but p is the shaft:
    # the column below p changes, so not local
    assert _edit(b, L, (12, 12, 55), STONE) != "local"


def test_random_cave_edits_both_paths():
    rng = np.random.default_rng(11)
    b = _rock()
    b[2:22, 2:22, 30:40] = np.where(rng.random((20, 20, 10)) < 0.5, 0, STONE)
    b[6, 6, 40:] = 0  # daylight shafts into it
    b[17, 14, 40:] = 0
    where = rng.random((20, 20, 10)) < 0.03
    b[2:22, 2:22, 30:40][where] = rng.choice([ORE, MUSH, R.id("lamp_red")], int(where.sum()))
    L = full.solve(b, "numpy")
    ids = [0, 0, STONE, STONE, ORE, MUSH, R.id("water"), R.id("glass")]
    paths = []
    for _ in range(60):
        p = (int(rng.integers(2, 22)), int(rng.integers(2, 22)), int(rng.integers(29, 41)))
        new = int(rng.choice(ids))
        if b[p] != new:
            paths.append(_edit(b, L, p, new))
    assert paths.count("local") >= 10 and len(paths) - paths.count("local") >= 10, paths


def test_leaves_on_top_go_sparse():
    """Stone set on a leaf column darkens the daylight below it; digging the top leaf
    brightens it: a few voxels each, relit without the box."""
    b = _rock()
    b[:, :, 60:64] = STONE
    b[10, 10, 60:64] = R.id("leaves")  # a leaf column sunk in the rock
    b[11, 10, 60] = R.id("leaves")  # roofed: lit only through the column
    L = full.solve(b, "numpy")
    assert L[10, 10, 60] >> 12 == 11 and L[11, 10, 60] >> 12 == 9
    assert _edit(b, L, (10, 10, 64), STONE) == "sparse"
    assert L[11, 10, 60] >> 12 == 0
    assert _edit(b, L, (10, 10, 64), 0) == "sparse"
    assert _edit(b, L, (10, 10, 63), 0) == "sparse"


def test_random_forest_edits_all_paths():
    """Random leaf and water columns on flat ground, edits on and around them."""
    rng = np.random.default_rng(5)
    b = _rock()
    tops = rng.integers(60, 66, (24, 24))
    kinds = rng.choice([R.id("leaves"), R.id("water"), R.id("glass"), 0, 0], (24, 24))
    for i in range(24):
        for j in range(24):
            b[i, j, 60:tops[i, j]] = kinds[i, j]
    L = full.solve(b, "numpy")
    ids = [0, 0, STONE, R.id("leaves"), R.id("water"), R.id("glass"), ORE, R.id("lamp_red")]
    paths = []
    for _ in range(90):
        i, j = (int(v) for v in rng.integers(0, 24, 2))
        p = (i, j, int(rng.integers(58, 67)))
        new = int(rng.choice(ids))
        if b[p] != new:
            paths.append(_edit(b, L, p, new))
    assert min(paths.count(k) for k in ("local", "sparse", "box")) >= 3, paths


def test_part_window_relights_exactly_or_says_it_cannot():
    """update(part=True) on only the columns within K of the edit (an edit's first
    relight window, world/edit.py): either the full relight's result there, with
    nothing changed outside (the light stayed inside), or None and nothing written."""
    rng = np.random.default_rng(9)
    b = np.zeros((40, 40, 256), np.uint16, order="F")
    b[:, :, :60] = STONE
    tops = rng.integers(60, 66, (40, 40))
    kinds = rng.choice([R.id("leaves"), R.id("water"), R.id("glass"), 0, 0], (40, 40))
    for i in range(40):
        for j in range(40):
            b[i, j, 60:tops[i, j]] = kinds[i, j]
    b[5:35, 5:35, 50:58] = np.where(rng.random((30, 30, 8)) < 0.4, 0, STONE)  # caves
    L = full.solve(b, "numpy")
    b[20, 20, 58:tops[20, 20]] = R.id("leaves")  # a leaf column into the rock whose
    b[20, 20, 60:] = 0                            # daylight fills a roofed tunnel
    b[21:32, 20, 58] = 0
    ids = [0, 0, STONE, R.id("leaves"), R.id("water"), R.id("glass"), ORE, R.id("lamp_red")]
    done = {True: 0, False: 0}
    for t in range(70):
        K = 3 + t % 3
        x, y = (int(v) for v in rng.integers(K, 40 - K, 2))
        z = int(rng.integers(50, 67))
        new = int(rng.choice(ids))
        if t in (0, 1):   # roof the column, open it: the tunnel's light moves past K
            x, y, z, new = 20, 20, 60, (STONE, 0)[t]
        if b[x, y, z] == new:
            continue
        done[part_edit(b, L, x, y, z, new, K)] += 1
    assert min(done.values()) >= 5, done


def test_column_days_equals_the_column_pass():
    """sparse.column_days (walked down in Python from the highest block below
    z, air runs at once) against the column pass written with NumPy over the whole
    column: water, leaves and glass under and over z, caves of air below the
    surface, opaque voxels at z or just under it, z at the floor and the top."""
    from voxel_addon.light import model
    _, att, opaque, _, _, _ = model.tables()
    ids = [0, 0, 0, STONE, R.id("water"), R.id("leaves"), R.id("glass"), R.id("dirt")]
    rng = np.random.default_rng(11)
    for i in range(300):
        b = np.zeros((1, 1, 256), np.uint16, order="F")
        top = int(rng.integers(1, 256))
        b[0, 0, :top] = rng.choice(ids, top)
        if i % 3 == 0:
            b[0, 0, int(rng.integers(0, 256)):] = 0     # open above
        z = (0, 255)[i % 2] if i < 4 else int(rng.integers(0, 256))
        old = int(rng.choice(ids))
        col = np.stack([b[0, 0, :z + 1], b[0, 0, :z + 1]])
        col[1, z] = old
        above = b[0, 0, z + 1:]
        carry = 0 if opaque[above].any() else max(model.MAX - int(att[above].sum()), 0)
        a = np.cumsum(att[col[:, ::-1]], axis=1, dtype=np.int16)[:, ::-1]
        blocked = np.maximum.accumulate(opaque[col[:, ::-1]], axis=1)[:, ::-1].astype(bool)
        want = np.where(blocked, 0, np.clip(carry - a, 0, model.MAX))
        assert np.array_equal(sparse.column_days(b, 0, 0, z, old), want), (i, z)


def test_sparse_at_the_arrays_edges():
    """The sparse path's neighbours of a voxel on the arrays' side faces stop there: a
    leaf column at each side, a sealed dark air voxel at the far end of the next row
    (where a flat index would run on to), the column roofed and opened again."""
    for col, pocket in (((10, 23), (11, 0)), ((10, 0), (9, 23)),
                        ((23, 10), (0, 11)), ((0, 10), (23, 9))):
        b = _rock()
        b[:, :, 60:64] = STONE
        b[col[0], col[1], 60:64] = R.id("leaves")
        b[pocket[0], pocket[1], 61] = 0
        L = full.solve(b, "numpy")
        assert _edit(b, L, (*col, 64), STONE) == "sparse"
        assert _edit(b, L, (*col, 64), 0) == "sparse"
        assert L[col[0], col[1], 61] >> 12 > 1 and L[pocket[0], pocket[1], 61] == 0
