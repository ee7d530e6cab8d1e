"""The background builder: nearest tiles first, a view change never leaves a hole
(old tiles go only when every new tile over their area was handed out), bad
distances are refused."""
import time

import pytest

from voxel_addon.core.errors import VoxelError
from voxel_addon.far import Builder, grid
from voxel_addon.world import World

SEED = 7


def area(keys):
    return sum((grid.rect(k)[2] - grid.rect(k)[0]) ** 2 for k in keys)


def cells(keys):
    """The 64-block cells the tiles cover."""
    out = set()
    for k in keys:
        r = grid.rect(k)
        out |= {(x, y) for x in range(r[0] // 64, r[2] // 64) for y in range(r[1] // 64, r[3] // 64)}
    return out


def test_nearest_first_and_no_holes_when_the_view_moves(tmp_path, cl_device):
    with World.create(tmp_path / "w.sqlite", seed=SEED, backend="opencl") as w:
        with Builder(w.file, w.generator) as b:
            b.set_view(8.0, 8.0, far=24, near=2)
            order = []
            drawn = set()
            while True:
                ready, gone = b.drain(0.004)
                order += [m.key for m in ready]
                drawn |= {m.key for m in ready}
                drawn -= set(gone)
                if b.counts[0] == len(drawn):
                    break
                if b.error:
                    raise b.error
                time.sleep(0.002)
            dist = dict(grid.select(8.0, 8.0, 24, 2))
            d = [dist[k] for k in order]
            assert d == sorted(d)
            full = area(drawn)
            # walk: tiles split and merge; the drawn set always covers the ring it covered
            b.set_view(300.0, 8.0, far=24, near=2)
            want = {k for k, _ in grid.select(300.0, 8.0, 24, 2)}
            keep = cells(drawn) & cells(want)   # covered before and wanted after
            end = time.monotonic() + 60
            while time.monotonic() < end:
                ready, gone = b.drain(0.004)
                drawn |= {m.key for m in ready}
                drawn -= set(gone)
                # tiles may overlap for a moment, but what was covered stays covered
                assert keep <= cells(drawn)
                if drawn == want:
                    break
                time.sleep(0.002)
            assert drawn == want
            assert area(drawn) == full   # the ring moved, its area is the same


def test_gone_only_after_the_replacements(tmp_path, cl_device):
    with World.create(tmp_path / "w.sqlite", seed=SEED, backend="opencl") as w:
        with Builder(w.file, w.generator) as b:
            b.set_view(8.0, 8.0, far=16, near=0, detail=8)
            assert b.wait_ready(60)
            old = {m.key for m in b.drain(1.0)[0]}
            b.set_view(8.0, 8.0, far=16, near=0, detail=64)   # finer: coarse tiles split
            new = {k for k, _ in grid.select(8.0, 8.0, 16, 0, 64)}
            drawn = set(old)
            handed = set()
            while True:
                ready, gone = b.drain(0.004)
                handed |= {m.key for m in ready}
                for k in gone:
                    over = {n for n in new if not (grid.rect(n)[2] <= grid.rect(k)[0]
                                                   or grid.rect(n)[0] >= grid.rect(k)[2]
                                                   or grid.rect(n)[3] <= grid.rect(k)[1]
                                                   or grid.rect(n)[1] >= grid.rect(k)[3])}
                    assert over <= handed | (old & new)
                drawn = (drawn | handed) - set(gone)
                if drawn == new:
                    break
                if b.error:
                    raise b.error
                time.sleep(0.002)


def test_bad_distances(tmp_path):
    with World.create(tmp_path / "w.sqlite", seed=SEED, backend="numpy", loader=False) as w:
        with Builder(w.file, w.generator) as b:
            with pytest.raises(VoxelError):
                b.set_view(0, 0, far=257)
            with pytest.raises(VoxelError):
                b.set_view(0, 0, far=-1)
            b.set_view(0, 0, far=0)
            assert b.counts == (0, 0)
