"""Minecraft import against region files the tests write (tests/formats/mcfiles.py):
exact voxel positions and names, palettes of 1 and of 300+ entries, empty sections,
negative chunks, every compression type, both folder layouts, old versions, the
report, --replace, --area, Status, y-min."""
from __future__ import annotations

import os

import sqlite3

import numpy as np
import pytest

from voxel_addon.cli import main
from voxel_addon.core import chunk as C
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.formats import anvil, minecraft, nbt
from voxel_addon.world import World

from . import mcfiles as mc

AIR = "minecraft:air"
MANY = [f"minecraft:mystery_{i}" for i in range(300)]  # unknown: fallback stone


def column(rng, cx, cz):
    """Sections -> names [y][z][x] for a test chunk, and {(x, y, z): name} of the
    Minecraft blocks that are not air (world coordinates)."""
    secs, blocks = {}, {}
    # section -4 (y -64..-49): one palette entry (stone), no data
    secs[-4] = np.full((16, 16, 16), "minecraft:stone", object)
    # section 0: 300+ distinct names, a few known ones at random places
    a = np.array(MANY * 14, object)[:4096].reshape(16, 16, 16)
    a[rng.random(a.shape) < 0.5] = AIR
    known = ["minecraft:oak_planks", "minecraft:red_wool", "minecraft:glass_pane",
             "minecraft:torch", "minecraft:lava", "minecraft:cobblestone"]
    for k in range(60):
        y, z, x = rng.integers(0, 16, 3)
        a[y, z, x] = known[k % len(known)]
    secs[0] = a
    # section 2: all air (a palette of one: air)
    secs[2] = np.full((16, 16, 16), AIR, object)
    # section 12 (y 192..207): above z 255 with y_min -64 -> dropped
    b = np.full((16, 16, 16), AIR, object)
    b[0, 0, 0] = b[5, 5, 5] = "minecraft:gold_block"
    secs[12] = b
    for y, arr in secs.items():
        for (yy, zz, xx), n in np.ndenumerate(arr):
            if n != AIR:
                blocks[(16 * cx + xx, 16 * y + yy, 16 * cz + zz)] = n
    return secs, blocks


def expected(name):
    from voxel_addon.formats.mapping import lookup
    return lookup(name)[0]


def check_world(path, blocks, y_min=-64, sample=400, rng=None):
    rng = rng or np.random.default_rng(0)
    items = list(blocks.items())
    pick = [items[i] for i in rng.choice(len(items), min(sample, len(items)), replace=False)]
    with World.open(path, loader=False, readonly=True) as w:
        for (x, y, z), name in pick:
            zz = y - y_min
            if not 0 <= zz < 256:
                continue
            got = REGISTRY[w.get_block(x, -1 - z, zz)].name
            assert got == expected(name), ((x, y, z), name, got)
        # air stays air: the voxel above a known block in the empty section 2
        assert w.get_block(16 * 0, -1, 32 - y_min + 3) == 0


@pytest.mark.parametrize("kind", [1, 2, 3, 4])
def test_every_compression_and_exact_positions(tmp_path, kind):
    rng = np.random.default_rng(kind)
    chunks, blocks = {}, {}
    for cx, cz in [(0, 0), (-1, -1), (1, -33), (-40, 5)]:  # negative, other regions
        secs, b = column(rng, cx, cz)
        chunks[(cx, cz)] = mc.chunk_nbt(cx, cz, secs)
        blocks.update(b)
    save = tmp_path / "save"
    mc.write_region(save / "region", chunks, kind)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        rep = minecraft.import_world(world, save)
    assert rep.chunks == 4 and not rep.damaged and rep.y_min == -64
    assert rep.dropped == 2 * 4                     # the gold blocks above z 255
    with World.open(w, loader=False, readonly=True) as world:
        assert sorted(world.file.chunk_keys()) == sorted(
            minecraft.to_key(cx, cz) for cx, cz in chunks)
    check_world(w, blocks, rng=rng)
    assert rep.blocks["minecraft:mystery_7"][1] == "fallback"
    assert rep.blocks["minecraft:red_wool"][:2] == ["color", "class"]


def test_cli_layouts_report_and_replace(tmp_path, capsys):
    rng = np.random.default_rng(5)
    secs, blocks = column(rng, 2, 3)
    data = {(2, 3): mc.chunk_nbt(2, 3, secs),
            (4, 3): mc.chunk_nbt(4, 3, secs, status="minecraft:features"),
            (5, 3): b"\x0a\x00\x00garbage"}
    save = tmp_path / "new"
    mc.write_region(save / "dimensions/minecraft/overworld/region", data, 2)
    mc.level_dat(save, 4671)
    w = tmp_path / "w.sqlite"
    assert main(["import", "--world", str(w), "--from", str(save)]) == 0
    out = capsys.readouterr().out
    assert "1 chunks imported" in out and "1 minecraft:features" in out
    assert "damaged: 1" in out and "minecraft:red_wool -> color (class)" in out
    check_world(w, {k: v for k, v in blocks.items()})
    with World.open(w, loader=False) as world:
        assert world.file.generator == "empty" and world.file.chunk_count() == 1
        assert world.get_block(100, 100, 100) == 0          # nothing generated around
    # again: asks for --replace, then replaces
    assert main(["import", "--world", str(w), "--from", str(save)]) == 2
    assert "--replace" in capsys.readouterr().err
    assert main(["import", "--world", str(w), "--from", str(save), "--replace"]) == 0


def test_area_y_min_and_single_file(tmp_path):
    rng = np.random.default_rng(7)
    chunks, blocks = {}, {}
    for cx in range(3):
        secs, b = column(rng, cx, 0)
        chunks[(cx, 0)] = mc.chunk_nbt(cx, 0, secs)
        if cx == 1:
            blocks = b
    folder = mc.write_region(tmp_path / "mca", chunks, 3)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        rep = minecraft.import_world(world, folder / "r.0.0.mca", area=(20, 0, 30, 16),
                                     y_min=-32)
    assert rep.chunks == 1 and rep.y_min == -32
    with World.open(w, loader=False, readonly=True) as world:
        assert world.file.chunk_keys() == [(1, -1)]
    check_world(w, blocks, y_min=-32)


@pytest.mark.parametrize("version", [2586, 2230])   # 1.16 (packed), 1.15 (spanning longs)
def test_older_versions(tmp_path, version):
    rng = np.random.default_rng(version)
    secs, blocks = column(rng, 0, 0)
    secs = {y + 4: a for y, a in secs.items() if 0 <= y + 4 < 16}  # y 0..255 worlds
    blocks = {(x, y + 64, z): n for (x, y, z), n in blocks.items() if 0 <= y + 64 < 256}
    mc.write_region(tmp_path / "region", {(0, 0): mc.chunk_nbt(0, 0, secs, version,
                                                                 "full")}, 2)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        rep = minecraft.import_world(world, tmp_path)
    assert rep.chunks == 1 and rep.y_min == 0
    check_world(w, blocks, y_min=0)


def test_unsupported_and_external(tmp_path):
    old = mc.nbt({"Level": {"xPos": 0, "zPos": 0, "Blocks": mc.T("bytes", [1] * 10)}})
    mc.write_region(tmp_path / "a" / "region", {(0, 0): old}, 2)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        with pytest.raises(VoxelError, match="1.13"):
            minecraft.import_world(world, tmp_path / "a")
        secs, _ = column(np.random.default_rng(1), 0, 0)
        data = {(0, 0): mc.chunk_nbt(0, 0, secs), (1, 0): mc.chunk_nbt(1, 0, secs)}
        mc.write_region(tmp_path / "b", data, 2, external={(1, 0)})
        rep = minecraft.import_world(world, tmp_path / "b")
        assert rep.chunks == 1 and rep.external == 1
    with pytest.raises(VoxelError, match="no region files"):
        minecraft.regions_of(tmp_path)


def test_unpack_matches_a_plain_loop():
    rng = np.random.default_rng(3)
    for n in (2, 16, 17, 300, 4096):
        idx = rng.integers(0, n, 4096)
        bits = max(4, (n - 1).bit_length())
        for spanning in (False, True):
            longs = np.array(mc.pack(idx, bits, spanning), ">i8")
            assert np.array_equal(anvil.unpack(longs, n, spanning), idx)


def test_interrupted_import_keeps_finished_batches_and_resumes(tmp_path):
    """A cancelled import (Blender's Cancel, the CLI's Ctrl-C) keeps its batches; the
    same import again resumes (formats/job.py): the rows an uninterrupted one writes.
    The save mixes versions: y_min follows the plan's first chunk (1.16: 0), not the
    first one the resumed run reads (1.21: -64)."""
    secs = {0: np.full((16, 16, 16), "minecraft:stone", object)}
    secs[1] = np.where(np.arange(16)[:, None, None] < 3, "minecraft:oak_planks", secs[0])
    chunks = {(x, z): mc.chunk_nbt(x, z, secs) for x in range(8) for z in range(5)}
    chunks[(0, 0)] = mc.chunk_nbt(0, 0, secs, 2586)
    mc.write_region(tmp_path / "region", chunks, 3)

    def rows(path):
        with sqlite3.connect(path) as db:
            return (db.execute("SELECT * FROM chunks ORDER BY cx, cy").fetchall(),
                    dict(db.execute("SELECT key, value FROM meta WHERE key LIKE 'mc_%'")))

    want = tmp_path / "want.sqlite"
    with World.create(want, seed=0, generator="empty", loader=False) as world:
        assert minecraft.import_world(world, tmp_path).y_min == 0
    w = tmp_path / "w.sqlite"
    calls, said = [], []
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        rep = minecraft.import_world(world, tmp_path, progress=lambda d, t: calls.append(d),
                                     cancelled=lambda: True)
    assert rep.chunks == minecraft.BATCH and calls == [minecraft.BATCH]
    f = tmp_path / "region" / "r.0.0.mca"
    t = f.stat().st_mtime_ns
    with World.open(w, loader=False) as world:
        assert world.file.chunk_count() == minecraft.BATCH
        os.utime(f, ns=(t + 10**9, t + 10**9))   # the game saved it since: another import
        with pytest.raises(VoxelError, match="unfinished import .* before the game saved"):
            minecraft.import_world(world, tmp_path)
        os.utime(f, ns=(t, t))
        rep = minecraft.import_world(world, tmp_path, say=said.append)
    assert said == [f"resuming an interrupted import: {minecraft.BATCH} of 40 chunks already "
                    "imported"]
    assert rep.chunks == 40 - minecraft.BATCH and rep.resumed == minecraft.BATCH
    assert rep.y_min == 0 and rows(w) == rows(want)
    with World.open(w, loader=False) as world:   # finished: an import again is refused
        with pytest.raises(VoxelError, match="replace"):
            minecraft.import_world(world, tmp_path)
        assert minecraft.import_world(world, tmp_path, replace=True).chunks == 40


def test_a_refused_import_keeps_the_batches_before_it(tmp_path):
    """Batches are written behind the parse (formats/minecraft.steps): a hostile
    chunk in the second batch refuses the import with the first batch written."""
    secs = {0: np.full((16, 16, 16), "minecraft:stone", object)}
    body = mc.chunk_nbt(0, 0, secs)
    deep = b"\x0a\x00\x00\x03\x00\x0bDataVersion\x00\x00\x0f\x71" + b"\x0a\x00\x01x" * 600 \
        + b"\x00" * 601
    chunks = {(x, z): body for x in range(8) for z in range(5)}
    chunks[(3, 4)] = deep          # the 36th in the import's order (z, then x)
    mc.write_region(tmp_path / "region", chunks, 3)
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=0, generator="empty", loader=False) as world:
        with pytest.raises(VoxelError, match="refused"):
            minecraft.import_world(world, tmp_path)
    with World.open(w, loader=False) as world:
        assert world.file.chunk_count() == minecraft.BATCH


def test_the_import_without_its_helper_thread_writes_the_same(tmp_path, monkeypatch):
    """VOXEL_IMPORT_THREAD=0 (or one core): inflate and compress inline, same rows."""
    rng = np.random.default_rng(5)
    names = np.array(["minecraft:stone", "minecraft:air", "minecraft:oak_planks",
                      "minecraft:water[level=3]"], object)
    chunks = {(x, z): mc.chunk_nbt(x, z, {y: names[rng.integers(0, 4, (16, 16, 16))]
                                          for y in (-1, 0, 3)}) for x in range(6) for z in range(6)}
    mc.write_region(tmp_path / "region", chunks, 2)
    rows = []
    for flag in ("1", "0"):
        monkeypatch.setenv("VOXEL_IMPORT_THREAD", flag)
        ex = minecraft._helper()
        assert isinstance(ex, minecraft._Inline) == (flag == "0")
        ex.shutdown()
        w = tmp_path / f"w{flag}.sqlite"
        with World.create(w, seed=0, generator="empty", loader=False) as world:
            minecraft.import_world(world, tmp_path)
        db = sqlite3.connect(w)
        rows.append(db.execute("SELECT cx, cy, blocks, data FROM chunks ORDER BY cx, cy").fetchall()
                    + db.execute("SELECT * FROM mc_biomes ORDER BY cx, cy").fetchall())
        db.close()
    assert len(rows[0]) == 72 and rows[0] == rows[1]


def test_a_large_chunk_is_not_inflated_ahead_and_still_imported(tmp_path):
    """The helper thread holds at most AHEAD_MAX bytes of a chunk (a compression bomb
    is decoded only under the import's own limits): a larger chunk comes back None
    from _inflate and is decoded again by the import."""
    secs = {0: np.full((16, 16, 16), "minecraft:stone", object)}
    small = mc.chunk_nbt(0, 0, secs)
    junk = b"\x07\x00\x04junk" + (minecraft.AHEAD_MAX + 8).to_bytes(4, "big") \
        + bytes(minecraft.AHEAD_MAX + 8)
    big = small[:3] + junk + small[3:]                   # first in the root compound
    mc.write_region(tmp_path / "region", {(0, 0): big, (1, 0): small}, 2)
    from voxel_addon.formats.region import Region
    reg = Region(tmp_path / "region" / "r.0.0.mca")
    got = minecraft._inflate([(reg, 0, 0), (reg, 1, 0)])
    assert got[0] is None and got[1] == small
    done = minecraft._Inline().submit(lambda: got)
    assert minecraft._scan(done)[0] is None and minecraft._scan(done)[1][0] == small
    pre, tags = minecraft._scan(done)[1][1]             # read ahead, charged by the import
    want = anvil.read(small)
    assert [(s.y, s.palette) for s in pre.sections] == [(s.y, s.palette) for s in want.sections]
    assert tags == nbt.read(small, anvil.KEEP, anvil.CHUNK_TAGS)[1]
    with World.create(tmp_path / "w.sqlite", seed=0, generator="empty", loader=False) as world:
        rep = minecraft.import_world(world, tmp_path)
        assert rep.chunks == 2 and not rep.damaged and world.file.chunk_count() == 2


def test_arrays_used_again_hold_nothing_of_their_last_chunk(tmp_path, monkeypatch):
    """convert fills the arrays of batches already compressed (_Blank): each chunk's
    rows are those of an import with new arrays, though its chunks hold fewer blocks
    and states than ones before them (three batches)."""
    rng = np.random.default_rng(7)
    names = np.array(["minecraft:stone", "minecraft:water[level=3]",
                      "minecraft:oak_stairs[facing=east,half=top,shape=straight,waterlogged=false]",
                      "minecraft:oak_stairs[facing=west,half=top,shape=straight,waterlogged=false]"],
                     object)   # one stairs state is not the default: data
    chunks = {}
    for i in range(2 * minecraft.BATCH + 6):
        top = int(rng.integers(1, 64))
        a = names[rng.integers(0, 4, (64, 16, 16))]
        a[top:] = "minecraft:air"
        chunks[(i % 9, i // 9)] = mc.chunk_nbt(i % 9, i // 9, {y: a[16 * y:16 * y + 16] for y in range(4)})
    mc.write_region(tmp_path / "region", chunks, 2)
    rows = []
    for fresh in (False, True):
        if fresh:
            monkeypatch.setattr(minecraft._Blank, "__call__", lambda self: C.empty())
        w = tmp_path / f"w{fresh}.sqlite"
        with World.create(w, seed=0, generator="empty", loader=False) as world:
            minecraft.import_world(world, tmp_path)
        db = sqlite3.connect(w)
        rows.append(db.execute("SELECT cx, cy, blocks, data FROM chunks ORDER BY cx, cy").fetchall())
        db.close()
    assert len(rows[0]) == len(chunks) and rows[0] == rows[1]
    assert sum(r[3] is not None for r in rows[0]) > len(chunks) // 2   # states kept
