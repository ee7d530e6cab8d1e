import itertools

import pytest

from voxel_addon.core import brush
from voxel_addon.core.errors import VoxelError


@pytest.mark.parametrize("size", range(1, 9))
def test_cube_and_sphere(size):
    c = brush.cells((10, 20, 100), size, "CUBE")
    assert len(c) == size ** 3 == len(set(c))
    assert (10, 20, 100) in c
    xs = sorted({p[0] for p in c})
    assert xs == list(range(10 - (size - 1) // 2, 10 + size // 2 + 1))
    s = set(brush.cells((10, 20, 100), size, "SPHERE"))
    assert (10, 20, 100) in s and s <= set(c)
    if size >= 3:
        assert len(s) < len(c)                    # corners cut
    # symmetric about the brush centre
    m = sum(xs) / len(xs)
    assert {(round(2 * m - x), y, z) for x, y, z in s} == {(x, y, z) for x, y, z in s} or size % 2 == 0


def test_clipped_to_the_world_and_refusals():
    assert all(0 <= z <= 255 for _, _, z in brush.cells((0, 0, 255), 4))
    assert len(brush.cells((0, 0, 0), 3)) == 18
    with pytest.raises(VoxelError):
        brush.cells((0, 0, 0), 9)
    with pytest.raises(VoxelError):
        brush.cells((0, 0, 0), 1, "CONE")


def test_box():
    b = brush.box((3, 1, 5), (1, 2, 5))
    assert sorted(b) == sorted(itertools.product(range(1, 4), range(1, 3), [5]))
    assert len(brush.box((0, 0, 250), (0, 0, 300))) == 6
    with pytest.raises(VoxelError):
        brush.box((0, 0, 0), (100, 100, 100))
