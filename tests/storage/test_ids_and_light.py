"""What the file holds, re-read with plain sqlite3: edits in the file's own block ids
(a file written by another version numbers its types differently), and stored light
only where it still holds (light is derived data: a stale row is a wrong picture
after a crash)."""
from __future__ import annotations

import sqlite3

import numpy as np

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.storage import WorldFile
from voxel_addon.world import World, build
from voxel_addon.world.edit import edit

GLASS, LAMP = REGISTRY.id("glass"), REGISTRY.id("lamp_red")


def foreign(path):
    """A file whose block table numbers types unlike the registry."""
    WorldFile.create(path, seed=1, generator="flat", generator_version=1).close()
    db = sqlite3.connect(path)
    db.execute("DELETE FROM block_types")
    db.executemany("INSERT INTO block_types VALUES (?, ?)",
                   [(0, "air"), (3, "water"), (9, "stone"), (12, "dirt"), (13, "grass")])
    db.commit()
    db.close()


def test_edits_are_stored_in_file_ids(world_path):
    foreign(world_path)
    with World.open(world_path, loader=False) as w:
        w.set_block(3, 4, 100, "glass", 7)
        w.set_blocks([(20, 4, 101)], [LAMP])
        w.flush()
    db = sqlite3.connect(world_path)
    names = dict(db.execute("SELECT id, name FROM block_types"))
    rows = sorted(db.execute("SELECT x, y, z, block, data FROM edits"))
    db.close()
    assert [(x, y, z, names[b], d) for x, y, z, b, d in rows] == \
        [(3, 4, 100, "glass", 7), (20, 4, 101, "lamp_red", 0)]
    with World.open(world_path, loader=False) as w:   # regenerated: the edits come back
        w.recreate(keep_edits=True)
        assert w.get_block(3, 4, 100) == GLASS and w.chunk_at(0, 0).data[3, 4, 100] == 7
        assert w.get_block(20, 4, 101) == LAMP


def light_rows(path):
    db = sqlite3.connect(path)
    try:
        return {tuple(r) for r in db.execute("SELECT cx, cy FROM light")}, \
            {tuple(r) for r in db.execute("SELECT cx, cy FROM chunks")}
    finally:
        db.close()


def test_no_light_row_outlives_its_chunk(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        build.light_and_mesh(w, -1, -1, 2, 2)
        w.flush()
        lit, held = light_rows(world_path)
        assert lit and lit <= held
        w.recreate(keep_edits=True)
        lit, held = light_rows(world_path)
        assert lit <= held


def test_a_committed_edit_leaves_no_stale_light_beside_it(world_path):
    """A lamp at a chunk border is committed; the neighbour it relit is saved later.
    Read at that moment (as after a crash), the file must not hand out the
    neighbour's old light: it holds the new light or none (recomputed)."""
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        build.light_and_mesh(w, -1, -1, 3, 2)
        w.flush()
        top = int(np.flatnonzero(w.chunk_at(0, 0).blocks[15, 8])[-1])
        old = w.chunk_at(1, 0).light
        edit(w, (15, 8, top + 1, LAMP))              # chunk (0, 0); lights (1, 0) too
        w.settle()                                   # its write (the writer thread) done
        new = w.chunk_at(1, 0).light
        assert not np.array_equal(old, new)
        with World.open(world_path, loader=False, readonly=True) as r:
            got = r.file.read_chunk((1, 0), light=True)[2]
        assert got is None or np.array_equal(got, new)
