"""Hostile world files (issue 21): a chunk or light blob that inflates far beyond the
65,536 values it must hold is reported damaged after at most its expected size was
decoded, not after inflating all of it (a 65 KB zstd frame of 2 GiB of zeros took
4.9 s and 2.2 GB before)."""
from __future__ import annotations

import gzip
import sqlite3
import zlib

import numpy as np
import pytest
import zstandard

from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.storage import CorruptChunk, WorldFile, codecs
from voxel_addon.world import World

from ..memory import peak_of

SIZE = chunk.VOLUME * 2
MIB = 1 << 20


def zstd_bomb(n: int, declared: bool = True) -> bytes:
    """One zstd frame of n bytes of zeros (a few KB per GiB), its size in the header
    or not."""
    c = zstandard.ZstdCompressor(level=1, write_content_size=declared)
    zero = bytes(MIB)
    chunks = c.chunker(size=n if declared else -1, chunk_size=1 << 17)
    out = []
    for _ in range(n // MIB):
        out.extend(chunks.compress(zero))
    out.extend(chunks.finish())
    return b"".join(out)


def zlib_bomb(n: int, wbits: int = 15) -> bytes:
    c = zlib.compressobj(9, zlib.DEFLATED, wbits)
    zero = bytes(MIB)
    return b"".join([c.compress(zero) for _ in range(n // MIB)] + [c.flush()])


@pytest.fixture(scope="module")
def bombs():
    return {"zstd": zstd_bomb(2048 * MIB), "zlib": zlib_bomb(256 * MIB),
            "zstd-undeclared": zstd_bomb(256 * MIB, declared=False),
            "gzip": zlib_bomb(64 * MIB, 31)}


def _read_fails(world_path, match: str) -> None:
    """Chunk (0, 0) of the file reads as a damaged chunk, saying MATCH."""
    wf = WorldFile(world_path, readonly=True)
    try:
        with pytest.raises(CorruptChunk, match=match):
            wf.read_chunk((0, 0))
    finally:
        wf.close()


@pytest.mark.parametrize("kind", ["zstd", "zlib", "zstd-undeclared"])
def test_decode_stops_at_the_expected_size(bombs, kind):
    blob, codec = bombs[kind], kind.split("-")[0]
    assert len(blob) < 300_000

    def go():
        with pytest.raises(ValueError):
            codecs.decode(codec, blob, SIZE)
    assert peak_of(go) < 8 * SIZE


def test_gzip_inflate_stops_at_the_expected_size(bombs):
    def go():
        with pytest.raises(ValueError):
            codecs.inflate(bombs["gzip"], SIZE, 31)
    assert peak_of(go) < 8 * SIZE
    raw = bytes(range(256)) * 8
    assert codecs.inflate(gzip.compress(raw), len(raw), 31) == raw


@pytest.mark.parametrize("blob", ["text", 12, 1.5])
def test_a_blob_of_another_type_is_a_damaged_chunk(world_path, blob):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.chunk_at(0, 0)
        w.flush()
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=? WHERE cx=0 AND cy=0", (blob,))
    db.commit()
    db.close()
    _read_fails(world_path, "where a blob belongs")


@pytest.mark.parametrize("codec", ["zstd", "zlib"])
@pytest.mark.parametrize("column", ["blocks", "data", "light"])
def test_world_reports_a_bomb_without_inflating_it(world_path, bombs, codec, column):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.chunk_at(0, 0)
        w.flush()
        from voxel_addon.world import build
        build.light_and_mesh(w, 0, 0, 1, 1)
        w.flush()
    db = sqlite3.connect(world_path)
    table = "light" if column == "light" else "chunks"
    assert db.execute(f"SELECT COUNT(*) FROM {table}").fetchone()[0] >= 1
    db.execute(f"UPDATE {table} SET codec=?, {column}=? WHERE cx=0 AND cy=0",
               (codec, bombs[codec]))
    db.commit()
    db.close()
    wf = WorldFile(world_path, readonly=True)
    try:
        def go():
            if column == "light":  # derived data: dropped and computed again
                assert wf.read_chunk((0, 0), light=True)[2] is None
            else:
                with pytest.raises(CorruptChunk):
                    wf.read_chunk((0, 0))
        assert peak_of(go) < 8 * SIZE
    finally:
        wf.close()


def test_good_blobs_still_decode():
    raw = np.arange(chunk.VOLUME, dtype="<u2").tobytes()
    for codec in codecs.CODECS:
        assert codecs.decode(codec, codecs.encode(codec, raw), SIZE) == raw
        with pytest.raises(ValueError):  # short
            codecs.decode(codec, codecs.encode(codec, raw[:-2]), SIZE)
        with pytest.raises(ValueError):  # long, by one value
            codecs.decode(codec, codecs.encode(codec, raw + b"\0\0"), SIZE)
    # a zstd frame without a declared size decodes too
    c = zstandard.ZstdCompressor(write_content_size=False)
    assert codecs.decode("zstd", c.compress(raw), SIZE) == raw


def test_hostile_tables_give_one_line_or_are_left_out(world_path):
    from voxel_addon.core.errors import VoxelError
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.set_block(1, 2, 100, "glass")
    db = sqlite3.connect(world_path)
    db.executemany("INSERT OR REPLACE INTO edits VALUES (?, ?, ?, ?, ?, 0)",
                   [(3, 3, 300, 1, 0), (4, 4, -1, 1, 0), (5, 5, 50, 1, 1 << 20),
                    (6, 6, 60, -7, 0), (7, 7, 70, 1 << 40, 0)])
    db.commit()
    with World.open(world_path, loader=False, readonly=True) as w:
        c = w.chunk_at(0, 0)                      # loads; bad rows never reach the arrays
        assert c.get(1, 2, 100) != 0 and w.file.edits_in((0, 0))
    # regenerated from the seed with the stored edits: the hostile rows are skipped
    db.execute("DELETE FROM chunks")
    db.commit()
    with World.open(world_path, loader=False, readonly=True) as w:
        c = w.chunk_at(0, 0)
        assert c.get(1, 2, 100) != 0 and c.get(6, 6, 60) == 0 and c.get(7, 7, 70) == 0
    db.execute("INSERT INTO block_types VALUES (?, 'stone_x')", (1 << 40,))
    db.commit()
    db.close()
    with pytest.raises(VoxelError, match="outside 0..65535"):
        WorldFile(world_path, readonly=True)


def test_chunk_rows_keyed_outside_the_world_are_left_out(world_path):
    # a text or real key made `map` sort mixed types (a TypeError's traceback); a key
    # far outside the world made it refuse a span no chunk of the world has
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0), (1, -1)])
    db = sqlite3.connect(world_path)
    for key in [("a", 0), (2.5, 0), (1, 0.5), (1 << 40, 0), (0, -(1 << 26) - 1), (0, 1 << 26)]:
        db.execute("INSERT INTO chunks SELECT ?, ?, codec, blocks, data FROM chunks "
                   "WHERE cx=0 AND cy=0", key)
    db.commit()
    db.close()
    wf = WorldFile(world_path, readonly=True)
    try:
        assert sorted(wf.chunk_keys()) == [(0, 0), (1, -1)] and wf.chunk_count() == 2
        assert wf.chunks_in(-5, -5, 5, 5) == {(0, 0), (1, -1)}
    finally:
        wf.close()


def test_block_ids_beyond_the_table_are_a_damaged_chunk(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0)])
    ids = np.full(chunk.VOLUME, 5000, "<u2").tobytes()
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET codec='zlib', blocks=? WHERE cx=0 AND cy=0",
               (zlib.compress(ids),))
    db.commit()
    db.close()
    _read_fails(world_path, "missing from block_types")


def test_an_id_whose_name_is_gone_from_the_table_is_a_damaged_chunk(world_path):
    # stone's row moved to another id (another program's INSERT OR REPLACE): its
    # voxels read as air, and an edit wrote the chunk back without them
    from voxel_addon.core.errors import VoxelError
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0)])
        stone = w.file.file_ids[REGISTRY.id("stone")]
        assert stone in np.asarray(w.file.read_chunk((0, 0))[0])
    db = sqlite3.connect(world_path)
    db.execute("INSERT OR REPLACE INTO block_types VALUES (7000, 'stone')")
    db.commit()
    before = db.execute("SELECT blocks FROM chunks WHERE cx=0 AND cy=0").fetchone()
    db.close()
    _read_fails(world_path, "missing from block_types")
    with World.open(world_path, loader=False) as w:
        with pytest.raises(VoxelError, match="missing from block_types"):
            w.set_block(1, 1, 100, "glass")
    db = sqlite3.connect(world_path)
    assert db.execute("SELECT blocks FROM chunks WHERE cx=0 AND cy=0").fetchone() == before
    db.close()


@pytest.mark.parametrize("identity", [True, False])
def test_the_first_id_past_the_table_is_a_damaged_chunk(world_path, identity):
    """At the edge, in files numbered like the registry and not (the two paths)."""
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0), (1, 0)])
    db = sqlite3.connect(world_path)
    n = db.execute("SELECT MAX(id) + 1 FROM block_types").fetchone()[0]
    if not identity:  # two names swap ids: the file's ids are not the registry's
        a, b = db.execute("SELECT name FROM block_types WHERE id IN (1, 2) ORDER BY id")
        db.execute("UPDATE block_types SET name=? WHERE id=1", ("x",))
        db.execute("UPDATE block_types SET name=? WHERE id=2", a)
        db.execute("UPDATE block_types SET name=? WHERE id=1", b)
    for cx, top in ((0, n - 1), (1, n)):
        ids = np.zeros(chunk.VOLUME, "<u2")
        ids[777] = top
        db.execute("UPDATE chunks SET codec='zstd', blocks=? WHERE cx=? AND cy=0",
                   (codecs.encode("zstd", ids.tobytes()), cx))
    db.commit()
    db.close()
    wf = WorldFile(world_path, readonly=True)
    try:
        assert wf._identity == identity
        assert wf.read_chunk((0, 0))[0].max() == wf.registry_ids[n - 1]
        with pytest.raises(CorruptChunk, match="missing from block_types"):
            wf.read_chunk((1, 0))
        many = dict(wf.read_many([(0, 0), (1, 0)]))  # the batch read: the same check
        assert many[(0, 0)][0].max() == wf.registry_ids[n - 1]
        assert isinstance(many[(1, 0)], CorruptChunk)
        # the world's loader (frames kept as read where the ids are the registry's)
        got = wf.fetch_many([(0, 0), (1, 0)], packed=True)
        b = got[(0, 0)][0]
        assert isinstance(b, chunk.Packed) == identity
        assert (b.unpack() if identity else b).max() == wf.registry_ids[n - 1]
        assert isinstance(got[(1, 0)], CorruptChunk)
        assert "missing from block_types" in str(got[(1, 0)])
    finally:
        wf.close()


def _rle_end(frame: bytes, zeros: int, byte: int = 0) -> bytes:
    """`frame` (one compressed block) with its block made not last and an RLE block
    of `zeros` x `byte` after it, under encode()'s header declaring SIZE bytes."""
    fhd = frame[4]
    start = 5 + (fhd >> 5 & 1 ^ 1) + ((fhd >> 5 & 1), 2, 4, 8)[fhd >> 6]
    h = int.from_bytes(frame[start:start + 3], "little")
    assert fhd & 7 == 0 and h & 7 == 5 and start + 3 + (h >> 3) == len(frame)  # one block
    return b"".join((frame[:4], b"\xa0", SIZE.to_bytes(4, "little"),
                     (h & ~1).to_bytes(3, "little"), frame[start + 3:],
                     (3 | zeros << 3).to_bytes(3, "little"), bytes([byte])))


@pytest.mark.parametrize("how", ["ids under the zeros", "zeros of another byte",
                                 "an id just below zeros that end mid-layer"])
def test_an_rle_end_hides_no_ids(world_path, how):
    """The block-id check skips the zeros a frame ends with (codecs.zero_tail): a
    frame that claims such an end over ids past the table, or ends with another
    byte (0x0505 ids), is still a damaged chunk, in one line; so is a well-formed
    one whose zeros start inside a layer, an id past the table just below them
    (the check skips whole layers of zeros only)."""
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0)])
    ids = np.zeros(chunk.VOLUME, "<u2")
    ids[:5000] = 1
    zeros = 8192
    if how == "ids under the zeros":  # the first block already holds all SIZE bytes
        ids[-100] = 60000
        blob = _rle_end(zstandard.ZstdCompressor().compress(ids.tobytes()), zeros)
    elif how.startswith("an id just below"):
        zeros = 2 * (chunk.VOLUME - 5001)  # ends 1 value into layer 19
        ids[5000] = 60000
        blob = _rle_end(zstandard.ZstdCompressor().compress(ids[:5001].tobytes()), zeros)
        assert codecs.decode("zstd", blob, SIZE) == ids.tobytes()  # a sound frame
    else:
        blob = _rle_end(zstandard.ZstdCompressor().compress(ids[:-zeros // 2].tobytes()),
                        zeros, 5)
    assert codecs.zero_tail(blob) == (0 if how == "zeros of another byte" else zeros)
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET codec='zstd', blocks=? WHERE cx=0 AND cy=0", (blob,))
    db.commit()
    db.close()
    wf = WorldFile(world_path, readonly=True)
    try:
        with pytest.raises(CorruptChunk) as e:
            wf.read_chunk((0, 0))
        assert "\n" not in str(e.value)
        got = wf.fetch_many([(0, 0)], packed=True)[(0, 0)]  # the world's loader
        assert isinstance(got, CorruptChunk) and "\n" not in str(got)
        got = dict(wf.read_many([(0, 0)]))[(0, 0)]
        assert isinstance(got, CorruptChunk) and "\n" not in str(got)
    finally:
        wf.close()


@pytest.mark.parametrize("generator, params", [
    ("flat", '{"layers": 5}'), ("flat", '{"layers": [["stone", "x"]]}'),
    ("flat", '{"layers": [[1]]}'), ("flat", "[1, 2"), ("flat", '"text"'),
    ("overworld", '{"sea_level": 1e999}'), ("flat", "[" * 100_000)])
def test_damaged_generator_settings_are_one_line(world_path, generator, params):
    from voxel_addon.core.errors import VoxelError
    from voxel_addon.generation import for_file
    World.create(world_path, seed=1, generator=generator, loader=False).close()
    db = sqlite3.connect(world_path)
    db.execute("UPDATE meta SET value=? WHERE key='generator_params'", (params,))
    db.commit()
    db.close()
    with pytest.raises(VoxelError) as e:
        World.open(world_path, loader=False)
    assert "\n" not in str(e.value)
    wf = WorldFile(world_path, readonly=True)  # the CLI's map and info read it so
    try:
        with pytest.raises(VoxelError, match="generator settings are damaged"):
            for_file(wf)
    finally:
        wf.close()
