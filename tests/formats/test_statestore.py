"""How an import stores block states (formats/mcstate.py, storage/minecraft.py): data
0 is the block's default state, other states carry their index. Round trips against
the region's own blocks (bench/mcsave.py writes the file from a code array: that
array is the oracle), the data left 0 wherever the state is the default, a world
written before defaults (data = index) read and grown as before, the cluster writer
bit for bit equal to one process, and readers that get no data at all."""
from __future__ import annotations

import json
import sqlite3

import numpy as np
import pytest

from voxel_addon.bench import mcsave
from voxel_addon.core import colors
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.formats import mapping, mcstate, minecraft
from voxel_addon.storage import minecraft as mcfile
from voxel_addon.world import World

from . import mcfiles as mc

CHUNKS = [(0, 0), (1, 0), (0, 1), (1, 1), (11, 0), (6, 3)]   # huts: (0, 0), (11, 0); sea: (6, 3)
COLOR = REGISTRY.id("color")


def _expected():
    """Per Minecraft state code: (block id, state key or "" for air) as mapped."""
    out = []
    for name, props in mcsave.STATES:
        block, _, _ = mapping.lookup(name)
        out.append((REGISTRY.id(block), mcstate.state_key(name, props) if block != "air" else ""))
    return out


def _save(path, chunks=CHUNKS):
    mc.write_region(path / "region", {k: mcsave.chunk_nbt(*k) for k in chunks})
    return path


@pytest.fixture(scope="module")
def save(tmp_path_factory):
    return _save(tmp_path_factory.mktemp("save"))


def _import(path, save, **kw):
    with World.create(path, seed=0, generator="empty", loader=False) as w:
        return minecraft.import_world(w, save, **kw)


def _read(path):
    """{key: (blocks, data, states as strings [lx, ly, z])} of every chunk, read as
    the bake and the live view read them, and the meta."""
    with World.open(path, loader=False, readonly=True) as w:
        meta = dict(w.file.meta)
        pal = json.loads(meta[mcfile.STATES])
        cst = {int(k): v for k, v in json.loads(meta.get(mcfile.COLOR_STATES) or "{}").items()}
        dflt = mcfile.defaults(meta)
        out = {}
        for k in w.file.chunk_keys():
            b, d = w.file.read_chunk(k)
            st = mcfile.states(b, d, pal, cst, COLOR, dflt)
            out[tuple(k)] = (b, d, np.array(pal, object)[st])
    return out, meta


def _oracle(cx, cz):
    """(block ids, state strings) [lx, ly, z] of Minecraft chunk (cx, cz), from the code
    array the region file was written from (y_min -64: z = y + 64, 256 high)."""
    codes = mcsave.chunk(cx, cz)[:256].transpose(2, 1, 0)[:, ::-1, :]
    exp = _expected()
    ids = np.array([e[0] for e in exp], np.uint16)[codes]
    keys = np.array([e[1] for e in exp], object)[codes]
    return ids, keys


def test_every_voxel_reads_back_its_state(save, tmp_path):
    _import(tmp_path / "w.sqlite", save)
    got, meta = _read(tmp_path / "w.sqlite")
    assert len(got) == len(CHUNKS)
    differs = 0
    for cx, cz in CHUNKS:
        ids, keys = _oracle(cx, cz)
        b, d, st = got[minecraft.to_key(cx, cz)]
        assert (b == ids).all()
        assert (st == keys).all(), f"chunk {cx, cz}: {np.unique(st[st != keys])}"
        differs += int(((d if d is not None else 0) != 0).sum())
    assert differs          # states other than the defaults are there (granite, stairs…)
    dflt = json.loads(meta[mcfile.DEFAULTS])
    pal = json.loads(meta[mcfile.STATES])
    assert pal[dflt["stone"]] == "minecraft:stone"
    assert pal[dflt["water"]] == "minecraft:water[level=0]"
    assert pal[dflt["water"]] != pal[dflt["stone"]]
    # a few flowers per chunk (under mcstate.SETTLE) decide nothing: they keep indices
    assert "flowers" not in dflt and "color" not in dflt


def test_data_is_zero_where_the_state_is_the_default(save, tmp_path):
    """What makes the channel cheap: only states that differ from their block's
    default carry data, the `color` block's data is its colour."""
    _import(tmp_path / "w.sqlite", save)
    got, meta = _read(tmp_path / "w.sqlite")
    pal = json.loads(meta[mcfile.STATES])
    dflt = mcfile.defaults(meta)
    palette = colors.parse(meta)
    seen = set()
    # blocks decided in the first chunk that has SETTLE of them (ore is not: a chunk
    # imported before its decision keeps indices, valid ones)
    common = np.isin(np.arange(len(REGISTRY)), [REGISTRY.id(n) for n in (
        "stone", "deepslate", "dirt", "grass", "water")])
    for key, (b, d, st) in got.items():
        d = np.zeros(b.shape, np.uint16) if d is None else d
        plain = (b != COLOR) & (b != 0)
        own = np.array(pal, object)[dflt[b]]
        assert (d[common[b] & (st == own)] == 0).all()
        assert (d[plain & (st != own)] != 0).all()
        col = b == COLOR
        for v, s in {(int(v), s) for v, s in zip(d[col], st[col])}:
            base = s.split(":")[1]
            assert palette[v].tolist() == list(mapping.lookup(base)[1]), s
            seen.add(s)
    assert seen == {"minecraft:white_wool", "minecraft:red_terracotta"}
    # the first chunk decided stone: its most common stone-block state
    ids, keys = _oracle(0, 0)
    stone = keys[ids == REGISTRY.id("stone")]
    names, n = np.unique(stone, return_counts=True)
    assert pal[dflt[REGISTRY.id("stone")]] == names[n.argmax()] == "minecraft:stone"


def test_a_world_from_before_defaults_reads_and_grows_as_before(save, tmp_path):
    """Written by the import before defaults: data the state index, no
    `mc_state_defaults`. It reads the same, and a later import keeps that meaning."""
    p = tmp_path / "old.sqlite"
    _import(p, save, area=(0, 0, 32, 16))
    new, _ = _read(p)
    with World.open(p, loader=False) as w:     # rewrite it as the old import wrote it
        meta = w.file.meta
        pal = json.loads(meta[mcfile.STATES])
        cst = {int(k): v for k, v in json.loads(meta[mcfile.COLOR_STATES]).items()}
        dflt = mcfile.defaults(meta)
        rows = []
        for k in w.file.chunk_keys():
            b, d = w.file.read_chunk(k)
            full = mcfile.states(b, d, pal, cst, COLOR, dflt).astype(np.uint16)
            rows.append((tuple(k), b, np.where(b == COLOR, d, full)))
        w.store_chunks(rows)
    with sqlite3.connect(p) as db:
        db.execute("DELETE FROM meta WHERE key = ?", (mcfile.DEFAULTS,))
    old, meta = _read(p)
    assert mcfile.DEFAULTS not in meta
    for k, (b, d, st) in old.items():
        assert (st == new[k][2]).all()
        assert d is not None and (d[b == REGISTRY.id("stone")] != 0).all()
    with World.open(p, loader=False) as w:       # the rest of the save, into the old world
        minecraft.import_world(w, save, area=(0, 16, 32, 32))
        minecraft.import_world(w, save, area=(16 * 11, 0, 16 * 12, 16))
        minecraft.import_world(w, save, area=(16 * 6, 48, 16 * 7, 64))
    grown, meta = _read(p)
    assert mcfile.DEFAULTS not in meta and len(grown) == len(CHUNKS)
    for cx, cz in CHUNKS:
        b, d, st = grown[minecraft.to_key(cx, cz)]
        assert (st == _oracle(cx, cz)[1]).all()
        assert (d[b == REGISTRY.id("stone")] != 0).all()     # index, not 0


def test_the_cluster_writer_stores_the_same_bytes(save, tmp_path, monkeypatch):
    from voxel_addon import cluster
    from voxel_addon.cluster import imports
    monkeypatch.setenv("VOXEL_COMMIT", "2")     # defaults decided across commits
    one, two = tmp_path / "one.sqlite", tmp_path / "two.sqlite"
    _import(one, save)
    with World.create(two, seed=0, generator="empty", loader=False) as w:
        imports.run(w, cluster.Serial(), save)
    q = "SELECT cx, cy, codec, blocks, data FROM chunks ORDER BY cx, cy"
    with sqlite3.connect(one) as a, sqlite3.connect(two) as b:
        assert a.execute(q).fetchall() == b.execute(q).fetchall()
        for key in (mcfile.STATES, mcfile.DEFAULTS, mcfile.COLOR_STATES, colors.KEY):
            m = "SELECT value FROM meta WHERE key = ?"
            assert a.execute(m, (key,)).fetchone() == b.execute(m, (key,)).fetchone()


def test_readers_draw_models_of_chunks_without_data(tmp_path):
    """All default states (no colour block, a layer of each block: mcstate.SETTLE):
    the chunk's data is NULL, and the bake and the live view still see every state."""
    from tests.mcres import packfiles as pf
    from voxel_addon.bake import models as bake_models
    from voxel_addon.cli import main
    from voxel_addon.world import models as world_models
    a = np.full((16, 16, 16), "minecraft:air", object)
    a[0] = "minecraft:stone"
    a[1] = "minecraft:oak_stairs[facing=east,half=bottom,shape=straight,waterlogged=false]"
    a[2] = "minecraft:poppy"
    mc.write_region(tmp_path / "save" / "region", {(0, 0): mc.chunk_nbt(0, 0, {0: a})})
    jar = pf.write(tmp_path / "client.jar", jar=True)
    p = tmp_path / "w.sqlite"
    assert main(["import", "--world", str(p), "--from", str(tmp_path / "save"),
                 "--resources", str(jar)]) == 0
    with World.open(p, loader=False, readonly=True) as w:
        b, d = w.file.read_chunk((0, -1))
        assert d is None
        m, note = bake_models.of_world(w, 0, -16, 16, 0, b, None)
        assert m is not None, note
        pal = np.array(m.palette, object)
        assert (pal[m.state[:, :, 66]] == "minecraft:poppy").all()
        assert all(s.startswith("minecraft:oak_stairs[facing=east") for s in
                   pal[m.state[:, :, 65]].ravel())
        assert (pal[m.state[:, :, 64]] == "minecraft:stone").all()
        ring = np.zeros((18, 18, 256), np.uint16, order="F")
        ring[1:-1, 1:-1] = b
        got = world_models.build(w, ring, None, 0, -1)
        assert (0, -1) in got and got[(0, -1)].mesh.quads


def test_a_floor_of_wool_keeps_its_colour(tmp_path):
    """Enough `color` voxels to decide a default if colours took part: their data
    stays their colour, never 0 for 'the usual one'."""
    a = np.full((16, 16, 16), "minecraft:air", object)
    a[0] = "minecraft:white_wool"
    a[1, :8] = "minecraft:red_wool"
    mc.write_region(tmp_path / "save" / "region", {(0, 0): mc.chunk_nbt(0, 0, {0: a})})
    _import(tmp_path / "w.sqlite", tmp_path / "save")
    got, meta = _read(tmp_path / "w.sqlite")
    b, d, st = got[(0, -1)]
    pal = colors.parse(meta)
    assert "color" not in json.loads(meta[mcfile.DEFAULTS])
    assert pal[d[:, :, 64]].tolist() == [[list(mapping.DYES["white"])] * 16] * 16
    assert (st[:, 8:, 65] == "minecraft:red_wool").all() and (st[:, :, 64] == "minecraft:white_wool").all()
