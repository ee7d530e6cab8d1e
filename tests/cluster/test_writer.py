"""The cluster commands' one writer commits through the versioned write path: a chunk
another writer stored while the job ran is kept (generate; import without
--replace), an edit saved meanwhile is applied again over an imported chunk (import
--replace), and the workers' decoding stays inside the hostile-input budgets. The
tasks run in this process (cluster.Serial, the same functions the workers run), and
the other writer is a second World on the same file, writing between two batches."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import cluster
from voxel_addon.cluster import generate, imports
from voxel_addon.core import chunk as C
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.formats import budget, minecraft
from voxel_addon.world import World
from tests.formats import hostile as H
from tests.formats import mcfiles as mc

STONE = {0: np.full((16, 16, 16), "minecraft:stone", object)}


def _save(path, n=8):
    mc.write_region(path / "region", {(x, 0): mc.chunk_nbt(x, 0, STONE) for x in range(n)})
    return path


def _glass():
    return np.full(C.SHAPE, REGISTRY.id("glass"), np.uint16, order="F")


def _meanwhile(path, act):
    """A progress callback doing `act(other world)` once, after the first commit."""
    done = []

    def progress(n, total):
        if n and not done:
            done.append(n)
            with World.open(path, loader=False) as other:
                act(other)
    return progress, done


@pytest.fixture
def small_commits(monkeypatch):
    monkeypatch.setenv("VOXEL_COMMIT", "2")


def test_generate_keeps_a_chunk_stored_meanwhile(tmp_path, small_commits):
    p = tmp_path / "w.sqlite"
    keys = [(x, 0) for x in range(6)]
    progress, done = _meanwhile(p, lambda o: o.store_chunks([(keys[-1], _glass(), None)]))
    with World.create(p, seed=3, generator="flat", backend="numpy", loader=False) as w:
        made, computed = generate.run(w, cluster.Serial(), keys, "numpy", progress)
        assert done and done[0] < len(keys)  # the other writer came between two batches
        assert computed == 6 and made == 5
        assert (w.file.read_chunk(keys[-1])[0] == REGISTRY.id("glass")).all()


def test_import_keeps_a_chunk_stored_meanwhile(tmp_path, small_commits):
    save, p = _save(tmp_path / "save"), tmp_path / "w.sqlite"
    last = minecraft.to_key(7, 0)
    progress, done = _meanwhile(p, lambda o: o.store_chunks([(last, _glass(), None)]))
    rep = minecraft.Report()
    with World.create(p, seed=0, generator="empty", loader=False) as w:
        imports.run(w, cluster.Serial(), save, progress=progress, report=rep)
        assert done and (rep.chunks, rep.kept) == (7, 1)
        assert (w.file.read_chunk(last)[0] == REGISTRY.id("glass")).all()
        assert (w.file.read_chunk(minecraft.to_key(6, 0))[0] != REGISTRY.id("glass")).all()


def test_import_replace_applies_edits_saved_meanwhile(tmp_path, small_commits):
    save, p = _save(tmp_path / "save"), tmp_path / "w.sqlite"
    key = minecraft.to_key(7, 0)
    x, y = key[0] * 16 + 3, key[1] * 16 + 4
    with World.create(p, seed=0, generator="empty", loader=False) as w:
        minecraft.import_world(w, save)

    def edit(o):
        o.set_block(x, y, 200, "glass")
        o.flush()
    progress, done = _meanwhile(p, edit)
    rep = minecraft.Report()
    with World.open(p, loader=False) as w:
        imports.run(w, cluster.Serial(), save, replace=True, progress=progress, report=rep)
        assert done and rep.chunks == 8
        blocks, _ = w.file.read_chunk(key)
        assert blocks[3, 4, 200] == REGISTRY.id("glass")  # the import did not undo it
        assert blocks[3, 4, 201] == 0


def test_workers_decode_inside_the_budgets(tmp_path, monkeypatch):
    bomb = tmp_path / "bomb"
    mc.write_region(bomb / "region", {(0, 0): mc.chunk_nbt(0, 0, STONE),
                                      (1, 0): H.tag_bomb(1 << 20)})
    with World.create(tmp_path / "a.sqlite", seed=0, generator="empty", loader=False) as w:
        with pytest.raises(VoxelError, match=r"chunk \(1, 0\).*in one chunk.*import refused"):
            imports.run(w, cluster.Serial(), bomb)
    # the import's budget: charged by the writer with what the workers decoded
    save = _save(tmp_path / "save", 4)
    monkeypatch.setattr(budget, "TAGS_FLOOR", 50)
    monkeypatch.setattr(budget, "TAGS_PER_INPUT", 0)
    with World.create(tmp_path / "b.sqlite", seed=0, generator="empty", loader=False) as w:
        with pytest.raises(VoxelError, match="more than 50 NBT tags in this import"):
            imports.run(w, cluster.Serial(), save)


def test_workers_encode_data_blobs_as_one_process(tmp_path, monkeypatch):
    """Tasks that go out once the writer has settled some chunks carry the block
    states' world values; workers encode those chunks' data blobs themselves (the
    writer's largest cost), the writer those with a state not settled yet: all equal to
    the one-process import, bit for bit, colours met in another order per chunk."""
    from tests.cluster.test_cluster import chunks, meta, save_folder
    save = save_folder(tmp_path / "save")
    one, two = tmp_path / "one.sqlite", tmp_path / "two.sqlite"
    with World.create(one, seed=0, generator="empty", loader=False) as w:
        rep1 = minecraft.import_world(w, save)
    made = {"worker": 0, "writer": 0}
    read = imports.read

    def counted(item, shared):
        out = read(item, shared)
        for r, _, _ in out:
            if r[0] == "ok" and r[3] is not None:
                made["worker" if isinstance(r[3], tuple) else "writer"] += 1
        return out
    monkeypatch.setattr(imports, "read", counted)

    class Two(cluster.Serial):
        size = 2  # tasks of 3 chunks (the first 8 of one)
    rep2 = minecraft.Report()
    with World.create(two, seed=0, generator="empty", loader=False) as w:
        imports.run(w, Two(), save, report=rep2)
    assert made["worker"] > 30 and made["writer"] >= 1, made  # both ways taken
    assert chunks(two) == chunks(one)
    # a task's palette lists settled chunk by chunk: the same states, colours, biomes
    # and report lines (names in the order met, voxels per name) as one process
    for key in ("colors", "mc_states", "mc_state_defaults", "mc_color_states", "mc_biome_names"):
        assert meta(two, key) == meta(one, key), key
    assert biomes(two) == biomes(one)
    assert rep2.lines() == rep1.lines() and list(rep2.blocks) == list(rep1.blocks)


def biomes(p):
    import sqlite3
    with sqlite3.connect(p) as db:
        return sorted(db.execute("SELECT * FROM mc_biomes"))


def test_a_default_decided_while_tasks_are_out(tmp_path, monkeypatch):
    """A block's default state decided by a chunk still in flight (the first window
    goes out with nothing known) after later tasks were sent with that state's index:
    the writer zeroes those voxels in the workers' blobs (colour voxels of the same
    number stay), bit for bit as one process."""
    from tests.cluster.test_cluster import chunks
    logx, logy = "minecraft:oak_log[axis=x]", "minecraft:oak_log[axis=y]"
    wool = ["minecraft:red_wool", "minecraft:blue_wool", "minecraft:lime_wool"]
    rng = np.random.default_rng(5)
    region = {}
    for cx in range(16):
        a = np.full((16, 16, 16), "minecraft:air", object)
        a[0] = "minecraft:stone"
        spots = rng.permutation(16 * 16)[:40]
        a[1].reshape(-1)[spots[:5]] = logx
        a[1].reshape(-1)[spots[5:8]] = wool   # colour indices: small numbers too
        if cx == 0:
            a[2].reshape(-1)[:50] = logy      # log seen, not decided: 55 voxels
        if cx == 6:
            a[3:5] = logx                     # 512 voxels: log's default is axis=x
        region[(cx, 0)] = mc.chunk_nbt(cx, 0, {0: a})
    save = tmp_path / "save"
    mc.write_region(save / "region", region)
    one, two = tmp_path / "one.sqlite", tmp_path / "two.sqlite"
    with World.create(one, seed=0, generator="empty", loader=False) as w:
        minecraft.import_world(w, save)
    made = []
    redefault = imports._Writer._redefault

    def counted(self, *a):
        made.append(a[0])
        return redefault(self, *a)
    monkeypatch.setattr(imports._Writer, "_redefault", counted)

    class Two(cluster.Serial):
        size = 2
    with World.create(two, seed=0, generator="empty", loader=False) as w:
        imports.run(w, Two(), save)
    assert made, "no blob was encoded before its block's default was decided"
    assert chunks(two) == chunks(one)


def test_a_task_met_a_state_its_later_chunks_lack(tmp_path):
    """A task's palette is the task's: a chunk that meets a state nobody knew yet makes
    the later chunks of its task carry that state too (not theirs, no voxel has it)
    while every state they do have is known: the worker encodes their blobs, and the
    writer compares only the states the chunk has (else it would take the stranger's
    value for a changed default and stop the import)."""
    from tests.cluster.test_cluster import chunks
    stairs = [f"minecraft:oak_stairs[facing={f},half={h},shape={s}]"
              for f in ("north", "south", "east", "west") for h in ("top", "bottom")
              for s in ("straight", "inner_left", "inner_right")]
    keys = [(x, 0) for x in range(24)]
    save = tmp_path / "save"

    def write(order):
        region = {}
        for pos, k in enumerate(order):
            a = np.full((16, 16, 16), "minecraft:air", object)
            a[0] = "minecraft:stone"
            a[1, 0, :5] = "minecraft:oak_log[axis=y]"   # known once the first is settled
            if pos == 0:
                a[2:4] = "minecraft:oak_log[axis=x]"    # 512 voxels: the log's default
            elif pos % 2 == 0:
                a[1, 1, 0] = stairs[pos // 2]                # a state met here first
            region[k] = mc.chunk_nbt(k[0], k[1], {0: a})
        mc.write_region(save / "region", region)
    write(keys)
    order = [(cx, cz) for _, cx, cz in minecraft.plan(save)]
    write(order)   # the plan's order: every other chunk meets a new state
    one, two = tmp_path / "one.sqlite", tmp_path / "two.sqlite"
    with World.create(one, seed=0, generator="empty", loader=False) as w:
        minecraft.import_world(w, save)

    class Two(cluster.Serial):
        size = 1  # tasks of 3 chunks after the first window's 4 of one
    with World.create(two, seed=0, generator="empty", loader=False) as w:
        imports.run(w, Two(), save)
    assert chunks(two) == chunks(one)


def test_the_last_tasks_are_smaller():
    """The last 2 tasks per worker take a quarter of the step, so the workers finish
    together; every item is in exactly one task."""
    for n, workers in ((1089, 2), (4096, 2), (800, 8)):
        step = cluster.task_size(n, workers)
        sizes, left = [], n
        while left > 0:   # as the commands slice
            sizes.append(min(left, cluster.tail(left, step, workers)))
            left -= sizes[-1]
        assert sum(sizes) == n and min(sizes) >= 1
        big = [i for i, s in enumerate(sizes) if s == step]
        end = sum(sizes[big[-1] + 1:]) if big else n
        assert 2 * workers * step - step < end <= 2 * workers * step, (n, workers, sizes)
        assert all(s <= step // 4 for s in sizes[len(big):])


def test_a_chunk_naming_more_than_255_biomes(tmp_path):
    """A hostile chunk whose biome palette names 300 biomes: workers number biomes per
    chunk (bytes), the world keeps at most 255 (names past them read as entry 0);
    the columns come out as one process makes them, also for the names past 256 in
    the chunk (not wrapped to others) and for a later chunk reusing some of them."""
    names = [f"minecraft:b{i}" for i in range(300)]
    cells = np.arange(64) % 16 + 240
    # the columns' tops (cells 48-63): names the world keeps (1-253 with plains first)
    # and names past its 255 (254-299)
    cells[48:] = [250, 251, 252, 253, 254, 256, 260, 270, 280, 290, 299, 0, 1, 2, 3, 4]
    secs = {0: np.full((16, 16, 16), "minecraft:stone", object)}
    later = {0: (["minecraft:b0", "minecraft:b3", "minecraft:b290"], np.arange(64) % 3)}
    save = tmp_path / "save"
    mc.write_region(save / "region", {
        (0, 0): mc.chunk_nbt(0, 0, secs, biomes={0: (names, cells)}),
        (1, 0): mc.chunk_nbt(1, 0, secs, biomes=later),
        (2, 0): mc.chunk_nbt(2, 0, secs, biomes={0: (names[::-1], cells)})})
    one, two = tmp_path / "one.sqlite", tmp_path / "two.sqlite"
    with World.create(one, seed=0, generator="empty", loader=False) as w:
        minecraft.import_world(w, save)
    with World.create(two, seed=0, generator="empty", loader=False) as w:
        imports.run(w, cluster.Serial(), save)
    from tests.cluster.test_cluster import meta
    assert meta(two, "mc_biome_names") == meta(one, "mc_biome_names")
    got, want = biomes(two), biomes(one)
    assert len(want) == 3 and got == want
    # the oracle itself: one process gave some columns 0 (past the world's 255) and
    # others their own entries above 200 (names met before the cap)
    import json
    import zlib
    col = np.frombuffer(zlib.decompress(want[0][2]), np.uint8)
    assert len(json.loads(meta(one, "mc_biome_names"))) == 255
    assert (col == 0).any() and (col > 200).any() and (col < 10).any()


def test_workers_reading_the_files_meet_external_and_broken_chunks(tmp_path):
    """A local cluster's workers read the region files themselves (the writer does not
    read a chunk's sectors to plan): a chunk stored in an .mcc file and one whose
    length does not fit its sectors are reported as the one-process import does."""
    from tests.cluster.test_cluster import chunks
    save = tmp_path / "save"
    f = mc.write_region(save / "region", {(x, 0): mc.chunk_nbt(x, 0, STONE) for x in range(5)},
                        external={(1, 0)}) / "r.0.0.mca"
    raw = bytearray(f.read_bytes())
    at = int.from_bytes(raw[12:15], "big") * 4096   # chunk (3, 0): its length, too long
    raw[at:at + 4] = (1 << 30).to_bytes(4, "big")
    f.write_bytes(bytes(raw))
    one, two = tmp_path / "one.sqlite", tmp_path / "two.sqlite"
    with World.create(one, seed=0, generator="empty", loader=False) as w:
        rep1 = minecraft.import_world(w, save)

    class Near(cluster.Serial):
        local = True   # as --workers: the workers get the files' paths
    rep2 = minecraft.Report()
    with World.create(two, seed=0, generator="empty", loader=False) as w:
        imports.run(w, Near(), save, report=rep2)
    assert (rep2.chunks, rep2.external, len(rep2.damaged)) == (3, 1, 1)
    assert rep2.lines() == rep1.lines() and rep2.damaged == rep1.damaged
    assert chunks(two) == chunks(one)


def test_import_maps_its_batches_onto_palettes_another_import_moved(tmp_path, monkeypatch):
    """Another import adds its block states, dye colours, default states and biome
    names between two commits, at the indices this import's next batches use: those
    batches are mapped onto the file's palettes (not written over them), and both
    saves' chunks show what each shows imported alone."""
    monkeypatch.setenv("VOXEL_COMMIT", "1")
    red = mc.dyed_save(tmp_path / "red", "red", "x", "minecraft:desert", (0, 1, 2, 3))
    blue = mc.dyed_save(tmp_path / "blue", "blue", "z", "minecraft:jungle", (6,))
    keys = [(x, -1) for x in (0, 1, 2, 3, 6)]
    for name, run in (("red", lambda w: imports.run(w, cluster.Serial(), red)),
                      ("blue", lambda w: minecraft.import_world(w, blue))):
        with World.create(tmp_path / f"{name}.sqlite", seed=1, generator="empty",
                          loader=False) as w:
            run(w)
    want = {**mc.shown(tmp_path / "red.sqlite", keys[:4]),
            **mc.shown(tmp_path / "blue.sqlite", keys[4:])}
    p = tmp_path / "both.sqlite"
    progress, done = _meanwhile(p, lambda o: minecraft.import_world(o, blue))
    with World.create(p, seed=1, generator="empty", loader=False) as w:
        imports.run(w, cluster.Serial(), red, progress=progress, report=(rep := minecraft.Report()))
    assert done == [1] and rep.chunks == 4
    got = mc.shown(p, keys)
    for k, (st, rgb, bio) in want.items():
        assert (got[k][0] == st).all() and (got[k][1] == rgb).all(), k
        assert (got[k][2] == bio).all(), k
