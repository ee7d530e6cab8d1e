"""The far tables in a real world file: tiles survive reopening (a second view is
only loaded), chunk writes dirty what lies over them (triggers, whoever writes),
another generator signature clears them, damaged rows are rebuilt, a read-only
file keeps its far data in memory."""
import sqlite3

import numpy as np

from voxel_addon.far import Builder, grid, signature
from voxel_addon.far.tiles import empty
from voxel_addon.storage import WorldFile
from voxel_addon.storage.far import FarStore
from voxel_addon.world import World

SEED = 7


def _view(b, far=20):
    b.set_view(8.0, 8.0, far=far, near=4)
    assert b.wait_ready(120)
    return b.drain(1.0)[0]


def test_second_view_is_loaded_not_built(tmp_path, cl_device):
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=SEED, backend="opencl") as w:
        with Builder(w.file, w.generator) as b:
            first = _view(b)
            assert b.stats["built"] == len(first) > 0 and b.stats["loaded"] == 0
    with World.open(path, backend="opencl") as w:
        with Builder(w.file, w.generator) as b:
            second = _view(b)
            assert b.stats["built"] == 0 and b.stats["loaded"] == len(first)
    a = {m.key: m for m in first}
    for m in second:
        assert np.array_equal(m.vertices, a[m.key].vertices)
        assert np.array_equal(m.ground, a[m.key].ground)


def test_chunk_writes_dirty_the_tiles_over_them(tmp_path):
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=SEED, backend="numpy", loader=False) as w:
        store = FarStore(w.file, signature(w.generator))
        a = empty()
        a["height"][:] = 70
        store.put_tiles([((1, 0, 0), a), ((3, 5, 5), a)])
        store.put_columns([((0, 0), empty(16))])
        w.generate_area([(0, 0)])           # any writer: the trigger sees it
        assert store.columns((0, 0)) is None
        gone = store.take_dirty(lambda cs: {k for c in cs for k in grid.touching(*c)})
        assert (1, 0, 0) in gone and (3, 5, 5) not in gone
        assert store.tile((1, 0, 0), grid.N) is None
        assert store.tile((3, 5, 5), grid.N)["height"][0, 0] == 70
        assert store.take_dirty(lambda cs: set()) == set()
        w.set_block(-20, 5, 100, "stone")
        w.flush()
        store.take_dirty(lambda cs: set())
        w.file.clear_edits()           # edits gone: the tiles they raised are stale
        got = store.take_dirty(lambda cs: {(9,) + c for c in cs})
        assert got == {(9, -2, 0)}


def test_dirty_rows_naming_no_chunk_are_dropped(tmp_path):
    # a hostile file's far_dirty row of text or reals made `far` a TypeError's
    # traceback (tiles_of computed with them); now dropped with the good ones
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=SEED, backend="numpy", loader=False) as w:
        store = FarStore(w.file, signature(w.generator))
        w.generate_area([(0, 0)])
        db = sqlite3.connect(path)
        db.executemany("INSERT INTO far_dirty VALUES (?, ?)",
                       [("a", 0), (2.5, 1), (1 << 40, 0), (0, 1 << 26)])
        db.commit()
        seen = []
        store.take_dirty(lambda cs: seen.extend(cs) or set())
        assert seen == [(0, 0)]
        assert db.execute("SELECT COUNT(*) FROM far_dirty").fetchone()[0] == 0
        db.close()


def test_other_generator_clears(tmp_path):
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=SEED, backend="numpy", loader=False) as w:
        FarStore(w.file, "one").put_tiles([((2, 0, 0), empty())])
        assert FarStore(w.file, "one").tile((2, 0, 0), grid.N) is not None
        assert FarStore(w.file, "two").tile((2, 0, 0), grid.N) is None
        assert FarStore(w.file, "one").tile((2, 0, 0), grid.N) is None


def test_damaged_rows_read_as_missing(tmp_path):
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=SEED, backend="numpy", loader=False) as w:
        store = FarStore(w.file, "sig")
        a = empty()
        a["top"][:] = 3
        store.put_tiles([((1, 0, 0), a), ((1, 1, 0), a), ((1, 2, 0), a)])
    db = sqlite3.connect(path)
    db.execute("UPDATE far_tiles SET data = x'00112233' WHERE tx = 0")
    # a valid frame of the wrong size, and one whose values are out of range
    from voxel_addon.storage import codecs
    db.execute("UPDATE far_tiles SET data = ? WHERE tx = 1",
               (codecs.encode(codecs.default(), b"\0" * 100),))
    bad = np.full(grid.N * grid.N * 7, 0x7f, np.uint8).tobytes()
    db.execute("UPDATE far_tiles SET data = ? WHERE tx = 2",
               (codecs.encode(codecs.default(), bad),))
    db.commit()
    db.close()
    wf = WorldFile(path)
    store = FarStore(wf, "sig")
    assert all(store.tile((1, t, 0), grid.N) is None for t in range(3))
    wf.close()


def test_read_only_file_keeps_far_data_in_memory(tmp_path, cl_device):
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=SEED, backend="opencl", loader=False) as w:
        w.generate_area([(0, 0)])
    before = path.read_bytes()
    with World.open(path, readonly=True, backend="opencl", loader=False) as w:
        with Builder(w.file, w.generator) as b:
            got = _view(b, far=12)
            assert got and b.stats["built"] == len(got)
            assert all(b.store.tile(m.key, grid.N) is not None for m in got)
    assert path.read_bytes() == before
