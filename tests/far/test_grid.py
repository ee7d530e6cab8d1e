"""Levels and tiles: a view's selection covers the ring once, nearest first, each
level far enough for its spacing; `touching` finds every tile sampling a chunk."""
import numpy as np
import pytest

from voxel_addon.far import grid


@pytest.mark.parametrize("x,y,far,near", [(8, 8, 64, 16), (-3000.5, 517.0, 128, 8),
                                          (100, -20, 24, 0)])
def test_selection_covers_the_ring_once(x, y, far, near):
    sel = grid.select(x, y, far, near)
    keys = [k for k, _ in sel]
    assert len(set(keys)) == len(keys)
    vcx, vcy = int(np.floor(x)) >> 4, int(np.floor(y)) >> 4
    # rasterise at 16 blocks (every tile edge is a multiple of 64)
    x0, y0 = 16 * (vcx - far) - 2048, 16 * (vcy - far) - 2048
    n = (2 * far + 1) + 256
    hits = np.zeros((n, n), np.int32)
    for k in keys:
        r = grid.rect(k)
        hits[(r[0] - x0) // 16:(r[2] - x0) // 16, (r[1] - y0) // 16:(r[3] - y0) // 16] += 1
    assert hits.max() == 1  # no two tiles overlap
    ring = np.zeros_like(hits, bool)
    o = (vcx - far) * 16 - x0
    ring[o // 16:o // 16 + 2 * far + 1, (16 * (vcy - far) - y0) // 16:
         (16 * (vcy - far) - y0) // 16 + 2 * far + 1] = True
    inner = np.zeros_like(ring)
    if near:
        a, b = (16 * (vcx - near) - x0) // 16, (16 * (vcy - near) - y0) // 16
        inner[a:a + 2 * near + 1, b:b + 2 * near + 1] = True
    assert hits[ring & ~inner].min() == 1  # the whole ring is covered
    # each tile is as coarse as its distance allows, and no finer than needed
    for k, d in sel:
        s = grid.spacing(k[0])
        if k[0] > grid.LEVELS[0]:
            assert d >= grid.DETAIL * s
        if k[0] < grid.LEVELS[-1]:
            parent = (k[0] + 1, k[1] >> 1, k[2] >> 1)
            assert grid._dist(x, y, grid.rect(parent)) < grid.DETAIL * 2 * s
    ds = [d for _, d in sel]
    assert ds == sorted(ds)


def test_columns_are_point_samples_shared_by_levels():
    key = (3, -2, 5)
    X, Y = grid.columns(key)
    assert X.shape == (grid.N, grid.N)
    s, x0, y0 = 8, -2 * 32 * 8, 5 * 32 * 8
    assert X[1, 0] == x0 and Y[0, 1] == y0 and X[0, 0] == x0 - s and X[-1, 0] == x0 + 33 * s
    # the coarser level's samples are every other sample of the finer one
    fine = grid.columns((2, -4, 10))
    assert X[1, 1] == fine[0][1, 1] and X[2, 1] == fine[0][3, 1]


def test_touching_is_every_tile_sampling_the_chunk():
    for cx, cy in [(0, 0), (-1, 3), (37, -64)]:
        got = set(grid.touching(cx, cy))
        want = set()
        for level in grid.LEVELS:
            w = grid.span(level)
            for tx in range(cx * 16 // w - 2, cx * 16 // w + 3):
                for ty in range(cy * 16 // w - 2, cy * 16 // w + 3):
                    X, Y = grid.columns((level, tx, ty))
                    if ((X >> 4 == cx) & (Y >> 4 == cy)).any():
                        want.add((level, tx, ty))
        assert want <= got
        # extra tiles only where cells (not samples) touch the chunk: at most one ring
        assert len(got) <= len(want) + 4 * len(grid.LEVELS)
