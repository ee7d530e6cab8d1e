"""Chunk blocks and light kept packed (Packed: LZ4) and the viewport's light packs
(pack_layers: only the non-uniform layers) read back exactly."""
import numpy as np
import pytest

from voxel_addon.core import chunk as C, packed as P
from voxel_addon.core.chunk import Chunk, pack, pack_layers, unpack_layers


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
        assert c._light is None and c._blocks is None
        assert c.nbytes() == c._bpack.nbytes + c._lpack.nbytes < a.nbytes
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
    """A chunk is born packed; a read gives the blocks back exactly and keeps them
    hot until compact() finds them unread for HOT_S; a write after a read survives
    the next compact."""
    rng = np.random.default_rng(1)
    a = C.empty()
    a[:, :, :60] = 1
    a[:, :, 60:70] = rng.integers(0, 9, (16, 16, 10))
    src = a.copy(order="F")
    c = Chunk((0, 0), src)
    assert c._blocks is None and c.nbytes() == c._bpack.nbytes < a.nbytes // 10
    src[0, 0, 0] = 5  # the chunk keeps its own copy
    got = c.blocks
    assert np.array_equal(got, a) and got.flags.f_contiguous and got.flags.writeable
    assert got.dtype == np.uint16 and c.blocks is got
    c.compact()
    assert c._blocks is got  # just read: hot, stays an array
    monkeypatch.setattr(C, "HOT_S", -1.0)
    c.compact()
    assert c._blocks is None
    c.set(3, 4, 200, 7)
    c.compact()
    assert c._blocks is None and c.get(3, 4, 200) == 7
    a[3, 4, 200] = 7
    assert np.array_equal(c.blocks, a)


def _volume(rng, kinds: int, dtype=np.uint16, shape=C.SHAPE):
    """Terrain-like: uniform below and above, `kinds` distinct values (all present)
    in the layers between, from the whole range of the dtype."""
    top = int(np.iinfo(dtype).max)
    vals = rng.choice(top + 1, size=kinds, replace=False).astype(dtype)
    lo, hi = sorted(int(v) for v in rng.integers(0, shape[2] + 1, 2))
    if (hi - lo) * shape[0] * shape[1] < kinds:
        lo, hi = 0, shape[2]
    a = np.empty(shape, dtype, order="F")
    a[:, :, :lo] = vals[0]
    a[:, :, hi:] = vals[-1]
    mid = a[:, :, lo:hi].reshape(-1, order="F")
    idx = rng.integers(0, kinds, mid.size)
    idx[:kinds] = np.arange(kinds)
    a[:, :, lo:hi] = vals[idx].reshape((shape[0], shape[1], hi - lo), order="F")
    return a


@pytest.mark.parametrize("kinds", [1, 2, 16, 17, 256, 257, 4096])
def test_pack_round_trips_exactly(kinds):
    """Any values (block ids, light's four nibbles), dtypes, C- or Fortran-ordered,
    any shape: unpack() gives a new writable Fortran array equal to the packed one
    and into() any window of it."""
    rng = np.random.default_rng(kinds)
    for t in range(6):
        dtype = np.uint8 if t == 5 and kinds <= 256 else np.uint16
        shape = (18, 18, 256) if t == 4 else C.SHAPE
        a = _volume(rng, kinds, dtype, shape)
        if t == 3:
            a = np.ascontiguousarray(a)
        p = pack(a)
        a0 = a.copy()
        a[...] = 0  # the pack is a copy
        b = p.unpack()
        assert b.dtype == a0.dtype and b.shape == a0.shape and np.array_equal(b, a0)
        assert b.flags.f_contiguous and b.flags.writeable
        b[0, 0, 0] ^= 1  # a new array each time
        assert np.array_equal(p.unpack(), a0)
        out = np.full(a0.shape, 77, a0.dtype, order="F")  # or into a given one
        assert p.unpack(out) is out and np.array_equal(out, a0)
        for _ in range(4):
            x0, x1 = sorted(int(v) for v in rng.integers(0, shape[0] + 1, 2))
            y0, y1 = sorted(int(v) for v in rng.integers(0, shape[1] + 1, 2))
            z0, z1 = sorted(int(v) for v in rng.integers(0, shape[2] + 1, 2))
            out = np.full((x1 - x0, y1 - y0, z1 - z0), 77, a0.dtype, order="F")
            p.into(out, slice(x0, x1), slice(y0, y1), z0, z1)
            assert np.array_equal(out, a0[x0:x1, y0:y1, z0:z1])


def test_layers_of_one_value_each_read_back():
    """Sections that each hold one value (as daylight over dark rock does), side by
    side with others, and windows across them."""
    a = C.empty()
    for z in range(256):
        a[:, :, z] = z // 32 + 1 if z < 200 else 0xF000  # sections 0-5: one value each
    a[3, 4, 100] = 9
    p = pack(a)
    assert np.array_equal(p.unpack(), a)
    for z0, z1 in ((0, 256), (10, 70), (31, 33), (60, 130), (190, 256)):
        out = np.zeros((2, 16, z1 - z0), np.uint16, order="F")
        p.into(out, slice(2, 4), slice(None), z0, z1)
        assert np.array_equal(out, a[2:4, :, z0:z1])


def test_pack_without_lz4_keeps_the_array(monkeypatch):
    monkeypatch.setattr(P, "_lz4", None)
    a = _volume(np.random.default_rng(5), 17)
    a0 = a.copy()
    p = pack(a)
    a[...] = 0  # a copy of the array
    assert p.nbytes == a.nbytes and np.array_equal(p.unpack(), a0)
    assert p.unpack() is not p.unpack()  # a new array each time: writes stay local
    a = a0
    c = Chunk((0, 0), a)
    assert np.array_equal(c.blocks, a)


def test_typical_chunk_packs_small():
    """Generated terrain's blocks and light: a few KB each (issue 29: <= 1 B/voxel in
    all, meshes included)."""
    from voxel_addon.generation import make_generator
    from voxel_addon.light import region_light
    keys = [(x, y) for y in range(-1, 2) for x in range(-1, 2)]
    g = make_generator("overworld", 2019, None, "numpy")
    region = C.paste(zip(keys, g.generate(keys)), -1, -1, 2, 2)
    lit = np.asfortranarray(region_light(region, tile=1, backend="numpy"))
    blocks = np.asfortranarray(region[16:32, 16:32])
    for a in (blocks, lit):
        p = pack(a)
        assert p.nbytes < 0.15 * C.VOLUME and np.array_equal(p.unpack(), a)


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


def test_light_out_leaves_packed_light_packed():
    """A payload's light (issue 29): the hot array itself, or a new array rebuilt
    from the packed light that the chunk does not keep (nothing to pack again at
    the next compact); writes into either stay out of the other."""
    a = C.empty()
    a[:, :, 100:] = 0xF000
    a[3, 4, 90] = 0x0F0F
    c = Chunk((0, 0))
    assert c.light_out() is None
    c.light = a
    assert c.light_out() is a  # hot: the array itself
    c.compact()
    p = c._lpack
    got = c.light_out()
    assert np.array_equal(got, a) and got.flags.f_contiguous and got is not a
    assert c._light is None and c._lpack is p  # still packed, the same pack
    got[3, 4, 90] = 1
    assert c.light_out()[3, 4, 90] == 0x0F0F and c.light[3, 4, 90] == 0x0F0F


@pytest.mark.parametrize("lz4", [True, False])
def test_air_from_is_where_the_blocks_stay_air(monkeypatch, lz4):
    """Chunk.air_from(z0) (an edit's window copies no air above it): every layer from
    there up is air, and it is at most a section above the last non-air layer; for
    packed, hot, and hot blocks written in place since they were packed (the packed
    copy is then a stale hint)."""
    if not lz4:
        monkeypatch.setattr(P, "_lz4", None)
    rng = np.random.default_rng(8)
    for t in range(80):
        a = C.empty()
        top = int(rng.integers(0, 257)) if t % 4 else 32 * int(rng.integers(0, 9))
        a[:, :, :top] = rng.integers(0, 3, (16, 16, top)) if t % 2 else 1   # or all stone
        c = Chunk((0, 0), a.copy(order="F"))
        if t % 3:
            b = c.blocks          # hot (the packed copy stays beside it)
            if t % 3 == 2:        # written in place: the packed copy is stale
                z = int(rng.integers(0, 256))
                b[int(rng.integers(0, 16)), int(rng.integers(0, 16)), z] = 5
                a[:, :, :] = b
        z0 = int(rng.integers(0, 257))
        got = c.air_from(z0)
        nz = np.flatnonzero(a.any(axis=(0, 1)))
        last = int(nz[-1]) + 1 if nz.size else 0
        assert z0 <= got <= 256 and not a[:, :, got:].any(), (t, got, last)
        assert got <= max(z0, -(-last // C.Packed.SECTION) * C.Packed.SECTION), (t, got, last)
