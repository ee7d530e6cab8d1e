"""meshing.patch (an edit's remesh on the CPU) against full meshes of the new blocks on
both backends: random windows with every shape and render kind, changes on the chunk
edge, the world's floor and ceiling and region borders; its row greedy against the
NumPy reference's."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import meshing
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.meshing import aggregate, scenes
from voxel_addon.meshing.slices import greedy_rows

from .helpers import random_window

NAMES = ["air", "air", "stone", "grass", "leaves", "glass", "water", "water", "flowers",
         "wheat", "cactus", "log"]
IDS = [REGISTRY.id(n) for n in NAMES]
ZS = [0, 1, 2, 15, 16, 31, 32, 62, 63, 64, 65, 127, 128, 253, 254, 255] + list(range(46, 84))


def _same(got, want):
    assert np.array_equal(got.quads, want.quads)
    assert np.array_equal(got.vertices, want.vertices)
    assert np.array_equal(got.ranges, want.ranges)
    assert got.colors is None and want.colors is None


def _edits(seed, b, n):
    """n random changes in place (x, y from -1 to 16: the ring too); cells, old ids."""
    rng = np.random.default_rng(seed)
    cells, before = [], []
    for _ in range(n):
        x, y = (int(v) for v in rng.integers(-1, 17, 2))
        z = int(rng.choice(ZS))
        if rng.random() < 0.3 and cells:  # next to the last one, or the same cell again
            x, y, z = cells[-1][0] + int(rng.integers(-1, 2)), cells[-1][1], cells[-1][2]
            x = min(max(x, -1), 16)
        before.append(int(b[x + 1, y + 1, z]))
        b[x + 1, y + 1, z] = rng.choice(IDS)
        cells.append((x, y, z))
    return cells, before


@pytest.mark.parametrize("seed", range(24))
def test_patch_equals_full_mesh(seed):
    b = random_window(seed, shape=(18, 18, 256), band=(50, 80))
    b[:, :, 250:256] = b[:, :, 60:66]     # faces at the world's ceiling too
    rh = (64, 32, 16, 8)[seed % 4]
    old = meshing.build_chunk(b, region_h=rh)
    cells, before = _edits(seed, b, 1 + seed % 4)
    want = meshing.build_chunk(b, region_h=rh)
    _same(meshing.patch(old, b, cells, before), want)
    _same(meshing.patch(old, b, cells), want)          # no old ids: every slice again


def test_patch_equals_opencl_on_terrain(greedy_path):
    """Surface edits on real terrain (a window inside a bigger area: `origin`) against
    the OpenCL mesher; each patched mesh is the next edit's old one."""
    area = np.asfortranarray(scenes.blocks("landscape")[:34, :34])   # 2x2 chunks + ring
    meshes = meshing.build_chunks(area, backend="opencl")
    rng = np.random.default_rng(5)
    stone, flower = REGISTRY.id("stone"), REGISTRY.id("flowers")
    for i in range(30):
        x, y = (int(v) for v in rng.integers(0, 32, 2))
        z = int(np.flatnonzero(area[x + 1, y + 1])[-1]) + (i % 3 == 1)
        before = int(area[x + 1, y + 1, z])
        area[x + 1, y + 1, z] = (0, stone, flower)[i % 3]
        full = meshing.build_chunks(area, backend="opencl")
        for k in full:
            o = (16 * k[0], 16 * k[1])
            got = meshing.patch(meshes[k], area, [(x - o[0], y - o[1], z)], [before], o)
            _same(got, full[k])
            meshes[k] = got


def test_patch_refuses_colours():
    b = random_window(1, shape=(18, 18, 256), band=(50, 80))
    old = meshing.build_chunk(b)
    before = int(b[5, 5, 70])
    b[5, 5, 70] = REGISTRY.id("color")
    assert meshing.patch(old, b, [(4, 4, 70)], [before]) is None


def test_patch_unchanged_faces_keep_the_mesh():
    b = random_window(2, shape=(18, 18, 256), band=(50, 80))
    old = meshing.build_chunk(b)
    b[5, 5, 10] = REGISTRY.id("log")      # one opaque block for another inside rock
    assert meshing.patch(old, b, [(4, 4, 10)], [REGISTRY.id("stone")]) is old


@pytest.mark.parametrize("seed", range(6))
def test_greedy_rows_equals_reference(seed):
    rng = np.random.default_rng(seed)
    K = rng.choice([0, 0, 1, 2, 3], size=(5, 16, 40)).astype(np.uint16)
    K[:, 3:9, 5:30] = 2                    # big rects too
    s, v, u, h, w = aggregate.greedy(K)
    want = sorted(zip(s.tolist(), v.tolist(), u.tolist(), h.tolist(), w.tolist()))
    got = []
    for i, sl in enumerate(K):
        rows = []
        for row in sl:
            segs, u0 = [], 0
            while u0 < len(row):
                u1 = u0
                while u1 < len(row) and row[u1] == row[u0]:
                    u1 += 1
                if row[u0]:
                    segs.append((u0, u1, int(row[u0])))
                u0 = u1
            rows.append(segs)
        for v0, c, nr, nc, k in greedy_rows(rows):
            assert k == K[i, v0, c]
            got.append((i, v0, c, nr, nc))
    assert sorted(got) == want
