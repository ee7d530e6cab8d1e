"""Chunk blobs (issue 29): a chunk array's zstd frame ends with the zeros above the
terrain (the air) as one RLE block (a memset when decoded), still one plain frame
that any zstd reader reads, and says so in its shape (zero_tail); decode_u16 writes
into a new array; reads in one transaction."""
from __future__ import annotations

import sqlite3
import zlib

import numpy as np
import pytest
import zstandard

from voxel_addon.core import chunk
from voxel_addon.storage import CorruptChunk, WorldFile, codecs
from voxel_addon.world import World

SIZE = chunk.VOLUME * 2


def plain(raw) -> bytes:
    """The frame the compressor writes by itself (what encode wrote before)."""
    return zstandard.ZstdCompressor(level=3).compress(raw)


def terrain(top: int, seed: int = 0) -> bytes:
    """Linear-order ids: varied below value index `top`, zeros (air) from there."""
    a = np.zeros(chunk.VOLUME, "<u2")
    a[:top] = np.random.default_rng(seed).integers(1, 9, top) // 3 + 1
    return a.tobytes()


@pytest.mark.parametrize("top", [70 * 256, 70 * 256 + 5, 1023, 1024, 1, chunk.VOLUME - 1])
def test_trailing_air_is_one_rle_block_of_a_plain_frame(top):
    raw = terrain(top)
    blob = codecs.encode("zstd", raw)
    # any zstd reader, told nothing: one frame declaring its size
    assert zstandard.ZstdDecompressor().decompress(blob) == raw
    assert zstandard.frame_content_size(blob) == SIZE
    got = codecs.decode_u16("zstd", blob, chunk.VOLUME)
    assert got.flags.writeable and got.dtype == np.uint16
    assert np.array_equal(got, np.frombuffer(raw, "<u2"))
    zeros = SIZE - -(-2 * top // codecs.SLAB) * codecs.SLAB  # whole 4-layer slabs
    if zeros:  # the last block: RLE (type 1), last, of `zeros` bytes of 0
        assert blob[-4:] == (1 | 1 << 1 | zeros << 3).to_bytes(3, "little") + b"\0"
    else:
        assert blob == plain(raw)
    assert codecs.zero_tail(blob) == zeros  # what the block-id check may skip
    assert codecs.zero_tail(memoryview(blob)) == zeros
    assert len(blob) <= len(plain(raw)) + 16


LIGHT = np.where(np.arange(chunk.VOLUME) < 60 * 256, 0, 0xF000).astype("<u2").tobytes()


@pytest.mark.parametrize("raw", [bytes(SIZE), np.full(chunk.VOLUME, 3, "<u2").tobytes(),
                                 LIGHT, terrain(9000)[:-2], b"\0" * 100])
def test_what_ends_in_no_zero_slab_stays_plain(raw):
    """Uniform chunks, light (daylight on top), sizes not of whole slabs (far tiles)."""
    blob = codecs.encode("zstd", raw)
    assert blob == plain(raw) and codecs.zero_tail(blob) == 0
    assert codecs.decode("zstd", blob, len(raw)) == raw
    assert zlib.decompress(codecs.encode("zlib", raw)) == raw


def test_zero_tail_reads_only_that_shape():
    blob = codecs.encode("zstd", terrain(9000))
    assert codecs.zero_tail(blob) == SIZE - 18 * 1024
    for bad in (blob[:-1] + b"\1",  # an RLE block of another byte
                blob[:4] + b"\xa4" + blob[5:],  # a checksum: not the header encode writes
                blob + b"\0",  # more after the last block
                blob[:9], b""):
        assert codecs.zero_tail(bad) == 0


def test_decode_u16_refuses_what_decode_refuses():
    raw = terrain(9000)
    for codec in codecs.CODECS:
        assert codecs.decode_u16(codec, codecs.encode(codec, raw), chunk.VOLUME).tobytes() == raw
        for bad in (raw[:-2], raw + b"\0\0"):
            with pytest.raises(ValueError):
                codecs.decode_u16(codec, codecs.encode(codec, bad), chunk.VOLUME)
    # a frame declaring the right size that holds less; one without a declared size
    full = codecs.encode("zstd", raw)
    with pytest.raises(ValueError):
        codecs.decode_u16("zstd", full[:-4], chunk.VOLUME)
    undeclared = zstandard.ZstdCompressor(write_content_size=False).compress(raw)
    assert codecs.decode_u16("zstd", undeclared, chunk.VOLUME).tobytes() == raw
    with pytest.raises(ValueError, match="where a blob belongs"):
        codecs.decode_u16("zstd", "text", chunk.VOLUME)


def test_reading_is_one_instant(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0)])
    wf, other = WorldFile(world_path, readonly=True), WorldFile(world_path)
    try:
        before = wf.read_chunk((0, 0))[0]
        changed = before.copy(order="F")
        changed[3, 4, 200] = 2
        with wf.reading():
            assert np.array_equal(wf.read_chunk((0, 0))[0], before)
            other.write_chunks([((0, 0), changed, None)])
            with wf.reading():  # nests
                assert np.array_equal(wf.read_chunk((0, 0))[0], before)
                assert wf.fetch((0, 0))[3] == wf.version((0, 0))
            assert np.array_equal(wf.read_chunk((0, 0))[0], before)
        assert np.array_equal(wf.read_chunk((0, 0))[0], changed)
        with other.transaction(), other.reading():  # inside a write: adds nothing
            assert np.array_equal(other.read_chunk((0, 0))[0], changed)
        other.write_chunks([((0, 0), before, None)])  # the lock and file are free again
    finally:
        wf.close()
        other.close()


def test_fetch_many_is_fetch_of_each(world_path):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0), (1, 0), (2, 0)])
        w.set_block(17, 3, 40, "glass")
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=? WHERE cx=2 AND cy=0", (b"junk",))
    db.commit()
    db.close()
    wf = WorldFile(world_path, readonly=True)
    try:
        keys = [(0, 0), (1, 0), (2, 0), (5, 5)]
        got = wf.fetch_many(keys)
        assert list(got) == keys
        for k in ((0, 0), (1, 0)):
            want = wf.fetch(k)
            assert all(np.array_equal(a, b) if a is not None else b is None
                       for a, b in zip(got[k][:3], want[:3])) and got[k][3] == want[3]
        assert got[(1, 0)][0][1, 3, 40] != got[(0, 0)][0][1, 3, 40]
        assert isinstance(got[(2, 0)], CorruptChunk)
        assert got[(5, 5)] == (None, None, None, 0)
    finally:
        wf.close()


def test_read_many_is_read_chunk_of_each(world_path, monkeypatch):
    """read_many (a statement per _MANY keys, each chunk decoded when the loop asks):
    every key in order with read_chunk's pair, None or a damaged chunk's error; keys
    spread over several statements (_MANY made 2)."""
    from voxel_addon.storage import worldfile
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0), (1, 0), (2, 0), (0, 1)])
        w.set_block(17, 3, 40, "glass")
        w.set_block(3, 20, 41, "glass")
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=? WHERE cx=2 AND cy=0", (b"junk",))
    db.commit()
    db.close()
    monkeypatch.setattr(worldfile, "_MANY", 2)
    wf = WorldFile(world_path, readonly=True)
    try:
        keys = [(0, 1), (1, 0), (2, 0), (5, 5), (0, 0)]
        got = list(wf.read_many(keys))
        assert [k for k, _ in got] == keys
        got = dict(got)
        for k in ((0, 0), (1, 0), (0, 1)):
            assert np.array_equal(got[k][0], wf.read_chunk(k)[0]) and got[k][1] is None
            assert got[k][0].shape == chunk.SHAPE and got[k][0].flags.f_contiguous
        assert got[(1, 0)][0][1, 3, 40] != got[(0, 0)][0][1, 3, 40]
        assert got[(0, 1)][0][3, 4, 41] != got[(0, 0)][0][3, 4, 41]
        assert isinstance(got[(2, 0)], CorruptChunk) and got[(5, 5)] is None
    finally:
        wf.close()


def test_read_many_of_a_box_is_read_chunk_of_each(world_path):
    """A batch that is every chunk of a box (columns of one run of cy) is one range
    statement: the same pairs as read_chunk, in the keys' order, absent chunks None
    and a damaged one its error; keys that are not a box (a hole, a repeat) too."""
    from voxel_addon.storage import worldfile
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(x, y) for x in (-1, 0, 2) for y in (3, 4, 5)] + [(0, 6), (1, 4)])
        for x, y in ((-1, 3), (0, 4), (2, 5), (0, 6)):
            w.set_block(16 * x + 5, 16 * y + 7, 40 + x + y, "glass")
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=? WHERE cx=2 AND cy=3", (b"junk",))
    db.execute("DELETE FROM chunks WHERE cx=-1 AND cy=4")
    db.commit()
    db.close()
    wf = WorldFile(world_path, readonly=True)
    box = [(x, y) for y in (5, 3, 4) for x in (2, -1, 0)]  # cx need not be a run
    try:
        for keys, is_box in ((box, True), (box[:-1], False), (box + box[:1], False),
                             ([(x, y) for x in range(-1, 3) for y in (3, 4)], True)):
            assert (wf._box_rows(keys) is not None) == is_box
            got = list(wf.read_many(keys))
            assert [k for k, _ in got] == keys
            for k, g in got:
                if k == (2, 3):
                    assert isinstance(g, CorruptChunk)
                elif wf.read_chunk(k) is None:
                    assert g is None and k in ((-1, 4), (1, 3))
                else:
                    want = wf.read_chunk(k)
                    assert np.array_equal(g[0], want[0]) and g[1] is None and \
                        g[0].shape == chunk.SHAPE
        assert worldfile._box_sql(3).count("?") == 5
    finally:
        wf.close()


def test_read_many_never_writes_an_array_kept(world_path):
    """read_many decodes into the array of the chunk before the last when the caller
    let it go: whatever the caller keeps (the pair, the array, a view of it, a
    buffer over it) still holds its own chunk after the loop (oracle: read_chunk)."""
    keys = [(x, y) for x in range(4) for y in range(4)]
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area(keys)
        for i, (x, y) in enumerate(keys):  # every chunk differs from every other
            w.set_block(16 * x + i % 16, 16 * y + i // 16, 30 + i, "glass")
    wf = WorldFile(world_path, readonly=True)
    try:
        kept, bases = {}, set()
        for n, (k, got) in enumerate(wf.read_many(keys)):
            bases.add(id(got[0].base))
            how = n % 5
            if how == 1:
                kept[k] = got
            elif how == 2:
                kept[k] = got[0]
            elif how == 3:
                kept[k] = got[0][:, :, :64]  # a view keeps its base
            elif how == 4:
                kept[k] = np.asarray(memoryview(got[0].base))  # a buffer too
        assert len(bases) < len(keys)  # dropped arrays were used again
        for k, v in kept.items():
            want = wf.read_chunk(k)[0]
            if isinstance(v, tuple):
                v = v[0]
            if v.shape == chunk.SHAPE:
                assert np.array_equal(v, want)
            elif v.shape == want.shape[::-1]:
                assert np.array_equal(v.T, want)
            else:
                assert np.array_equal(v, want[:, :, :64])
    finally:
        wf.close()
