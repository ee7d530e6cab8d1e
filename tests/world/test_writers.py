"""Two writers on one world file (issue 26): two World objects on one real SQLite
file stand for two processes (each has its own connection); tests/world/test_races.py
runs real processes. A stale copy is merged, never written over; another writer's
changes are taken in (data_version); undo leaves others' edits alone; a file deleted
or moved while open fails the next save."""
from __future__ import annotations

import os
import sqlite3

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.world import World
from voxel_addon.world import edit as E

STONE, GLASS, LAMP = REGISTRY.id("stone"), REGISTRY.id("glass"), REGISTRY.id("lamp_red")


def edit(world, changes, write=True):
    """world.edit.edit, its write done (the writer thread): the other writer sees it."""
    out = E.edit(world, changes, write)
    world.settle()
    return out


def undo(world, rec):
    out = E.undo(world, rec)
    world.settle()
    return out


@pytest.fixture
def path(tmp_path):
    p = tmp_path / "w.sqlite"
    with World.create(p, seed=2, generator="flat", loader=False) as w:
        w.chunk_at(0, 0)
    return p


def stored(path, x, y, z):
    with World.open(path, loader=False, readonly=True) as w:
        return w.get_block(x, y, z)


def test_stale_copies_merge_their_own_voxels(path):
    """Both load chunk (0, 0), both change it: every change ends up in the file, in
    both edits tables' rows and in the writers' memory; edits, set_block and set_blocks."""
    a, b = World.open(path, loader=False), World.open(path, loader=False)
    try:
        a.chunk_at(0, 0), b.chunk_at(0, 0)
        edit(a, (1, 1, 100, STONE))
        b.set_block(2, 1, 100, GLASS)
        b.set_blocks([(3, 1, 100), (4, 1, 101)], [LAMP, STONE])
        b.flush()                                # stale: a wrote since b read it
        assert [stored(path, x, 1, 100) for x in (1, 2, 3)] == [STONE, GLASS, LAMP]
        assert stored(path, 4, 1, 101) == STONE
        # b's memory holds the merge, light and mesh dropped for remaking
        assert b.get_block(1, 1, 100) == STONE and b.chunks[(0, 0)].light is None
        edit(a, (5, 1, 100, GLASS), write=False)  # a is stale now: its commit merges
        a.flush()
        assert [stored(path, x, 1, 100) for x in (1, 2, 3, 5)] == [STONE, GLASS, LAMP, GLASS]
        assert a.get_block(2, 1, 100) == GLASS
        # a voxel both changed: the later write wins
        edit(a, (6, 1, 100, STONE), write=False)
        b.set_block(6, 1, 100, GLASS)
        b.flush()
        a.flush()
        assert stored(path, 6, 1, 100) == STONE
    finally:
        a.close()
        b.close()
    with World.open(path, loader=False) as w:
        assert w.file.edit_count() == 6  # one row per voxel


def test_a_generated_copy_never_replaces_a_stored_chunk(path):
    """A chunk generated (not edited) while another writer stored it: the stored
    one stays, and the generated copy in memory becomes the stored one."""
    a, b = World.open(path, loader=False), World.open(path, loader=False)
    try:
        a.chunk_at(5, 5)                   # generated in a, not stored yet
        edit(b, (80, 80, 100, STONE))      # b generates, edits and stores it
        a.flush()
        assert stored(path, 80, 80, 100) == STONE
        assert a.get_block(80, 80, 100) == STONE
    finally:
        a.close()
        b.close()


def test_a_file_from_before_versions_still_merges(path):
    """A file written before chunk_versions (no table, no triggers) opens, gets them,
    and two writers on it still merge."""
    db = sqlite3.connect(path)
    for t in ("chunk_version_insert", "chunk_version_update", "chunk_version_delete"):
        db.execute(f"DROP TRIGGER {t}")
    db.execute("DROP TABLE chunk_versions")
    db.commit()
    db.close()
    a, b = World.open(path, loader=False), World.open(path, loader=False)
    try:
        a.set_block(1, 2, 100, STONE)
        b.set_block(2, 2, 100, GLASS)
        a.flush()
        b.flush()
    finally:
        a.close()
        b.close()
    assert (stored(path, 1, 2, 100), stored(path, 2, 2, 100)) == (STONE, GLASS)
    with World.open(path, loader=False, readonly=True) as w:  # versions read back too
        assert w.file.version((0, 0)) > 0


def test_refresh_takes_in_another_writers_chunks(path):
    a, b = World.open(path, loader=False), World.open(path, loader=False)
    try:
        a.chunk_at(0, 0)
        assert a.refresh() == set()        # nothing written: a pragma, no reload
        a.set_block(9, 9, 120, LAMP)       # own unsaved change
        v0 = a.bver[(0, 0)]
        edit(b, (3, 3, 100, STONE))
        assert a.refresh() == {(0, 0)}
        assert a.get_block(3, 3, 100) == STONE and a.get_block(9, 9, 120) == LAMP
        assert a.bver[(0, 0)] > v0 and a.chunks[(0, 0)].light is None
        assert a.refresh() == set()        # nothing new since
        a.flush()                          # not stale: refresh moved its version on
        assert stored(path, 3, 3, 100) == STONE and stored(path, 9, 9, 120) == LAMP
        assert b.refresh() == {(0, 0)}     # a's write is news to b
        assert b.get_block(9, 9, 120) == LAMP
    finally:
        a.close()
        b.close()


def test_undo_never_undoes_another_writers_edit(path):
    a, b = World.open(path, loader=False), World.open(path, loader=False)
    try:
        _, rec = edit(a, [(1, 4, 100, STONE), (2, 4, 100, STONE)])
        edit(b, (2, 4, 100, GLASS))        # b overwrote one of a's voxels
        undo(a, rec)
        assert stored(path, 1, 4, 100) == 0        # a's own voxel undone
        assert stored(path, 2, 4, 100) == GLASS    # b's edit stays
        assert a.get_block(2, 4, 100) == GLASS
    finally:
        a.close()
        b.close()


@pytest.mark.parametrize("how", ["deleted", "moved", "replaced"])
def test_a_file_gone_while_open_fails_the_next_save(path, tmp_path, how):
    w = World.open(path, loader=False)
    edit(w, (1, 1, 100, STONE))
    if how == "deleted":
        os.remove(path)
    elif how == "moved":
        os.rename(path, tmp_path / "elsewhere.sqlite")
    else:
        os.rename(path, tmp_path / "old.sqlite")
        with World.create(path, seed=2, generator="flat", loader=False):
            pass
    assert w.file.gone()
    with pytest.raises(VoxelError, match="deleted or moved|replaced"):
        edit(w, (2, 1, 100, GLASS))
    assert (2, 1, 100, GLASS, 0) in w.unsaved_edits()   # kept for the rescue file
    with pytest.raises(VoxelError):
        w.close()
    w.discard()


def test_a_file_damaged_while_open_shows_in_its_header(path):
    """WorldFile.damage_seen reads the file's header (a read through the connection
    may be served by its -wal): cut short, overwritten by other bytes, or whole."""
    w = World.open(path, loader=False)
    try:
        edit(w, (1, 1, 100, STONE))   # (its pages in the -wal now)
        assert w.file.damage_seen() is None and not w.file.gone()
        size = os.path.getsize(path)
        with open(path, "r+b") as f:
            f.truncate(size - 4096)
        assert w.file.damage_seen() == "cut short"
        with open(path, "r+b") as f:
            f.truncate(50)
        assert w.file.damage_seen() == "cut short"
        with open(path, "r+b") as f:
            f.write(b"x" * 200)
        assert w.file.damage_seen() == "overwritten"
    finally:
        w.discard()


def test_store_chunks_keeps_or_merges_per_chunk(path):
    """An import decides per chunk at write time: without replace a stored chunk is
    kept; with replace, edits saved since the import started survive."""
    import time
    blocks = np.full((16, 16, 256), STONE, np.uint16, order="F")
    imp, ed = World.open(path, loader=False), World.open(path, loader=False)
    try:
        start = time.time()
        edit(ed, (40, 40, 100, GLASS))                 # chunk (2, 2) appears meanwhile
        kept = imp.store_chunks([((2, 2), blocks, None), ((3, 3), blocks, None)],
                                replace=False, since=start)
        assert kept == [(2, 2)]
        assert stored(path, 40, 40, 100) == GLASS and stored(path, 40, 40, 99) == 0
        assert stored(path, 50, 50, 99) == STONE
        edit(ed, (50, 50, 100, GLASS))                 # (3, 3): edited after the start
        assert imp.store_chunks([((3, 3), blocks, None)], replace=True, since=start) == []
        assert stored(path, 50, 50, 100) == GLASS and stored(path, 50, 50, 101) == STONE
    finally:
        imp.close()
        ed.close()


def test_a_merge_drops_the_stored_light_around_it(path):
    """The light b solved around its stale copy no longer holds once a's lamp is
    merged in: no light row of the 3x3 survives b's write (it is solved again)."""
    a, b = World.open(path, loader=False), World.open(path, loader=False)
    try:
        edit(b, (2, 1, 100, STONE), write=False)   # b relights its neighbours too
        edit(a, (1, 1, 100, LAMP))
        b.flush()                                  # ... and writes them with that light
        rows = sqlite3.connect(path).execute(
            "SELECT cx, cy FROM light WHERE cx BETWEEN -1 AND 1 AND cy BETWEEN -1 AND 1"
        ).fetchall()
        assert rows == [], rows
        assert (stored(path, 1, 1, 100), stored(path, 2, 1, 100)) == (LAMP, STONE)
    finally:
        a.close()
        b.close()
