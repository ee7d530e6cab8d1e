"""The incremental relight's lamp paths (light/lamp.relight: a lamp's colour flooded
from it alone, one component; lamp.placed: a lamp set where no colour
passed, its daylight on the sparse path and its colour by lamp.relight) against a
full solve: random lamps of every colour placed and removed on ground with leaf,
water and glass columns, beside and under each other, and with part windows (an
edit's first relight window: world/edit.py)."""
import numpy as np

from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import full, incremental

from . import part_edit

STONE = R.id("stone")
LAMPS = [R.id(n) for n in ("lamp_red", "lamp_green", "lamp_blue", "lamp_white", "torch")]


def _ground(rng, n=32):
    b = np.zeros((n, n, 256), np.uint16, order="F")
    b[:, :, :60] = STONE
    tops = rng.integers(60, 67, (n, n))
    kinds = rng.choice([R.id("leaves"), R.id("water"), R.id("glass"), STONE, 0, 0], (n, n))
    for i in range(n):
        for j in range(n):
            b[i, j, 60:tops[i, j]] = kinds[i, j]
    return b, tops


def test_random_lamps_placed_and_removed():
    rng = np.random.default_rng(29)
    b, tops = _ground(rng, 48)
    L = full.solve(b, "numpy")
    placed, paths = [], []
    for t in range(70):
        if placed and t % 3 == 2:   # take one out again (air, or stone in its place)
            x, y, z = placed.pop(int(rng.integers(len(placed))))
            new = int(rng.choice([0, STONE]))
        else:   # on the ground, on a column, in the air, next to another lamp
            x, y = (int(v) for v in rng.integers(0, b.shape[0], 2))
            z = int(tops[x, y]) + int(rng.integers(0, 3))
            if placed and t % 4 == 0:
                q = placed[-1]
                x, y, z = min(q[0] + 1, b.shape[0] - 1), q[1], q[2]
            new = int(rng.choice(LAMPS))
            placed.append((x, y, z))
        if b[x, y, z] == new:
            continue
        before = dict(incremental.STATS)
        incremental.edit(b, L, x, y, z, new)
        assert np.array_equal(L, full.solve(b, "numpy")), (t, x, y, z, new)
        paths.append(next(k for k, n in incremental.STATS.items() if n > before[k]))
    assert paths.count("lamp") >= 10 and paths.count("box") >= 12, paths


def test_lamp_in_part_windows():
    """update(part=True) with a lamp set (and taken out again on the whole array):
    the full relight's result on the part with nothing changed outside, or None and
    nothing written where its reach (14) meets the part's side faces."""
    rng = np.random.default_rng(30)
    b, tops = _ground(rng, 40)
    L = full.solve(b, "numpy")
    done = {True: 0, False: 0}
    for t in range(15):
        K = (13, 15, 17)[t % 3]
        x, y = (int(v) for v in rng.integers(K, 40 - K, 2))
        z = int(tops[x, y]) + int(rng.integers(0, 2))
        new = int(rng.choice(LAMPS[:3]))
        old, before = int(b[x, y, z]), L.copy()
        done[part_edit(b, L, x, y, z, new, K)] += 1
        incremental.edit(b, L, x, y, z, old)
        assert np.array_equal(L, before)
    assert done[True] >= 3 and done[False] >= 6, done
