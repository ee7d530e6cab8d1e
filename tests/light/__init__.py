"""Shared checks of the light tests."""
import numpy as np

from voxel_addon.light import incremental


def part_edit(b, L, x, y, z, new, K):
    """Set (x, y, z) to `new` in a part window of K columns a side (an edit's first
    relight window: world/edit.py) and in the whole arrays (`b`, `L` updated by the
    full relight); assert the part got the whole relight's result with nothing
    changed outside it, or None with nothing written. Returns whether it was None."""
    sx, sy = slice(x - K, x + K + 1), slice(y - K, y + K + 1)
    pb, pl = b[sx, sy].copy(order="F"), L[sx, sy].copy(order="F")
    old = int(pb[K, K, z])
    pb[K, K, z] = new
    before = L.copy()
    got = incremental.update(pb, pl, K, K, z, old, part=True)
    incremental.edit(b, L, x, y, z, new)
    if got is None:
        assert np.array_equal(pl, before[sx, sy])           # nothing written
    else:
        assert np.array_equal(pl, L[sx, sy]), (x, y, z, new)
        outside = before != L
        outside[sx, sy] = False
        assert not outside.any(), (x, y, z, new)
    return got is None
