"""The voxel ray walk (core/ray.py) against a brute-force oracle: every solid voxel's
box intersected with the ray (slab test), the nearest one wins; chunk columns that
are not loaded cut the ray once it has met a loaded one."""
from __future__ import annotations

import math

import numpy as np
import pytest

from voxel_addon.core import ray
from voxel_addon.core.chunk import HEIGHT, SIZE

MAX = 300.0


def _world(rng, loaded, density=0.004, top=48):
    chunks = {}
    for key in loaded:
        b = np.zeros((SIZE, SIZE, HEIGHT), np.uint16, order="F")
        b[:, :, 0] = 1                                   # a floor everywhere
        m = rng.random((SIZE, SIZE, top)) < density
        b[:, :, :top][m] = rng.integers(1, 20, m.sum())
        chunks[key] = b
    return chunks


def _slab(o, d, lo, hi):
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = (lo - o) / d, (hi - o) / d
    near, far = np.minimum(a, b), np.maximum(a, b)
    inside = (o >= lo) & (o <= hi)
    near = np.where(d == 0, np.where(inside, -np.inf, np.inf), near)
    far = np.where(d == 0, np.where(inside, np.inf, -np.inf), far)
    return near, far


def oracle(o, d, chunks):
    d = d / np.linalg.norm(d)
    z0, z1 = _slab(o[2:], d[2:], 0.0, float(HEIGHT))
    t0, t1 = max(z0[0], 0.0), min(z1[0], MAX)
    if t0 > t1:
        return ("none",)
    # the first unloaded column after the first loaded one, among columns the ray crosses
    cols = []
    for cx in range(-12, 12):
        for cy in range(-12, 12):
            n, f = _slab(o[:2], d[:2], np.array([cx, cy]) * SIZE, np.array([cx + 1, cy + 1]) * SIZE)
            a, b = max(n.max(), t0), min(f.min(), t1)
            if a < b:
                cols.append((a, (cx, cy) in chunks))
    cols.sort()
    first = next((a for a, ok in cols if ok), math.inf)
    cut = next((a for a, ok in cols if not ok and a >= first), math.inf)
    best = (math.inf, None, None)
    for (cx, cy), b in chunks.items():
        xs, ys, zs = np.nonzero(b)
        cells = np.stack([xs + cx * SIZE, ys + cy * SIZE, zs], 1).astype(float)
        n, f = _slab(o, d, cells, cells + 1)
        near, far = n.max(1), f.min(1)
        ok = (near <= far) & (far >= 0) & (near <= t1)
        if not ok.any():
            continue
        near = np.where(ok, np.maximum(near, 0), np.inf)
        i = int(near.argmin())
        if near[i] < best[0]:
            ax = int(n[i].argmax())
            normal = (0, 0, 0) if n[i].max() < 0 else tuple(
                int(-np.sign(d[ax])) if k == ax else 0 for k in range(3))
            best = (near[i], tuple(int(v) for v in cells[i]), normal)
    if best[0] < cut:
        return ("hit", best[1], best[2], best[0])
    if cut < math.inf:
        return ("unloaded",)
    return ("none",)


def _check(o, d, chunks):
    got = ray.cast(o, d, lambda cx, cy: chunks.get((cx, cy)), max_dist=MAX)
    want = oracle(np.array(o, float), np.array(d, float), chunks)
    if want[0] == "hit":
        assert got.status == ray.HIT, (o, d, got, want)
        assert got.cell == want[1] and got.normal == want[2], (o, d, got, want)
        assert abs(got.t - want[3]) < 1e-6
        x, y, z = got.cell
        assert got.block == chunks[(x >> 4, y >> 4)][x & 15, y & 15, z]
    elif want[0] == "unloaded":
        assert got.status == ray.UNLOADED, (o, d, got, want)
    else:
        assert got.status in (ray.SKY, ray.BELOW), (o, d, got, want)


@pytest.mark.parametrize("seed", range(4))
def test_random_rays_match_the_slab_oracle(seed):
    rng = np.random.default_rng(seed)
    loaded = {(cx, cy) for cx in range(-3, 3) for cy in range(-3, 3)} - {(1, 1), (-2, 0)}
    chunks = _world(rng, loaded)
    for _ in range(100):
        o = rng.uniform([-48, -48, 1], [48, 48, 70])
        if rng.random() < 0.2:                      # eyes far outside, as orthographic views have
            o = o + rng.normal(size=3) * 150
        d = rng.normal(size=3)
        _check(o, d, chunks)


def test_axis_aligned_rays_and_faces():
    chunks = _world(np.random.default_rng(9), {(0, 0)}, density=0)
    chunks[(0, 0)][5, 6, 10] = 3
    get = lambda cx, cy: chunks.get((cx, cy))
    h = ray.cast((5.5, 6.5, 100.0), (0, 0, -1), get)
    assert (h.status, h.cell, h.normal, h.before, h.block) == ("hit", (5, 6, 10), (0, 0, 1), (5, 6, 11), 3)
    assert h.t == pytest.approx(89.0)
    h = ray.cast((0.5, 6.5, 10.5), (1, 0, 0), get)
    assert (h.cell, h.normal, h.before) == ((5, 6, 10), (-1, 0, 0), (4, 6, 10))
    h = ray.cast((5.5, 6.5, 5.0), (0, 0, 1), get)      # from below
    assert (h.cell, h.normal) == ((5, 6, 10), (0, 0, -1))
    h = ray.cast((5.5, 6.5, 500.0), (0, 0, -1), get)    # eye above the world (orthographic)
    assert h.cell == (5, 6, 10)
    h = ray.cast((5.5, 6.5, 10.5), (0, 1, 0), get)      # eye inside a block: no face
    assert h.normal == (0, 0, 0) and h.before is None
    assert ray.cast((2.5, 2.5, 1.5), (0, 0, 1), get).status == ray.SKY
    assert ray.cast((2.5, 2.5, -3.0), (0, 0, -1), get).status == ray.BELOW
    assert ray.cast((2.5, 2.5, 300.0), (0, 0, 1), get).status == ray.SKY
    # the floor's top from above; a floor cell at z = 0 has no cell below it to place into
    h = ray.cast((2.5, 2.5, 0.5), (0, 0, -1), get)
    assert h.cell == (2, 2, 0)


def test_unloaded_chunks_cut_the_ray_only_after_a_loaded_one():
    chunks = _world(np.random.default_rng(1), {(0, 0)}, density=0)
    chunks[(0, 0)][:, :, 0] = 0
    chunks[(0, 0)][8, 8, 3] = 1
    get = lambda cx, cy: chunks.get((cx, cy))
    # from far away across unloaded chunks into the loaded one: hits
    h = ray.cast((-200.5, 8.5, 3.5), (1, 0, 0), get)
    assert h.cell == (8, 8, 3)
    # from inside the loaded chunk out into an unloaded one: unknown
    assert ray.cast((2.5, 2.5, 3.5), (-1, 0, 0), get).status == ray.UNLOADED


def test_ignore_cells_and_solid_table():
    chunks = _world(np.random.default_rng(2), {(0, 0)}, density=0)
    chunks[(0, 0)][4, 4, 1] = 16                          # water above the floor
    get = lambda cx, cy: chunks.get((cx, cy))
    assert ray.cast((4.5, 4.5, 9.0), (0, 0, -1), get).cell == (4, 4, 1)
    assert ray.cast((4.5, 4.5, 9.0), (0, 0, -1), get, ignore={(4, 4, 1)}).cell == (4, 4, 0)
    solid = np.ones(32, bool)
    solid[[0, 16]] = False
    assert ray.cast((4.5, 4.5, 9.0), (0, 0, -1), get, solid=solid).cell == (4, 4, 0)
