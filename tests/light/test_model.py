"""Hand-built scenes with known answers (the model pinned in issue 4), both backends."""
import numpy as np
import pytest

from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.core.errors import VoxelError
from voxel_addon.light import full as solve, model, sampler

STONE, WATER, GLASS = R.id("stone"), R.id("water"), R.id("glass")


@pytest.fixture(params=["numpy", "opencl"])
def backend(request):
    if request.param == "opencl":
        request.getfixturevalue("cl_device")
    return request.param


def comp(light, k):
    return (light >> (4 * k)) & 0xF


def test_lamp_in_closed_cave_is_manhattan(backend):
    b = chunk.empty(np.uint16, 40, 40)
    b[...] = STONE
    b[10:31, 10:31, 90:111] = 0
    b[20, 20, 100] = R.id("lamp_red")
    L = solve.solve(b, backend)
    x, y, z = np.indices(b.shape)
    dist = abs(x - 20) + abs(y - 20) + abs(z - 100)
    cave = b == 0
    assert np.array_equal(comp(L, 0)[cave], np.maximum(0, 15 - dist)[cave])
    assert L[20, 20, 100] == 15  # the opaque lamp keeps its emission, D = 0
    assert not comp(L, 1).any() and not comp(L, 2).any() and not comp(L, 3).any()
    assert not L[b == STONE][dist[b == STONE] > 0].any()


def test_under_water_attenuates(backend):
    b = chunk.empty(np.uint16, 40, 40)
    b[:, :, :10] = STONE
    b[:, :, 10:30] = WATER
    b[20, 20, 9] = R.id("lamp_red")
    L = solve.solve(b, backend)
    z = np.arange(10, 30)
    assert np.array_equal(comp(L, 3)[5, 5, 10:30], np.maximum(0, 15 - 2 * (30 - z)))
    assert (comp(L, 3)[:, :, 30:] == 15).all()
    x, y, zz = np.indices(b.shape)
    dist = abs(x - 20) + abs(y - 20) + abs(zz - 9)
    w = b == WATER
    assert np.array_equal(comp(L, 0)[w], np.maximum(0, 15 - 3 * dist)[w])


def test_glass_lets_daylight_through(backend):
    b = chunk.empty(np.uint16, 24, 24)
    b[:, :, :50] = STONE
    b[4:20, 4:20, 50:60] = STONE
    b[5:19, 5:19, 50:59] = 0  # a room, its roof glass
    b[5:19, 5:19, 59] = GLASS
    L = solve.solve(b, backend)
    assert (comp(L, 3)[5:19, 5:19, 50:60] == 15).all()
    b[5:19, 5:19, 59] = STONE
    L = solve.solve(b, backend)
    assert not comp(L, 3)[5:19, 5:19, 50:59].any()


def test_daylight_into_cave_mouth(backend):
    b = chunk.empty(np.uint16, 48, 8)
    b[:, :, :60] = STONE
    b[5, 4, 45:60] = 0  # a shaft to the sky
    b[6:40, 4, 45] = 0  # a tunnel from its foot
    L = solve.solve(b, backend)
    assert (comp(L, 3)[5, 4, 45:] == 15).all()
    d = np.arange(1, 35)
    assert np.array_equal(comp(L, 3)[6:40, 4, 45], np.maximum(0, 15 - d))


def test_diagonal_spill(backend):
    """Two sealed caves touching only along a vertical edge: the cellular model keeps
    the dark one dark (no 26-neighbourhood steps), but sampling its floor next to the
    shared edge interpolates the lit voxel across it: the fig. 4.7 spill."""
    b = chunk.empty(np.uint16, 20, 20)
    b[...] = STONE
    b[1:6, 1:6, 100:103] = 0
    b[6:11, 6:11, 100:103] = 0
    b[2, 2, 101] = R.id("lamp_white")
    L = solve.solve(b, backend)
    assert comp(L, 0)[5, 5, 100] > 0
    assert not L[6:11, 6:11, 100:103].any()
    s = sampler.sample(L, [(6.0, 6.0, 100.0), (8.0, 8.0, 100.0)], [(0, 0, 1)] * 2)
    assert s[0, 0] == pytest.approx(comp(L, 0)[5, 5, 100] / 15 / 4)
    assert s[1, 0] == 0


def test_bad_input():
    with pytest.raises(VoxelError):
        solve.solve(np.zeros((4, 4, 10), np.uint16), "numpy")
    with pytest.raises(VoxelError):
        solve.solve(chunk.empty(), "cuda")
    with pytest.raises(VoxelError):
        solve.chunk_light(chunk.empty(np.uint16, 32, 48), "numpy")


def test_skips_known_sky():
    b = chunk.empty(np.uint16, 16, 16)
    b[:, :, :30] = STONE
    z0, z1 = model.slab(b)
    assert z1 == 31 and z0 == 29
    L = solve.solve(b, "numpy")
    assert (L[:, :, 30:] == model.SKY).all() and not L[:, :, :30].any()
