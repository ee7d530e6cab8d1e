"""Chunk light kept compact (only its non-uniform layers) reads back exactly."""
import numpy as np

from voxel_addon.core.chunk import Chunk, pack_layers, unpack_layers


def test_pack_layers_round_trip_and_compact_chunk():
    rng = np.random.default_rng(0)
    for t in range(200):
        a = np.zeros((16, 16, 256), np.uint16, order="F")
        lo, hi = sorted(int(v) for v in rng.integers(0, 257, 2))
        a[:, :, hi:] = 0xF000 if t % 3 else rng.integers(0, 5)
        a[:, :, :lo] = rng.integers(0, 3)
        if hi > lo:
            a[:, :, lo:hi] = rng.integers(0, 3, (16, 16, hi - lo))
        if t % 5 == 0:
            a[rng.integers(16), rng.integers(16), rng.integers(256)] = 7
        p = pack_layers(a)
        b = unpack_layers(*p)
        assert np.array_equal(a, b) and b.flags.f_contiguous
        c = Chunk((0, 0))
        c.light = a
        c.compact()
        assert c.nbytes() == c.blocks.nbytes + p[-1].nbytes
        got = c.light
        assert np.array_equal(got, a) and got is c.light  # a read keeps it hot
        got[0, 0, 0] = 9  # written after a read: kept until the next compact
        c.compact()
        assert c.light[0, 0, 0] == 9


def test_typical_light_keeps_a_slab():
    a = np.full((16, 16, 256), 0xF000, np.uint16, order="F")
    a[:, :, :40] = 0
    a[:, :, 40:70] = 0x3000
    p = pack_layers(a)
    assert p[1:3] == (40, 70) and p[-1].shape == (16, 16, 30)


def test_cold_blocks_are_kept_packed(monkeypatch):
    """compact() packs blocks unused for HOT_S; reads give them back exactly and a
    write after a read survives the next compact."""
    from voxel_addon.core import chunk as C
    rng = np.random.default_rng(1)
    a = C.empty()
    a[:, :, :60] = 1
    a[:, :, 60:70] = rng.integers(0, 9, (16, 16, 10))
    c = Chunk((0, 0), a.copy(order="F"))
    c.compact()
    assert c._blocks is not None  # just set: hot, stays an array
    monkeypatch.setattr(C, "HOT_S", -1.0)
    c.compact()
    assert c._blocks is None and c.nbytes() == c._bpack[-1].nbytes < a.nbytes // 10
    assert np.array_equal(c.blocks, a) and c.blocks.flags.f_contiguous
    c.set(3, 4, 200, 7)
    c.compact()
    assert c.get(3, 4, 200) == 7 and c.blocks[3, 4, 200] == 7
    a[3, 4, 200] = 7
    assert np.array_equal(c.blocks, a)


def test_cold_blocks_keep_a_byte_per_voxel_when_ids_fit(monkeypatch):
    """Block ids below 256 are packed as bytes (half the memory of a cold chunk) and
    read back as the same uint16 ids; a chunk holding a larger id keeps two bytes."""
    from voxel_addon.core import chunk as C
    monkeypatch.setattr(C, "HOT_S", -1.0)
    rng = np.random.default_rng(2)
    for big in (0, 300, 65535):
        a = C.empty()
        a[:, :, :50] = 255
        a[:, :, 50:80] = rng.integers(0, 256, (16, 16, 30))
        if big:
            a[5, 6, 70] = big
        c = Chunk((0, 0), a.copy(order="F"))
        c.compact()
        slab = c._bpack[-1]
        assert slab.dtype == (np.uint16 if big else np.uint8)
        assert c.nbytes() == slab.nbytes == 16 * 16 * 30 * slab.itemsize
        got = c.blocks
        assert got.dtype == np.uint16 and got.flags.f_contiguous and np.array_equal(got, a)
    # light is never narrowed (its packs are uploaded as they are)
    a = np.zeros((16, 16, 256), np.uint16, order="F")
    a[:, :, 10:20] = 7
    assert pack_layers(a)[-1].dtype == np.uint16


def test_windows_of_cold_chunks_read_exactly_and_leave_them_cold(monkeypatch):
    """blocks_into / light_into (an edit's window) equal the arrays' windows for any
    columns and layers, cold or hot, and do not rebuild a cold chunk."""
    from voxel_addon.core import chunk as C
    monkeypatch.setattr(C, "HOT_S", -1.0)
    rng = np.random.default_rng(3)
    for t in range(60):
        a = C.empty()
        lo, hi = sorted(int(v) for v in rng.integers(0, 257, 2))
        a[:, :, :lo] = 1
        a[:, :, lo:hi] = rng.integers(0, 300 if t % 4 == 0 else 9, (16, 16, hi - lo))
        c = Chunk((0, 0), a.copy(order="F"))
        c.light = a.copy(order="F") + 3
        c.compact()
        assert c._blocks is None and c._light is None
        x0, x1 = sorted(int(v) for v in rng.integers(0, 17, 2))
        y0, y1 = sorted(int(v) for v in rng.integers(0, 17, 2))
        z0, z1 = sorted(int(v) for v in rng.integers(0, 257, 2))
        xs, ys = slice(x0, x1), slice(y0, y1)
        out = np.full((x1 - x0, y1 - y0, z1 - z0), 77, np.uint16, order="F")
        c.blocks_into(out, xs, ys, z0, z1)
        assert np.array_equal(out, a[xs, ys, z0:z1])
        c.light_into(out, xs, ys, z0, z1)
        assert np.array_equal(out, a[xs, ys, z0:z1] + 3)
        assert c._blocks is None and c._light is None  # still cold
        c.blocks_into(out, xs, ys, z0, z1)             # and hot: the same
        _ = c.blocks
        out2 = np.zeros_like(out)
        c.blocks_into(out2, xs, ys, z0, z1)
        assert np.array_equal(out2, a[xs, ys, z0:z1])
