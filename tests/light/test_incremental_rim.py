"""The incremental relight's box takes its 1-voxel rim from the old light (incremental.py):
each of the six rim sides must matter. Two lamps 28 apart in a stone corridor: the box
around the removed one ends 14 voxels from it, so the last voxel inside it gets its 1
from the other lamp only through the rim. A full solve is the oracle (whole volume)."""
import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.light import full, incremental

STONE, RED = R.id("stone"), R.id("lamp_red")


def _corridor(axis: int, sign: int):
    """Stone (sealed from the sky) with a 1-voxel corridor along `axis`; lamps at
    c and c + sign * 28. Returns blocks and the position of the lamp at c."""
    shape = [48, 24, 256]
    b = np.zeros(shape, np.uint16, order="F")
    b[:, :, :80] = STONE
    p = [10, 10, 10]
    p[axis] = 30 if sign < 0 else 2
    lo, hi = min(p[axis], p[axis] + 28 * sign), max(p[axis], p[axis] + 28 * sign)
    if axis == 2:
        p[axis] += 10  # keep the corridor off the array's floor
        lo, hi = lo + 10, hi + 10
    if axis == 1:
        b = np.zeros((24, 48, 256), np.uint16, order="F")
        b[:, :, :80] = STONE
    run = [slice(v, v + 1) for v in p]
    run[axis] = slice(lo, hi + 1)
    b[tuple(run)] = 0
    q = list(p)
    q[axis] += 28 * sign
    b[tuple(p)] = RED
    b[tuple(q)] = RED
    return b, tuple(p)


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("sign", [1, -1])
def test_lamp_removal_next_to_rim(axis, sign):
    """sign -1 removes the lamp at 30 with the other at 2 (the -axis rim matters;
    for x: voxel (16, 10, 10) must stay 1); sign +1 mirrors it (the +axis rim)."""
    b, p = _corridor(axis, sign)
    L = full.solve(b, "numpy")
    edge = list(p)
    edge[axis] -= 14 * (1 if sign < 0 else -1)
    assert L[tuple(edge)] & 15 == 1  # both lamps light it to exactly 1
    incremental.edit(b, L, *p, 0)
    want = full.solve(b, "numpy")
    assert want[tuple(edge)] & 15 == 1  # the lamp left over still does
    assert np.array_equal(L, want)


@pytest.mark.parametrize("axis", [0, 1])
@pytest.mark.parametrize("sign", [1, -1])
def test_shaft_closing_next_to_rim(axis, sign):
    """Daylight: two sky shafts 28 apart joined by a tunnel at z 10; closing one at
    the tunnel leaves the voxel 14 from it lit by the other shaft through the rim."""
    shape = (48, 24, 256) if axis == 0 else (24, 48, 256)
    b = np.zeros(shape, np.uint16, order="F")
    b[:, :, :80] = STONE
    p = [10, 10, 10]
    p[axis] = 30 if sign < 0 else 2
    q = list(p)
    q[axis] += 28 * sign
    run = [slice(10, 11)] * 3
    run[axis] = slice(min(p[axis], q[axis]), max(p[axis], q[axis]) + 1)
    b[tuple(run)] = 0
    for s in (p, q):
        b[s[0], s[1], 10:] = 0
    L = full.solve(b, "numpy")
    edge = list(p)
    edge[axis] -= 14 * (1 if sign < 0 else -1)
    assert L[tuple(edge)] >> 12 == 1
    incremental.edit(b, L, *p, STONE)
    want = full.solve(b, "numpy")
    assert want[tuple(edge)] >> 12 == 1
    assert np.array_equal(L, want)
