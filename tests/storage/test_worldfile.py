"""The file format round trip, read back independently of the writer (plain sqlite3 +
zlib/zstandard + the SPEC §3 index formula), and the file's failure modes."""
from __future__ import annotations

import sqlite3
import zlib

import numpy as np
import pytest
import zstandard

from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.world import World
from voxel_addon.storage import FORMAT_VERSION, CorruptChunk, WorldFile


def random_blocks(rng):
    a = chunk.empty()
    a[...] = rng.integers(0, len(REGISTRY), a.shape)
    return a


def decode_independently(codec, blob):
    raw = zlib.decompress(blob) if codec == "zlib" else zstandard.ZstdDecompressor().decompress(blob)
    return np.frombuffer(raw, "<u2")


@pytest.mark.parametrize("codec", ["zlib", "zstd"])
def test_round_trip_matches_spec_layout(world_path, codec):
    rng = np.random.default_rng(1)
    blocks, data = random_blocks(rng), random_blocks(rng)
    wf = WorldFile.create(world_path, seed=7, generator="flat", generator_version=1)
    wf.write_chunks([((-3, 5), blocks, data), ((0, 0), blocks, None)], codec=codec)
    wf.close()

    db = sqlite3.connect(world_path)
    cols = {r[1]: r[2] for r in db.execute("PRAGMA table_info(chunks)")}
    assert cols == {"cx": "INTEGER", "cy": "INTEGER", "codec": "TEXT", "blocks": "BLOB", "data": "BLOB"}
    meta = dict(db.execute("SELECT key, value FROM meta"))
    assert meta["format_version"] == str(FORMAT_VERSION) and meta["seed"] == "7"
    assert meta["generator"] == "flat" and "generator_version" in meta
    names = dict(db.execute("SELECT id, name FROM block_types"))
    row_codec, blob, dblob = db.execute(
        "SELECT codec, blocks, data FROM chunks WHERE cx=-3 AND cy=5").fetchone()
    assert row_codec == codec
    flat = decode_independently(codec, blob)
    for lx, ly, z in [(0, 0, 0), (15, 0, 0), (3, 9, 200), (15, 15, 255)]:
        i = lx + 16 * ly + 256 * z
        assert names[int(flat[i])] == REGISTRY[int(blocks[lx, ly, z])].name
    assert np.array_equal(decode_independently(codec, dblob).reshape(256, 16, 16).transpose(2, 1, 0), data)
    assert db.execute("SELECT data FROM chunks WHERE cx=0 AND cy=0").fetchone()[0] is None

    wf = WorldFile(world_path, readonly=True)
    got_blocks, got_data = wf.read_chunk((-3, 5))
    assert np.array_equal(got_blocks, blocks) and np.array_equal(got_data, data)
    assert wf.read_chunk((0, 0))[1] is None and wf.read_chunk((1, 1)) is None


def test_foreign_id_table_is_translated(world_path):
    """A file whose ids differ from the registry's (e.g. written by another version)."""
    wf = WorldFile.create(world_path, seed=1, generator="flat", generator_version=1)
    wf.close()
    db = sqlite3.connect(world_path)
    db.execute("DELETE FROM block_types")
    db.executemany("INSERT INTO block_types VALUES (?, ?)", [(0, "air"), (1, "water"), (7, "stone")])
    ids = np.zeros(chunk.VOLUME, "<u2")
    ids[:10] = 7
    ids[10:20] = 1
    db.execute("INSERT INTO chunks VALUES (0, 0, 'zlib', ?, NULL)", (zlib.compress(ids.tobytes()),))
    db.commit()
    db.close()
    with World.open(world_path, loader=False) as w:
        assert w.get_block(0, 0, 0) == REGISTRY.id("stone")
        assert w.get_block(10, 0, 0) == REGISTRY.id("water")
        w.set_block(0, 0, 1, "glass")
    db = sqlite3.connect(world_path)
    names = dict(db.execute("SELECT id, name FROM block_types"))
    codec, blob = db.execute("SELECT codec, blocks FROM chunks").fetchone()
    flat = decode_independently(codec, blob)
    assert names[int(flat[256])] == "glass" and names[int(flat[0])] == "stone"


def test_newer_format_is_refused_untouched(world_path):
    WorldFile.create(world_path, seed=1, generator="flat", generator_version=1).close()
    db = sqlite3.connect(world_path)
    db.execute("UPDATE meta SET value='99' WHERE key='format_version'")
    db.commit()
    db.close()
    before = world_path.read_bytes()
    with pytest.raises(VoxelError, match="newer"):
        WorldFile(world_path)
    assert world_path.read_bytes() == before


def test_corrupt_chunk_names_itself_and_is_never_overwritten(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0), (2, -1)])
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=X'deadbeef' WHERE cx=2 AND cy=-1")
    db.commit()
    db.close()
    with World.open(world_path, loader=False) as w:
        with pytest.raises(CorruptChunk, match=r"\(2, -1\)"):
            w.chunk_at(2, -1)
        w.set_block(1, 1, 100, "stone")   # other chunks keep working
        assert w.generate_area([(2, -1), (3, 3)]) == 1  # present (if damaged) is not regenerated
    db = sqlite3.connect(world_path)
    assert db.execute("SELECT blocks FROM chunks WHERE cx=2 AND cy=-1").fetchone()[0] == b"\xde\xad\xbe\xef"


def test_not_a_world_file(tmp_path):
    p = tmp_path / "x.sqlite"
    p.write_bytes(b"")
    with pytest.raises(VoxelError, match="not a readable world file"):
        WorldFile(p)
    assert p.read_bytes() == b""
    with pytest.raises(VoxelError, match="no world file"):
        WorldFile(tmp_path / "missing.sqlite")
    (tmp_path / "folder.sqlite").mkdir()  # not 'no world file': there is something
    for make in (lambda p: WorldFile(p), lambda p: WorldFile.create(
            p, seed=1, generator="flat", generator_version=1)):
        with pytest.raises(VoxelError, match="is a folder, not a world file"):
            make(tmp_path / "folder.sqlite")


def test_readonly_open_of_a_path_with_uri_characters(tmp_path):
    """Read-only opens go through an SQLite URI: #, ?, % and spaces in a folder name
    (and Windows drive letters) must not be read as URI syntax."""
    path = tmp_path / "my worlds #2 ?100%" / "w.sqlite"
    path.parent.mkdir()
    with World.create(path, seed=4, generator="flat") as w:
        w.set_block(1, 2, 100, "stone")
    wf = WorldFile(path, readonly=True)
    try:
        assert wf.seed == 4 and wf.read_chunk((0, 0)) is not None
    finally:
        wf.close()


def _spec_only(path, tables=("meta", "block_types", "chunks"), key=", PRIMARY KEY (cx, cy)"):
    """A world as another program writes it from SPEC 3 alone: meta, block_types and
    chunks (one zlib chunk: stone up to z 9), none of our own tables."""
    db = sqlite3.connect(path)
    if "meta" in tables:
        db.execute("CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT)")
        db.executemany("INSERT INTO meta VALUES (?, ?)", [
            ("format_version", "1"), ("seed", "3"), ("generator", "flat"),
            ("generator_version", "1")])
    if "block_types" in tables:
        db.execute("CREATE TABLE block_types(id INTEGER PRIMARY KEY, name TEXT UNIQUE NOT NULL)")
        db.executemany("INSERT INTO block_types VALUES (?, ?)", [(0, "air"), (1, "stone")])
    if "chunks" in tables:
        db.execute("CREATE TABLE chunks(cx INTEGER, cy INTEGER, codec TEXT NOT NULL, "
                   f"blocks BLOB NOT NULL, data BLOB{key})")
        b = np.zeros(chunk.SIZE * chunk.SIZE * chunk.HEIGHT, "<u2")
        b[:256 * 10] = 1
        db.execute("INSERT INTO chunks VALUES (0, 0, 'zlib', ?, NULL)",
                   (zlib.compress(b.tobytes()),))
    db.commit()
    db.close()


def test_a_file_written_to_the_spec_alone_opens_and_takes_edits(tmp_path):
    """No edits table (SPEC 3 calls it ours): read-only it opens untouched with no
    edits, writable it gets the table and keeps an edit."""
    p = tmp_path / "spec.sqlite"
    _spec_only(p)
    before = p.read_bytes()
    wf = WorldFile(p, readonly=True)
    try:
        assert wf.edit_count() == 0 and wf.edits_in((0, 0)) == []
    finally:
        wf.close()
    with World.open(p, readonly=True, loader=False) as w:
        assert w.get_block(1, 1, 9) == REGISTRY.id("stone") and w.get_block(1, 1, 10) == 0
    assert p.read_bytes() == before
    with World.open(p, loader=False) as w:
        w.set_block(1, 1, 10, "glass")
    with World.open(p, readonly=True, loader=False) as w:
        assert w.get_block(1, 1, 10) == REGISTRY.id("glass") and w.file.edit_count() == 1


def test_a_file_without_a_chunks_table_is_refused_untouched(tmp_path):
    p = tmp_path / "other.sqlite"
    _spec_only(p, tables=("meta", "block_types"))
    before = p.read_bytes()
    for ro in (False, True):
        with pytest.raises(VoxelError, match="not a Voxel Worlds file .*chunks"):
            WorldFile(p, readonly=ro)
    assert p.read_bytes() == before and sorted(x.name for x in tmp_path.iterdir()) == [p.name]


def test_a_chunks_table_without_a_key_is_refused_untouched(tmp_path):
    # every save added a row beside the old one (INSERT OR REPLACE replaces nothing
    # without a key): the file grew, reads picked one of them
    p = tmp_path / "nokey.sqlite"
    _spec_only(p, key="")
    before = p.read_bytes()
    for ro in (False, True):
        with pytest.raises(VoxelError, match="chunks table has no key on cx, cy"):
            WorldFile(p, readonly=ro)
    assert p.read_bytes() == before
    db = sqlite3.connect(p)  # a unique index of another program's making is a key
    db.execute('CREATE UNIQUE INDEX "by ""key""" ON chunks(cy, cx)')
    db.commit()
    db.close()
    with World.open(p, loader=False) as w:
        w.set_block(1, 1, 10, "glass")
    db = sqlite3.connect(p)
    assert db.execute("SELECT COUNT(*) FROM chunks").fetchone()[0] == 1
    db.close()


def test_a_killed_creates_leftovers_are_swept_once_surely_abandoned(tmp_path):
    """A create killed mid-way leaves its own-named new file beside the world; the next
    create at that path removes such files once they are old, never a fresh one (a
    create running now in another process)."""
    import os
    import time
    from voxel_addon.storage import opening
    old = [tmp_path / f".w.sqlite.{n}-1.new{s}" for n, s in ((11, ""), (11, "-wal"), (12, ""))]
    fresh = tmp_path / ".w.sqlite.13-1.new"
    other = tmp_path / ".v.sqlite.14-1.new"   # another world's
    for p in (*old, fresh, other):
        p.write_bytes(b"x")
    t = time.time() - opening.STALE_S - 5
    for p in (*old, other):
        os.utime(p, (t, t))
    WorldFile.create(tmp_path / "w.sqlite", seed=1, generator="flat", generator_version=1).close()
    assert sorted(p.name for p in tmp_path.iterdir() if ".new" in p.name) == [other.name,
                                                                           fresh.name]


def test_a_new_world_appears_in_wal_mode(tmp_path, monkeypatch):
    """The file linked into place is already in WAL mode (header bytes 18-19 = 2):
    switching a published file took an exclusive lock, and a second process opening the
    new world at that moment failed 'database is locked' (tests/world/test_races.py's
    two creates at once, ~1 round in 25)."""
    import os
    from voxel_addon.storage import opening
    seen = []
    real_link = os.link

    def link(src, dst):  # the file as it is published
        seen.append(open(src, "rb").read(20)[18:20])
        real_link(src, dst)
    monkeypatch.setattr(opening.os, "link", link)
    WorldFile.create(tmp_path / "w.sqlite", seed=1, generator="flat", generator_version=1).close()
    assert seen == [b"\x02\x02"]
