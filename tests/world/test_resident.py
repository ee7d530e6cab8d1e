"""Chunks kept packed in memory (issue 29): the world's reads and edits see exactly
the blocks and light they would see in arrays, and leave untouched chunks packed."""
import numpy as np

from voxel_addon.core import chunk as C
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.world import World, build
from voxel_addon.world.edit import edit


def _cold(w):
    with w.locked():
        for c in w.chunks.values():
            c.compact()
    return all(c._blocks is None and c._light is None for c in w.chunks.values())


def test_edit_on_cold_chunks_changes_exactly_one_voxel(tmp_path, monkeypatch):
    monkeypatch.setattr(C, "HOT_S", -1.0)  # compact() packs whatever was read
    with World.create(tmp_path / "w.sqlite", seed=7, backend="numpy") as w:
        build.light_and_mesh(w, -1, -1, 2, 2, backends_=("numpy", "numpy"))
        assert _cold(w)
        keys = sorted(w.chunks)
        blocks = {k: w.chunks[k].blocks_copy() for k in keys}
        assert _cold(w)  # (a copy leaves them packed)
        # a batch's snapshot decodes into its window and leaves the chunks packed
        got, _ = build.snapshot(w, -2, -2, 3, 3)
        assert np.array_equal(got, C.paste(blocks.items(), -2, -2, 3, 3))
        assert all(w.chunks[k]._blocks is None for k in keys)
        # one voxel on top of the terrain, in a chunk whose neighbours are all cold
        x, y = 5, 7
        z = int(np.flatnonzero(blocks[(0, 0)][x, y])[-1]) + 1
        stone = REGISTRY.id("stone")
        payloads, _ = edit(w, (x, y, z, stone))
        assert payloads
        assert _cold(w)
        after = {k: w.chunks[k].blocks_copy() for k in keys}
        assert sum(int((after[k] != blocks[k]).sum()) for k in keys) == 1
        assert after[(0, 0)][x, y, z] == stone and w.chunks[(0, 0)].get(x, y, z) == stone
        # its light is the light of the new blocks (a full solve of the 3x3 around)
        from voxel_addon.light import region_light
        region = C.paste(after.items(), -2, -2, 3, 3)
        want = region_light(region, tile=3, backend="numpy")
        for k in [(i, j) for j in (-1, 0, 1) for i in (-1, 0, 1)]:
            i, j = (k[0] + 1) * C.SIZE, (k[1] + 1) * C.SIZE
            assert np.array_equal(w.chunks[k].light, want[i:i + C.SIZE, j:j + C.SIZE]), k


def _arrays_read(monkeypatch):
    """Chunks read from the file as arrays (a file whose block numbering is not the
    registry's), not as the file's frames (Packed.frame)."""
    from voxel_addon.storage.worldfile import WorldFile
    real = WorldFile.fetch_many
    monkeypatch.setattr(WorldFile, "fetch_many", lambda f, keys, packed=False: real(f, keys))


def test_reloaded_chunks_keep_the_files_frames(tmp_path, monkeypatch):
    """Chunks read from the file (issue 29) keep its zstd frames as their packed
    blocks and light, byte for byte: no array made and packed; a batch over them
    decodes its window and hands out light equal to the stored arrays, leaves them
    as they were, and what they decode to is what the file holds (with any window,
    whole or a few columns over some layers)."""
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=7, backend="numpy") as w:
        build.light_and_mesh(w, -1, -1, 3, 3, backends_=("numpy", "numpy"))
    packs = []
    real = C.pack
    monkeypatch.setattr(C, "pack", lambda a: packs.append(id(a)) or real(a))
    with World.open(path) as w:
        rows = {k: w.file.query("SELECT c.blocks, l.light FROM chunks c JOIN light l "
                                "USING (cx, cy) WHERE cx=? AND cy=?", k)[0]
                for k in build.keys_of(-1, -1, 2, 2)}
        stored = {k: w.file.read_chunk(k, light=True) for k in rows}
        got = build.light_and_mesh(w, 0, 0, 1, 1, backends_=("numpy", "numpy"))
        assert [p.key for p in got] == [(0, 0)]
        c = w.chunks[(0, 0)]  # light as read (to the payload), its frame kept by compact
        assert got[0].light is c._light and np.array_equal(got[0].light, stored[(0, 0)][2])
        assert _cold(w) and packs == []
        for k, (b, light) in rows.items():
            c = w.chunks[k]
            assert c._bpack.body == b and c._lpack.body == light, k
            assert np.array_equal(c.blocks_copy(), stored[k][0]), k
            assert np.array_equal(c.light_out(), stored[k][2]), k
            top = c.air_from()  # (the frame's zero tail: whole 2 KiB slabs, 4 layers)
            assert 0 < top < C.HEIGHT and stored[k][0][:, :, top - 4:top].any() and \
                not stored[k][0][:, :, top:].any(), k
            win = np.full((5, 3, 40), 9, np.uint16, order="F")
            c.blocks_into(win, slice(2, 7), slice(10, 13), top - 20, top + 20)
            assert np.array_equal(win, stored[k][0][2:7, 10:13, top - 20:top + 20]), k
            c.light_into(win, slice(2, 7), slice(10, 13), top - 20, top + 20)
            assert np.array_equal(win, stored[k][2][2:7, 10:13, top - 20:top + 20]), k
        # a snapshot's window (zeroed: the air is not written) holds them
        snap, _ = build.snapshot(w, -1, -1, 2, 2)
        assert np.array_equal(snap, C.paste(((k, v[0]) for k, v in stored.items()),
                                            -1, -1, 2, 2))
        w.load([(2, 2)])  # not a batch: the same
        assert type(w.chunks[(2, 2)]._lpack.body) is bytes and packs == []
        # light read for writing is packed again, its stored frame dropped
        w.load([(2, 1)], hot=True)
        c = w.chunks[(2, 1)]
        c.light[1, 2, 3] = 7
        c.compact()
        assert len(packs) == 1 and c.light[1, 2, 3] == 7


def test_reloaded_batch_packs_its_light_once(tmp_path, monkeypatch):
    """A stream's batch of chunks read from the file as arrays (issue 29): their
    stored light goes to the payloads as read (not packed on load and rebuilt for
    the payload) and is packed once, by the compact after; a plain load packs it
    at once."""
    _arrays_read(monkeypatch)
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=7, backend="numpy") as w:
        build.light_and_mesh(w, -1, -1, 3, 3, backends_=("numpy", "numpy"))
        want = w.chunks[(0, 0)].light.copy()
    packs = []
    real = C.pack
    monkeypatch.setattr(C, "pack", lambda a: packs.append(id(a)) or real(a))
    with World.open(path) as w:
        got = build.light_and_mesh(w, 0, 0, 1, 1, backends_=("numpy", "numpy"))
        assert [p.key for p in got] == [(0, 0)]
        c = w.chunks[(0, 0)]
        assert got[0].light is c._light and np.array_equal(got[0].light, want)
        n, lit = len(packs), {id(c._light) for c in w.chunks.values()}
        assert _cold(w) and sum(a in lit for a in packs[n:]) == 9  # each packed once, here
        w.load([(2, 2)])  # not a batch: packed on load
        assert w.chunks[(2, 2)]._light is None and w.chunks[(2, 2)]._lpack is not None


def test_reloaded_batch_packs_blocks_once_and_decodes_none(tmp_path, monkeypatch):
    """A stream's batch of chunks read from the file as arrays (issue 29): their
    blocks stay as read until the batch's snapshot copied them, then each is packed
    once (not packed on load and decoded for the snapshot); payloads equal those of
    a batch over chunks loaded the plain way (born packed) and of one over chunks
    that keep the file's frames, and everything ends packed."""
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=7, backend="numpy") as w:
        build.light_and_mesh(w, -2, -2, 3, 3, backends_=("numpy", "numpy"))
        w.chunks[(0, 1)].set(3, 4, 200, REGISTRY.id("stone"))  # an edited chunk saved
        build.light_and_mesh(w, -1, 0, 2, 3, backends_=("numpy", "numpy"))
    nb = ("numpy", "numpy")
    with World.open(path) as w:  # the file's frames
        framed = {p.key: p for p in build.light_and_mesh(w, -1, -1, 2, 2, backends_=nb)}
    _arrays_read(monkeypatch)
    with World.open(path) as w:  # the old path: packed on load, decoded by the batch
        w.load(build.keys_of(-2, -2, 3, 3))
        want = {p.key: p for p in build.light_and_mesh(w, -1, -1, 2, 2, backends_=nb,
                                                       load=False)}
        blocks = {k: c.blocks_copy() for k, c in w.chunks.items()}
    assert sorted(framed) == sorted(want)
    for k, p in framed.items():
        q = want[k]
        assert np.array_equal(p.light, q.light) and \
            np.array_equal(p.mesh.vertices, q.mesh.vertices) and \
            np.array_equal(p.mesh.ranges, q.mesh.ranges), k
    packs, decodes = [], []
    real, unpack, into = C.pack, C.Packed.unpack, C.Packed.into
    monkeypatch.setattr(C, "pack", lambda a: packs.append(id(a)) or real(a))
    monkeypatch.setattr(C.Packed, "unpack",
                        lambda p, *a: decodes.append(p.dtype) or unpack(p, *a))
    monkeypatch.setattr(C.Packed, "into", lambda p, *a: decodes.append(p.dtype) or into(p, *a))
    with World.open(path) as w:
        got = build.light_and_mesh(w, -1, -1, 2, 2, backends_=nb)
        assert np.uint16 not in decodes  # no chunk's blocks decoded
        ring = build.keys_of(-2, -2, 3, 3)
        assert sorted(w.chunks) == sorted(ring)
        # the rectangle's blocks packed once; the ring's kept as read for the batch
        # that has them inside, or the compact sweep
        inner = build.keys_of(-1, -1, 2, 2)
        assert len(packs) == len(inner) == len(set(packs))
        assert all((w.chunks[k]._blocks is None) == (k in inner) for k in ring)
        n = len(packs)
        got2 = build.light_and_mesh(w, -2, -1, -1, 2, backends_=nb)  # a ring strip
        # (its ring's windows of the 3 chunks packed above are decoded, no more)
        assert got2 and len(decodes) <= 3 and len(packs) == n + 3
        # the compact sweep packs the rest once: every chunk's blocks packed once
        n = len(packs)
        fresh = {id(c.unread()) for c in w.chunks.values() if c.unread() is not None}
        lit = {id(c._light) for c in w.chunks.values() if c._light is not None}
        assert len(fresh) == len(w.chunks) - len(inner) - 3
        assert _cold(w) and sorted(packs[n:]) == sorted(fresh | lit)
        assert sorted(p.key for p in got) == sorted(want)
        for p in got:
            q = want[p.key]
            assert np.array_equal(p.light, q.light), p.key
            assert np.array_equal(p.mesh.vertices, q.mesh.vertices), p.key
            assert np.array_equal(p.mesh.ranges, q.mesh.ranges), p.key
        for k in ring:
            assert np.array_equal(w.chunks[k].blocks_copy(), blocks[k]), k


def test_hot_loaded_blocks_read_for_writing_stay_arrays(tmp_path, monkeypatch):
    """Blocks of a hot load that something read through .blocks (which may write
    into them) are not swapped for the pack made from them meanwhile."""
    _arrays_read(monkeypatch)
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=7, backend="numpy") as w:
        w.load([(0, 0)])
    with World.open(path) as w:
        c = w.load([(0, 0)], hot=True)[(0, 0)]
        a = c.unread()
        assert a is not None and c._bpack is None
        p = C.pack(a)
        c.blocks[1, 2, 250] = REGISTRY.id("stone")  # a writer read them
        assert c.unread() is None and not c.packed(a, p)
        assert c._blocks is a and c.get(1, 2, 250) == REGISTRY.id("stone")


def test_save_encodes_packed_chunks_as_their_arrays(tmp_path, monkeypatch):
    """A save snapshots cold chunks as their Packed blocks and light (issue 29: no
    decode under the lock; decoded into one reused buffer to encode): the rows are
    the bytes the arrays give, with any block numbering; a snapshot taken back (a
    chunk evicted while its save is in flight) and the reopened file hold them."""
    from voxel_addon.core.chunk import Chunk
    from voxel_addon.storage.rows import Encoder
    monkeypatch.setattr(C, "HOT_S", -1.0)
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=7, backend="numpy") as w:
        build.light_and_mesh(w, -1, -1, 2, 2, backends_=("numpy", "numpy"))
        assert _cold(w)
        lit = [k for k in sorted(w.chunks) if w.chunks[k].has_light]
        assert len(lit) == 9
        enc = w.file.encoder()
        mapped = Encoder(enc.codec, np.arange(len(REGISTRY), dtype=np.uint16)[::-1].copy())
        want = {}
        for k in lit:
            c = w.chunks[k]
            b, light = c.saved()
            assert b is c._bpack and light is c._lpack
            arrays = (b.unpack(), light.unpack())
            want[k] = arrays
            for e in (enc, mapped):
                assert e.row(k, b, None, light) == e.row(k, arrays[0], None, arrays[1])
            back = Chunk(k, b)
            back.light = light
            assert back._lpack is light and back._light is None
            assert np.array_equal(back.blocks, arrays[0]) and np.array_equal(back.light, arrays[1])
        hot = w.chunks[lit[0]]
        hot.blocks[0, 0, 255] = REGISTRY.id("stone")  # hot blocks: a copy goes
        b, _ = hot.saved()
        assert b is not hot.blocks and np.array_equal(b, hot.blocks)
        want[lit[0]] = (b, want[lit[0]][1])
        hot.dirty = True
    with World.open(path) as w:
        w.load(lit)
        for k in lit:
            c = w.chunks[k]
            assert np.array_equal(c.blocks, want[k][0]) and np.array_equal(c.light, want[k][1]), k


def test_batch_copies_blocks_outside_the_lock_and_drops_a_torn_copy(tmp_path, monkeypatch):
    """A batch's snapshot copies blocks without the world's lock (issue 29: the other
    worker waited on it): a block written during the copy, in place, by another
    thread, leaves no light or mesh made from the torn copy on its 3x3; the other
    chunks' are made."""
    import threading
    with World.create(tmp_path / "w.sqlite", seed=7, backend="numpy") as w:
        w.load(build.keys_of(-2, -2, 3, 3))
        real, hit = C.Chunk.blocks_into, []

        def racing(c, *a, **kw):
            if c.key == (0, 0) and not hit:
                def writer():  # (needs the lock: held by the copy, it would wait 5 s)
                    hit.append(w.set_block(3, 3, 250, "stone"))
                t = threading.Thread(target=writer)
                t.start()
                t.join(5)
                assert hit, "the snapshot held the world's lock while copying"
            return real(c, *a, **kw)
        monkeypatch.setattr(C.Chunk, "blocks_into", racing)
        got = {p.key for p in build.light_and_mesh(w, -1, -1, 2, 2,
                                                    backends_=("numpy", "numpy"))}
        assert hit and got == set()  # every chunk of the 3x3 around (0, 0)
        monkeypatch.setattr(C.Chunk, "blocks_into", real)
        got = {p.key for p in build.light_and_mesh(w, -1, -1, 2, 2,
                                                    backends_=("numpy", "numpy"))}
        assert got == set(build.keys_of(-1, -1, 2, 2))


def test_compact_packs_light_outside_the_lock_and_keeps_light_set_meanwhile(tmp_path,
                                                                             monkeypatch):
    """build.compact (a stream batch's) packs light without the world's lock; light
    set meanwhile (an edit) is the one kept, never the stale pack."""
    with World.create(tmp_path / "w.sqlite", seed=7, backend="numpy") as w:
        build.light_and_mesh(w, -1, -1, 2, 2, backends_=("numpy", "numpy"))
        keys = build.keys_of(-1, -1, 2, 2)
        old = {k: w.chunks[k].light for k in keys}
        new = C.empty()
        new[:] = 7
        real = C.pack

        def racing(a):
            if a is old[(0, 0)]:  # an edit sets (0, 0)'s light while it is packed
                w.chunks[(0, 0)].light = new
            return real(a)
        monkeypatch.setattr(C, "pack", racing)
        build.compact(w, keys)
        monkeypatch.setattr(C, "pack", real)
        for k in keys:
            c = w.chunks[k]
            assert c._light is None and c._lpack is not None, k
            assert np.array_equal(c.light, new if k == (0, 0) else old[k]), k


def test_zeroed_snapshot_windows_hold_the_blocks_however_kept():
    """blocks_into(zeroed=True) (a snapshot's fresh window: its air is not written)
    gives the blocks of a chunk kept as an array, LZ4 sections (one of them a
    uniform non-air section) or the file's frame, and writes nothing else."""
    from voxel_addon.storage import codecs
    a = C.empty()
    a[:, :, :40] = REGISTRY.id("stone")
    a[3, 4, 95] = a[0, 15, 36] = REGISTRY.id("dirt")  # (95: a hot array counts by 32)
    blob = codecs.encode("zstd", C.to_linear(a))
    top = (C.VOLUME - (codecs.zero_tail(blob) >> 1)) // (C.SIZE * C.SIZE)
    assert top == 96
    kept = {"array": C.Chunk((0, 0), a.copy(order="F"), hot=True),
            "lz4": C.Chunk((0, 0), a.copy(order="F")),
            "frame": C.Chunk((0, 0), C.Packed.frame(blob, C.SHAPE, np.uint16, top))}
    assert kept["lz4"]._bpack.body[0] == REGISTRY.id("stone")  # a uniform section
    for name, c in kept.items():
        out = C.empty(width=20, depth=20)
        c.blocks_into(out[2:18, 2:18], slice(None), slice(None), 0, C.HEIGHT, zeroed=True)
        want = np.zeros_like(out)
        want[2:18, 2:18] = a
        assert np.array_equal(out, want), name
        out = C.empty(width=5)
        c.blocks_into(out[:, 1:4], slice(1, 6), slice(2, 5), 0, C.HEIGHT, zeroed=True)
        assert np.array_equal(out[:, 1:4], a[1:6, 2:5]), name
        assert not out[:, :1].any() and not out[:, 4:].any(), name
