"""formats/chunkscan.py (anvil.read's one-pass path) against the general reader
(anvil.read(..., fast=False)): for real-shaped chunks and thousands of damaged ones,
the same sections (palettes, indices, properties, biomes), the same tags charged to
the budget, or the same error; and it does read real-shaped chunks itself."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.bench import mcsave
from voxel_addon.formats import anvil, chunkscan, nbt
from voxel_addon.formats.budget import Budget, Exceeded

from . import mcfiles as mc
from .test_fuzz import mutate, small_chunk

T = mc.T


def _odd_chunk():
    """Shapes a saved chunk has and mcsave leaves out: properties, empty and nested
    lists, block entities with items, a section without blocks, biomes of one name."""
    a = np.array(["minecraft:stone", "minecraft:oak_stairs[facing=east,half=top]",
                  "minecraft:water[level=0]"], object)[np.arange(4096).reshape(16, 16, 16) % 3]
    doc = mc.chunk_nbt(2, 3, {0: a, 1: np.full((16, 16, 16), "minecraft:air", object)},
                       biomes={0: (["minecraft:plains", "minecraft:river"], [0, 1] * 32)})
    root = {"DataVersion": 3953, "Status": "minecraft:full",
            "PostProcessing": T("list", [T("list", [], "short")] * 3, "list"),
            "block_ticks": T("list", [{"i": "minecraft:water", "t": 3}], "compound"),
            "sections": T("list", [
                {"Y": T("byte", -2), "SkyLight": T("bytes", [1] * 2048)},
                {"Y": T("byte", 5), "block_states": {"palette": T("list", [
                    {"Name": "minecraft:oak_log", "Properties": {"axis": "x"}, "x": T("ints", [1])}],
                    "compound")}, "biomes": {"palette": T("list", ["minecraft:forest"])}},
            ], "compound"),
            "structures": {"starts": {"a": {"Children": T("list", [{"BB": T("ints", [1, 2])}],
                                                               "compound")}}}}
    no_y = mc.nbt({"DataVersion": 3953, "sections": T("list", [{"block_states": {
        "palette": T("list", [{"Name": "minecraft:stone"}], "compound")}}], "compound")})
    return [no_y, doc, mc.nbt(root)]


@pytest.fixture(scope="module")
def docs():
    rng = np.random.default_rng(3)
    out = [mcsave.chunk_nbt(cx, cz) for cx, cz in ((0, 0), (5, 9), (11, 11))]
    out += [small_chunk(rng, 0, 0, v) for v in (3953, 2586)]
    return out + _odd_chunk()


def _same(a, b):
    assert (a.version, a.status, len(a.sections)) == (b.version, b.status, len(b.sections))
    for s, t in zip(a.sections, b.sections):
        assert (s.y, s.palette, s.props) == (t.y, t.palette, t.props)
        assert (s.indices is None) == (t.indices is None)
        if s.indices is not None:
            assert s.indices.dtype == t.indices.dtype and (s.indices == t.indices).all()
        assert (s.biomes is None) == (t.biomes is None)
        if s.biomes is not None:
            assert s.biomes[0] == t.biomes[0]
            assert (s.biomes[1] is None) == (t.biomes[1] is None)
            if s.biomes[1] is not None:
                assert (s.biomes[1] == t.biomes[1]).all()
    assert (a.biomes is None) == (b.biomes is None)


def _outcome(doc, fast, tags=anvil.CHUNK_TAGS):
    bud = Budget(1 << 30, tags)
    try:
        return anvil.read(doc, bud, fast=fast), bud.spent()
    except (anvil.ChunkError, nbt.NbtError, Exceeded) as e:
        return (type(e), str(e)), bud.spent()


def _compare(doc, tags=anvil.CHUNK_TAGS):
    got, want = _outcome(doc, True, tags), _outcome(doc, False, tags)
    assert got[1] == want[1]                       # the same tags charged
    if isinstance(want[0], anvil.Chunk):
        _same(got[0], want[0])
    else:
        assert got[0] == want[0]


def test_real_shaped_chunks_equal_the_general_reader(docs):
    for d in docs:
        _compare(d)
        _compare(d)   # again: palettes replayed from the memo


def test_real_shaped_chunks_take_the_one_pass_path(docs, monkeypatch):
    calls = []
    real = nbt.read
    monkeypatch.setattr(nbt, "read", lambda *a, **k: calls.append(1) or real(*a, **k))
    for d in docs[:3] + docs[3:4] + docs[6:]:       # every well-formed 1.18+ one
        anvil.read(d)
    assert not calls
    anvil.read(docs[4])                              # 1.16: the general reader
    assert calls


def test_damaged_chunks_equal_the_general_reader(docs):
    rng = np.random.default_rng(11)
    for d in docs:
        for _ in range(150):
            _compare(mutate(rng, d, 3))


def test_tag_limits_equal_the_general_reader(docs):
    for d in (docs[0], docs[-2], docs[-1]):
        tags = _outcome(d, False)[1][1]
        for lim in (tags - 1, tags, tags // 2, 10):
            _compare(d, lim)


def test_deep_and_flooded_chunks_are_refused_as_before():
    head = b"\x0a\x00\x00\x03\x00\x0bDataVersion\x00\x00\x0f\x71"
    deep = head + b"\x0a\x00\x01x" * 600 + b"\x00" * 601
    with pytest.raises(nbt.Hostile):
        anvil.read(deep)
    n = anvil.CHUNK_TAGS + 5
    flood = head + b"\x09\x00\x01x\x0a" + n.to_bytes(4, "big") + b"\x00" * n + b"\x00"
    with pytest.raises(nbt.TooMany):
        anvil.read(flood)


def test_the_palette_memos_stay_bounded():
    """A flood of distinct block and biome palettes (each chunk its own) cannot grow
    the memos (palettes, sections) past their bounds, and each chunk reads as its own."""
    import struct

    def doc(i):
        name = f"minecraft:b{i}".encode()
        block = name if i % 2 else b"minecraft:stone"   # half share one block palette
        ent = b"\x08\x00\x04Name" + struct.pack(">H", len(block)) + block + b"\x00"
        sec = (b"\x01\x00\x01Y\x00\x0a\x00\x0cblock_states\x09\x00\x07palette\x0a"
               + struct.pack(">i", 1) + ent + b"\x00\x0a\x00\x06biomes\x09\x00\x07palette\x08"
               + struct.pack(">i", 1) + struct.pack(">H", len(name)) + name + b"\x00\x00")
        return (b"\x0a\x00\x00\x03\x00\x0bDataVersion\x00\x00\x0f\x71\x09\x00\x08sections\x0a"
                + struct.pack(">i", 1) + sec + b"\x00")
    for i in range(3 * chunkscan._MEMO_MAX):
        ch = anvil.read(doc(i))
        assert ch.sections[0].palette == [f"minecraft:b{i}" if i % 2 else "minecraft:stone"]
        assert ch.sections[0].biomes[0] == [f"minecraft:b{i}"]
        assert len(chunkscan._MEMO) <= chunkscan._MEMO_MAX
        assert len(chunkscan._BIOMES) <= chunkscan._MEMO_MAX
        assert len(chunkscan._SECS) <= chunkscan._MEMO_MAX
        assert chunkscan._held[0] <= chunkscan._HELD_MAX


def _mixed_chunk():
    """4-bit sections apart (a 5-bit one and a missing one between), one 4-bit section
    of a single entry, states with properties: what read(packed=True) leaves packed."""
    rng = np.random.default_rng(5)
    names = np.array(["minecraft:stone", "minecraft:oak_stairs[facing=east,half=top]",
                      "minecraft:water[level=0]", "minecraft:white_wool", "minecraft:air",
                      "minecraft:oak_leaves[distance=3]"], object)
    wide = np.array([f"minecraft:{w}_wool" for w in ("red", "blue", "lime", "gray", "pink",
                     "cyan", "black", "brown", "green", "orange", "purple", "yellow",
                     "magenta", "light_blue", "light_gray", "white", "stone")], object)
    secs = {-4: names[rng.integers(0, 6, (16, 16, 16))], -3: wide[rng.integers(0, 17, (16, 16, 16))],
            -1: names[rng.integers(0, 3, (16, 16, 16))], 0: names[np.zeros((16, 16, 16), int)],
            2: names[rng.integers(2, 6, (16, 16, 16))]}
    return mc.chunk_nbt(1, 2, secs)


def _converted(doc, packed, y_min, tmp):
    from voxel_addon.formats import minecraft
    from voxel_addon.world import World
    try:
        ch = anvil.read(doc, None, packed=packed)
    except (anvil.ChunkError, nbt.NbtError, Exceeded) as e:
        return type(e), str(e)
    path = tmp / f"w{int(packed)}.sqlite"
    for p in (path, path.with_name(path.name + "-wal"), path.with_name(path.name + "-shm")):
        p.unlink(missing_ok=True)
    with World.create(path, seed=0, generator="empty", loader=False) as w:
        rep = minecraft.Report()
        pal = minecraft._Palettes(w, rep)
        out = [minecraft.convert(ch, y_min, pal) for _ in range(2)]   # again: memos
        return out, rep.blocks, dict(pal.states.defaults), list(pal.states.list)


def test_packed_sections_convert_as_unpacked(docs, tmp_path):
    """read(packed=True) (4-bit sections looked up by their bytes in convert) gives
    the blocks, data, dropped voxels, report counts and states of the unpacked path,
    also where the height cuts sections and for damaged chunks (or their error)."""
    rng = np.random.default_rng(17)
    cases = [(d, y) for d in docs + [_mixed_chunk()] for y in (-64, -56, 0, -200)]
    cases += [(mutate(rng, d, 3), -64) for d in (docs[0], docs[3]) for _ in range(40)]
    for doc, y_min in cases:
        got, want = _converted(doc, True, y_min, tmp_path), _converted(doc, False, y_min, tmp_path)
        if isinstance(want, tuple) and isinstance(want[0], type):
            assert got == want
            continue
        for (b, d, n), (b2, d2, n2) in zip(got[0], want[0]):
            assert n == n2 and b.flags.f_contiguous and (b == b2).all()
            assert (d is None) == (d2 is None) and (d is None or (d == d2).all())
        assert got[1:] == want[1:]


def test_convert_keeps_a_bounded_number_of_byte_tables(docs, tmp_path, monkeypatch):
    from voxel_addon.formats import convert as conv, minecraft
    from voxel_addon.world import World
    monkeypatch.setattr(conv, "PAIRS", 3)
    with World.create(tmp_path / "w.sqlite", seed=0, generator="empty", loader=False) as w:
        pal = minecraft._Palettes(w, minecraft.Report())
        for doc in docs[:3] + [_mixed_chunk()]:
            ch = anvil.read(doc, None, packed=True)
            minecraft.convert(ch, -64, pal)
            # cleared past PAIRS before a chunk adds its own (ids and values: 2 a section)
            assert len(pal.keyed[None]) <= 3 + 1 + 2 * len(ch.sections)
