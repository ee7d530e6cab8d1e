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


def test_the_last_chunks_are_taken_in_without_waiting_a_frames_time(world_path):
    """LiveView._tick: after a frame the next redraw waits as long as the frame took
    (the stream's workers' share of the CPU), but not once the stream has made every
    chunk it wants (issue 28: the whole view came 0.45-1.3 s after the last batch)."""
    from voxel_addon.blender.liveview.feed import Feed
    from voxel_addon.blender.liveview.view import POLL_S, LiveView
    lv = LiveView()
    with World.create(world_path, seed=7, generator="flat") as w:
        f = lv.feed = Feed(str(world_path), w, 1)
        try:
            lv._news, lv._due = True, time.perf_counter() + 30.0  # after a 30 s frame
            f.stream.set_view(8.0, 8.0)
            left = lv._tick()  # the stream still works: wait, polling
            assert left is not None and 0 < left <= POLL_S
            assert f.stream.wait_ready(60) and f.stream.queued
            assert lv._tick() is None  # all made, some not drawn: redraw now
        finally:
            f.close()
