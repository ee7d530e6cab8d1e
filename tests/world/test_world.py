"""Chunk lifecycle with the real loader thread and a real SQLite file."""
from __future__ import annotations

import hashlib
import threading
import time

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.world import World

STONE, LAMP = REGISTRY.id("stone"), REGISTRY.id("lamp_red")


def wait_for(fn, timeout=20.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = fn()
        if v:
            return v
        time.sleep(0.01)
    raise AssertionError("timed out")


def test_three_access_functions(world_path):
    with World.create(world_path, seed=1, generator="flat") as w:
        assert w.maybe_chunk_at(3, 4) is None
        assert w.maybe_load_chunk_at(3, 4) is None        # queued, not loaded yet
        c = wait_for(lambda: w.maybe_chunk_at(3, 4))      # the loader thread did it
        assert c.key == (3, 4) and c.get(0, 0, 0) == STONE
        assert w.chunk_at(-7, 2).key == (-7, 2)           # synchronous
        assert w.get_block(-7 * 16 + 3, 2 * 16, 0) == STONE


def test_idle_chunks_are_saved_and_unloaded(world_path):
    with World.create(world_path, seed=1, generator="flat", idle_timeout=0.2) as w:
        w.set_block(5, 6, 100, LAMP)
        wait_for(lambda: w.maybe_chunk_at(0, 0) is None)
        assert w.file.has_chunk((0, 0))
        assert w.get_block(5, 6, 100) == LAMP               # reloaded from the file


def test_concurrent_edits_and_unloads_lose_nothing(world_path):
    """Writers hammer blocks over 16 chunks while a tiny idle timeout unloads them."""
    expect = {}
    lock = threading.Lock()
    with World.create(world_path, seed=1, generator="flat", idle_timeout=0.005) as w:
        def writer(seed):
            rng = np.random.default_rng(seed)
            for _ in range(300):
                x, y, z = int(rng.integers(0, 64)), int(rng.integers(0, 64)), int(rng.integers(64, 200))
                b = int(rng.integers(1, len(REGISTRY)))
                with lock:  # the expectation must follow the world's order of writes
                    w.set_block(x, y, z, b)
                    expect[(x, y, z)] = b
                if rng.random() < 0.05:
                    w.unload_idle()
                if rng.random() < 0.05:
                    w.flush()
        threads = [threading.Thread(target=writer, args=(s,)) for s in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert w.loader_error is None
    with World.open(world_path, loader=False) as w:
        got = {k: w.get_block(*k) for k in expect}
    assert got == expect
    with World.open(world_path, loader=False) as w:  # and the edits table has them all
        edits = {}
        for cx in range(4):
            for cy in range(4):
                edits.update({(x, y, z): b for x, y, z, b, _ in w.file.edits_in((cx, cy))})
    assert edits == expect


def test_recreate_keeps_edits(world_path):
    with World.create(world_path, seed=1, generator="flat") as w:
        w.set_block(1, 1, 120, "glass")
        w.set_block(1, 1, 10, "air")
        w.flush()
        w.recreate(keep_edits=True)
        assert w.file.chunk_count() == 0
        assert w.get_block(1, 1, 120) == REGISTRY.id("glass")
        assert w.get_block(1, 1, 10) == 0 and w.get_block(1, 1, 11) == STONE
        w.recreate(keep_edits=False)
        assert w.get_block(1, 1, 120) == 0


def test_readonly_world_generates_in_memory_only(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0)])
    digest = hashlib.sha256(world_path.read_bytes()).hexdigest()
    with World.open(world_path, readonly=True, loader=False) as w:
        region = w.region_blocks(-1, -1, 2, 2)
        assert region.shape == (48, 48, 256) and (region[:, :, 0] == STONE).all()
        with pytest.raises(VoxelError):
            w.set_block(0, 0, 0, "air")
    assert hashlib.sha256(world_path.read_bytes()).hexdigest() == digest


def test_region_blocks_layout(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.set_block(-1, 17, 200, "sand")      # chunk (-1, 1), local (15, 1)
        r = w.region_blocks(-1, 0, 1, 2)      # x from -16, y from 0
        assert r.flags.f_contiguous
        assert r[15, 17, 200] == REGISTRY.id("sand")
        assert (r[:, :, 200] != 0).sum() == 1


def test_stored_edits_keep_data_values_both_ways(world_path):
    """Chunks regenerated on demand and by generate_area get the stored edits the
    same way, data values included (one place applies them)."""
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.set_block(3, 4, 100, "glass", 7)
        w.set_block(20, 4, 100, "glass", 9)
        w.flush()
        w.recreate(keep_edits=True)
        assert w.generate_area([(1, 0)]) == 1              # to the file, not resident
        c = w.chunk_at(0, 0)                               # generated on demand
        assert c.get(3, 4, 100) == REGISTRY.id("glass") and c.data[3, 4, 100] == 7
    with World.open(world_path, loader=False) as w:
        blocks, data = w.file.read_chunk((1, 0))
        assert blocks[4, 4, 100] == REGISTRY.id("glass") and data[4, 4, 100] == 9


def test_colour_palette_follows_the_file(world_path):
    from voxel_addon.core import colors
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        assert w.colors().tolist() == [[255, 255, 255]]
        pal, idx = colors.add(w.colors(), [(1, 2, 3), (255, 255, 255)])
        assert idx.tolist() == [1, 0]
        w.file.set_meta(colors.KEY, colors.dump(pal))
        assert w.colors().tolist() == [[255, 255, 255], [1, 2, 3]]
    with World.open(world_path, loader=False, readonly=True) as w:
        assert w.colors()[1].tolist() == [1, 2, 3]


def test_numpy_coordinates_read_the_stored_chunk(world_path):
    """A voxel asked for with NumPy ints (a test's or a tool's array arithmetic) is
    the stored one: such a key once activated an empty chunk in a read-only world."""
    with World.create(world_path, seed=1, generator="flat") as w:
        w.set_block(3, -7, 100, "stone")
    with World.open(world_path, readonly=True) as w:
        x, y, z = np.array([3, -7, 100])
        assert w.get_block(x, y, z) == REGISTRY.id("stone") == w.get_block(3, -7, 100)
