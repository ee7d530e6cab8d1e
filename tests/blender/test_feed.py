"""The live view's feed (blender/liveview/feed.py) with a real world and stream: its
generation says whether anything a window uploads changed (Pane.sync skips its walk
over every chunk while it stays)."""
from __future__ import annotations

import time

from voxel_addon.world import World


def test_gen_moves_exactly_when_the_chunks_change(world_path):
    from voxel_addon.blender.liveview.feed import Feed
    with World.create(world_path, seed=7, generator="flat") as w:
        f = Feed(str(world_path), w, 1)
        try:
            def step(at):
                before, gen = dict(f.chunks), f.gen
                f.update(at, (1.0, 0.0, 0.0), 1.0)
                changed = f.chunks.keys() != before.keys() or any(
                    f.chunks[k] is not before[k] for k in before)
                assert (f.gen != gen) == changed, (at, gen, f.gen)
                return changed
            t0, moved = time.monotonic(), 0
            while len(f.chunks) < 9 and time.monotonic() - t0 < 60:
                moved += step((8.0, 8.0))
                time.sleep(0.01)
            assert len(f.chunks) == 9 and moved
            assert not step((8.0, 8.0))  # nothing new: the same generation
            assert step((16.0 * 10, 8.0))  # the view left: its chunks went
        finally:
            f.close()
