"""Edits: model check with undo/redo against full recomputes, refusals, payloads, saving."""
from __future__ import annotations

import hashlib

import numpy as np
import pytest

from voxel_addon import light, meshing
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.generation import make_generator
from voxel_addon.world import Stream, World, build
from voxel_addon.world.edit import Record, edit, redo, undo, write

SEED = 7
PALETTE = [REGISTRY.id(n) for n in ("air", "stone", "glass", "lamp_red", "lamp_blue",
                                    "leaves", "water", "torch" if "torch" in REGISTRY.names()
                                    else "sand")]


def top(w, x, y):
    c = w.chunk_at(x >> 4, y >> 4)
    return int(np.flatnonzero(c.blocks[x & 15, y & 15])[-1])


def check_against_full(w, path, model, cx0, cy0, cx1, cy1):
    """Blocks = generated terrain + model; light and meshes of every chunk that has
    them = a full NumPy recompute of the region."""
    gen = make_generator("overworld", SEED, None, "numpy")
    keys = [(x, y) for y in range(cy0 - 1, cy1 + 1) for x in range(cx0 - 1, cx1 + 1)]
    region = np.zeros((16 * (cx1 - cx0 + 2), 16 * (cy1 - cy0 + 2), 256), np.uint16, order="F")
    for (kx, ky), a in zip(keys, gen.generate(keys)):
        region[16 * (kx - cx0 + 1):16 * (kx - cx0 + 2), 16 * (ky - cy0 + 1):16 * (ky - cy0 + 2)] = a
    for (x, y, z), (b, _) in model.items():
        region[x - 16 * (cx0 - 1), y - 16 * (cy0 - 1), z] = b
    assert np.array_equal(w.region_blocks(cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1), region)
    for (x, y, z), (b, d) in model.items():
        c = w.chunk_at(x >> 4, y >> 4)
        assert (0 if c.data is None else int(c.data[x & 15, y & 15, z])) == d
    full = light.region_light(region, backend="numpy")
    meshes = meshing.build_chunks(region[15:-15, 15:-15], (cx0, cy0), backend="numpy")
    n = 0
    for k, m in meshes.items():
        c = w.chunks.get(k)
        if c is None or c.light is None:
            continue
        i, j = 16 * (k[0] - cx0), 16 * (k[1] - cy0)
        assert np.array_equal(c.light, full[i:i + 16, j:j + 16]), k
        if c.mesh is not None:
            assert np.array_equal(c.mesh.vertices, m.vertices), k
            assert np.array_equal(c.mesh.ranges, m.ranges), k
        n += 1
    return n


def test_random_strokes_with_undo_redo_equal_model_and_full_recompute(world_path):
    rng = np.random.default_rng(11)
    model: dict = {}          # voxel -> (id, data), over the generated terrain
    base: dict = {}           # voxel -> generated (id, data)
    done: list[Record] = []
    redo_stack: list[Record] = []
    seen_keys = set()
    with World.create(world_path, seed=SEED, loader=False) as w:
        for step in range(40):
            op = rng.random()
            if op < 0.15 and done:
                rec = done.pop()
                payloads = undo(w, rec)
                redo_stack.append(rec)
                for v, b in zip(rec.voxels, rec.before):
                    model[v] = b
            elif op < 0.3 and redo_stack:
                rec = redo_stack.pop()
                payloads = redo(w, rec)
                done.append(rec)
                for v, a in zip(rec.voxels, rec.after):
                    model[v] = a
            else:
                cx, cy = int(rng.integers(0, 40)), int(rng.integers(0, 40))
                stroke = []
                for _ in range(int(rng.integers(1, 7))):
                    x, y = cx + int(rng.integers(-2, 3)), cy + int(rng.integers(-2, 3))
                    z = top(w, x, y) + int(rng.integers(-2, 3))
                    b = int(rng.choice(PALETTE))
                    d = int(rng.integers(0, 4)) if rng.random() < 0.3 else 0
                    if (x, y, z) not in base:
                        c = w.chunk_at(x >> 4, y >> 4)
                        base[(x, y, z)] = (c.get(x & 15, y & 15, z), 0)
                    stroke.append((x, y, z, b, d))
                if rng.random() < 0.4:  # a drag: parts held in memory, one write
                    parts = [edit(w, [ch], write=False) for ch in stroke]
                    write(w)
                    payloads = [p for ps, _ in parts for p in ps]
                    payloads = list({p.key: p for p in payloads}.values())
                    rec = _merge([r for _, r in parts])
                else:
                    payloads, rec = edit(w, stroke)
                for x, y, z, b, d in stroke:
                    model[(x, y, z)] = (b, d)
                if rec.voxels:
                    done.append(rec)
                    redo_stack.clear()
                # the record holds exactly the voxels that changed, before and after
                for v, b0, a in zip(rec.voxels, rec.before, rec.after):
                    assert b0 != a and model[v] == a
            keys = {p.key for p in payloads}
            seen_keys |= keys
            for p in payloads:
                assert p.version == w.pver[p.key]
                c = w.chunks[p.key]
                assert p.light is c.light and p.mesh is c.mesh
        n = check_against_full(w, world_path, model, -1, -1, 4, 4)
        assert n >= 9
    # every stroke was saved: a fresh open sees the model, and the light stored with
    # the chunks (what reloading uses instead of a solve) is still exact
    with World.open(world_path, loader=False) as w:
        for (x, y, z), (b, d) in model.items():
            c = w.chunk_at(x >> 4, y >> 4)
            assert c.get(x & 15, y & 15, z) == b
            assert (0 if c.data is None else int(c.data[x & 15, y & 15, z])) == d
        w.load([(x, y) for x in range(-1, 4) for y in range(-1, 4)])
        assert check_against_full(w, world_path, model, -1, -1, 4, 4) >= 9


def _merge(recs):
    first, last = {}, {}
    for r in recs:
        for v, b, a in zip(r.voxels, r.before, r.after):
            first.setdefault(v, b)
            last[v] = a
    vs = tuple(v for v in first if first[v] != last[v])
    return Record(vs, tuple(first[v] for v in vs), tuple(last[v] for v in vs))


def test_a_held_stroke_is_written_in_one_transaction(world_path):
    """Parts edited with write=False change the world at once but not the file (a
    second connection sees no commit); write() then commits them all in ONE
    transaction (COMMITs counted by SQLite's statement trace); a stroke left held
    is written when the world closes."""
    import sqlite3
    from voxel_addon.storage import WorldFile
    lamp, glass = REGISTRY.id("lamp_red"), REGISTRY.id("glass")
    with World.create(world_path, seed=SEED, loader=False) as w:
        edit(w, (8, 8, top(w, 8, 8) + 1, "stone"))       # light the area first
        w.settle()                                        # its write (the writer thread) done
        other = sqlite3.connect(world_path)
        version = lambda: other.execute("PRAGMA data_version").fetchone()[0]  # noqa: E731
        v0 = version()
        commits = []
        w.file.db.set_trace_callback(
            lambda sql: commits.append(sql) if sql.strip().upper().startswith("COMMIT") else None)
        cells = [(x, 3, top(w, x, 3) + 1) for x in range(-6, 22, 2)]  # across 3 chunks
        for x, y, z in cells:
            payloads, rec = edit(w, (x, y, z, lamp), write=False)
            assert payloads and rec.voxels == ((x, y, z),)
            assert w.get_block(x, y, z) == lamp
        assert w.held and commits == [] and version() == v0
        wf = WorldFile(world_path, readonly=True)
        assert all(wf.read_chunk((x >> 4, y >> 4)) is None or
                   wf.read_chunk((x >> 4, y >> 4))[0][x & 15, y & 15, z] != lamp
                   for x, y, z in cells)
        write(w)
        assert len(commits) == 1 and version() != v0 and not w.held
        for x, y, z in cells:
            assert wf.read_chunk((x >> 4, y >> 4))[0][x & 15, y & 15, z] == lamp
        wf.close()
        w.file.db.set_trace_callback(None)
        other.close()
        held = (30, 30, top(w, 30, 30) + 1)
        edit(w, (*held, glass), write=False)             # held when the world closes
    with World.open(world_path, loader=False) as w:
        assert w.get_block(*held) == glass
        assert all(w.get_block(*c) == lamp for c in cells)


def test_a_wide_stroke_is_relit_in_parts_and_written_at_once(world_path, tmp_path):
    """Voxels 512 blocks apart in one stroke (a script's list; the undo of a long
    drag): only the chunks around them are lit (one window over the box between
    would light ~1,200 chunks and take ~0.6 GB), one COMMIT, the same blocks and light
    as the voxels edited one by one in another world, and undo puts everything back."""
    import sqlite3
    stroke = [(0, 0, 100, "lamp_red"), (512, 7, 100, "stone"), (513, 7, 100, "glass"),
              (0, 0, 100, "lamp_blue"), (-3, 510, 101, "glass")]
    keys = {(x >> 4, y >> 4) for x, y, _, _ in stroke}
    one = tmp_path / "one.sqlite"
    with World.create(one, seed=1, generator="flat", loader=False, backend="numpy") as w1:
        for ch in stroke:
            edit(w1, ch)
        want = {k: (w1.chunk_at(*k).blocks.copy(), w1.chunk_at(*k).light.copy()) for k in keys}
    with World.create(world_path, seed=1, generator="flat", loader=False, backend="numpy") as w:
        commits = []
        w.file.db.set_trace_callback(
            lambda sql: commits.append(sql) if sql.strip().upper().startswith("COMMIT") else None)
        payloads, rec = edit(w, stroke)
        w.settle()
        w.file.db.set_trace_callback(None)
        assert len(w.chunks) < 100 and len(commits) == 1
        assert len({p.key for p in payloads}) == len(payloads) and keys <= {p.key for p in payloads}
        assert w.get_block(0, 0, 100) == REGISTRY.id("lamp_blue")
        for k, (b, light) in want.items():
            assert np.array_equal(w.chunk_at(*k).blocks, b)
            assert np.array_equal(w.chunk_at(*k).light, light), k
        db = sqlite3.connect(world_path)
        assert db.execute("SELECT COUNT(*) FROM edits").fetchone()[0] == 4
        db.close()
        assert sorted(rec.voxels) == sorted({tuple(ch[:3]) for ch in stroke})
        undo(w, rec)
        assert all(w.get_block(x, y, z) == 0 for x, y, z, _ in stroke)

def test_payloads_only_for_what_changed(world_path):
    stone, glass, lamp = (REGISTRY.id(n) for n in ("stone", "glass", "lamp_red"))
    with World.create(world_path, seed=SEED, loader=False) as w:
        payloads, _ = edit(w, (8, 8, 3, stone))  # lights the 3x3 around chunk (0, 0) first
        assert sorted(p.key for p in payloads) == [(i, j) for i in (-1, 0, 1) for j in (-1, 0, 1)]
        edit(w, [(24, 8, 3, stone), (24, 24, 3, stone)])   # ... and around (1, 0), (1, 1)
        # glass deep inside rock: its own chunk's mesh changes, no light anywhere
        old = w.chunk_at(0, 0).get(8, 8, 4)
        assert old != 0
        payloads, rec = edit(w, (8, 8, 4, glass))
        assert [p.key for p in payloads] == [(0, 0)]
        assert rec == (((8, 8, 4),), ((old, 0),), ((glass, 0),))
        # on the chunk border: both chunks' meshes
        payloads, _ = edit(w, (16, 8, 4, glass))
        assert sorted(p.key for p in payloads) == [(0, 0), (1, 0)]
        # setting what is there already changes nothing
        payloads, rec = edit(w, (16, 8, 4, glass))
        assert payloads == [] and rec.voxels == ()
        # a lamp in the open lights its neighbours: at most the 3x3 around it
        z = top(w, 20, 20) + 1
        payloads, rec = edit(w, (20, 20, z, lamp))
        keys = {p.key for p in payloads}
        assert (1, 1) in keys and len(keys) > 1
        assert keys <= {(1 + i, 1 + j) for i in (-1, 0, 1) for j in (-1, 0, 1)}
        before = {p.key: p.version for p in payloads}
        payloads = undo(w, rec)
        assert {p.key for p in payloads} == keys
        assert all(p.version > before[p.key] for p in payloads)


@pytest.mark.parametrize("bad, msg", [
    ((1, 1, 256, "stone"), "outside the world"),
    ((1, 1, -1, "stone"), "outside the world"),
    ((1, 1, 100, "unobtainium"), "unknown block name"),
    ((1, 1, 100, 9999), "unknown block id"),
    ((1, 1, 100, "stone", 70000), "data must be"),
    ((1 << 30, 1, 100, "stone"), "outside the world"),     # generation's int32 would wrap
    ((1, -(1 << 30) - 1, 100, "stone"), "outside the world"),
    ((1 << 63, 1, 100, "stone"), "outside the world"),     # past SQLite's integers
])
def test_bad_edits_refused_before_anything_changes(world_path, bad, msg):
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(0, 0)])
    digest = hashlib.sha256(world_path.read_bytes()).hexdigest()
    with World.open(world_path, loader=False) as w:
        with pytest.raises(VoxelError, match=msg) as e:
            edit(w, [(2, 2, 100, "glass"), (3, 3, 100, "glass"), bad])
        assert "\n" not in str(e.value)
        assert w.chunks == {} and w.file.edit_count() == 0
    assert hashlib.sha256(world_path.read_bytes()).hexdigest() == digest


def test_a_damaged_chunk_not_yet_read_is_refused_before_anything_changes(world_path):
    """The damage is found only when the stroke reads the chunk: a stroke (and a
    set_blocks reaching it from a good chunk) is refused on one line, nothing
    changed in memory or in the file."""
    import sqlite3
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(x, y) for x in range(-1, 3) for y in range(-1, 2)])
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=X'28b52ffd00deadbeef' WHERE cx=0 AND cy=0")
    db.commit()
    db.close()

    def rows():  # the stored chunks and edits (generated neighbours may be saved)
        db = sqlite3.connect(world_path)
        try:
            return ({(r[0], r[1]): r for r in db.execute("SELECT * FROM chunks")},
                    db.execute("SELECT * FROM edits").fetchall())
        finally:
            db.close()
    before = rows()
    with World.open(world_path, loader=False) as w:
        with pytest.raises(VoxelError, match=r"chunk \(0, 0\).* is damaged") as e:
            edit(w, (2, 2, 100, "glass"))
        assert "\n" not in str(e.value)
    with World.open(world_path, loader=False) as w:
        with pytest.raises(VoxelError, match=r"chunk \(0, 0\).* is damaged"):
            w.set_blocks([(-15, 1, 100), (1, 1, 100)], [REGISTRY.id("glass")] * 2)
        assert w.get_block(-15, 1, 100) == 0 and w.file.edit_count() == 0
    after = rows()
    assert {k: after[0][k] for k in before[0]} == before[0] and after[1] == before[1] == []

def test_closing_while_streaming_keeps_every_finished_edit(world_path):
    glass = REGISTRY.id("glass")
    done = []
    w = World.create(world_path, seed=SEED)
    s = Stream(w, 4, tile=4)
    s.set_view(0, 0, (1, 0))
    for i in range(12):
        x, y = 5 * i - 20, 3 * i - 15
        edit(w, (x, y, 200, glass, i))
        done.append((x, y, 200, i))
    assert s.running                                         # still streaming
    w.close()                                                 # stops the stream, saves
    assert not s.running
    with World.open(world_path, loader=False) as w:
        for x, y, z, d in done:
            c = w.chunk_at(x >> 4, y >> 4)
            assert c.get(x & 15, y & 15, z) == glass
            assert (0 if c.data is None else c.data[x & 15, y & 15, z]) == d


def test_stored_light_dropped_when_blocks_around_change(world_path):
    """World.set_block (no relight) drops the stored light of the 3x3 around it."""
    with World.create(world_path, seed=SEED, loader=False) as w:
        edit(w, (8, 8, 3, "stone"))                  # lights the 3x3 around (0, 0)
        w.flush()
    with World.open(world_path, loader=False) as w:
        assert w.chunk_at(1, 1).light is not None    # came from the file
        w.set_block(0, 0, 200, "glass")              # chunk (0, 0): 3x3 -1..1
        assert w.chunk_at(1, 1).light is None
    with World.open(world_path, loader=False) as w:
        assert all(w.chunk_at(x, y).light is None for x in (-1, 0, 1) for y in (-1, 0, 1))


def test_no_payload_when_nothing_visible_changes(world_path):
    with World.create(world_path, seed=SEED, loader=False) as w:
        edit(w, (8, 8, 3, "stone"))                    # light the 3x3 first
        c = w.chunk_at(0, 0)
        assert c.get(8, 8, 2) != 0 and REGISTRY.light_opaque[c.get(8, 8, 2)]
        payloads, rec = edit(w, (8, 8, 2, c.get(8, 8, 2), 5))   # only its data value
        assert payloads == [] and rec.after == ((c.get(8, 8, 2), 5),)
        assert w.chunk_at(0, 0).data[8, 8, 2] == 5


def test_opening_a_deep_shaft_relights_far_below(world_path):
    """Daylight through an opened cap falls 40 voxels down a shaft: the edit's light
    window (only the layers an update can touch) must reach that far."""
    model: dict = {}
    stone = REGISTRY.id("stone")
    with World.create(world_path, seed=SEED, loader=False) as w:
        x, y = 20, 24
        z = top(w, x, y)
        shaft = [(x, y, zz, 0) for zz in range(z - 40, z + 1)]
        edit(w, shaft + [(x, y, z + 1, stone)])  # a capped shaft: dark inside
        for x_, y_, z_, b in shaft + [(x, y, z + 1, stone)]:
            model[(x_, y_, z_)] = (b, 0)
        for b in (0, stone, 0):  # open, close, open the cap alone
            edit(w, (x, y, z + 1, b))
            model[(x, y, z + 1)] = (b, 0)
            assert check_against_full(w, world_path, model, 0, 0, 3, 3) >= 9


def test_relight_window_keeps_air_above_the_chunks(world_path):
    """The relight's blocks window copies no air above its chunks' highest non-air
    section (world/window.py): its buffer must hold air there, also after a stroke
    wrote a voxel up in the air into it (the next stroke's window, elsewhere, reads
    that buffer again)."""
    model: dict = {}
    stone, glass = REGISTRY.id("stone"), REGISTRY.id("glass")
    with World.create(world_path, seed=SEED, loader=False) as w:
        build.light_and_mesh(w, 0, 0, 3, 3)   # a one-voxel stroke lights only its part
        # the first two windows share no chunk: the second reads the buffer where
        # the first wrote its stone
        for x, y, b, dz in ((6, 7, stone, 120), (40, 41, 0, 0), (24, 40, glass, 1),
                            (9, 9, 0, 0)):
            z = top(w, x, y) + dz
            edit(w, (x, y, z, b))
            model[(x, y, z)] = (b, 0)
            n = check_against_full(w, world_path, model, 0, 0, 3, 3)
        assert n >= 8


def test_one_voxel_strokes_relit_in_part_then_whole(world_path, monkeypatch):
    """A one-voxel stroke is relit first on the columns near it (edit._part) and on
    the whole window where its light reaches further: both equal the full solve
    (a narrow part here, so that some strokes need the whole window)."""
    from voxel_addon.world import edit as E
    monkeypatch.setattr(E, "PART", 3)
    calls = {True: 0, False: 0}
    relight = E._relight

    def counted(*a, **k):
        got = relight(*a, **k)
        if a[-1] is True:            # a part
            calls[got is None] += 1
        return got
    monkeypatch.setattr(E, "_relight", counted)
    rng = np.random.default_rng(4)
    model: dict = {}
    ids = [0, REGISTRY.id("stone"), REGISTRY.id("leaves"), REGISTRY.id("water"),
           REGISTRY.id("glass")]
    with World.create(world_path, seed=SEED, loader=False) as w:
        for i in range(16):
            x, y = (int(v) for v in rng.integers(4, 44, 2))
            z = top(w, x, y) + int(rng.integers(-1, 2))
            b = ids[i % len(ids)]
            edit(w, (x, y, z, b))
            model[(x, y, z)] = (b, 0)
        assert check_against_full(w, world_path, model, 0, 0, 3, 3) >= 9
    assert calls[False] >= 3 and calls[True] >= 1, calls


def test_a_voxel_at_the_lit_edge_lights_only_what_its_part_reads(world_path):
    """Next to chunks not lit yet (the edge of the streamed area) a one-voxel stroke
    relit on its part (edit._needed) lights only the chunks that part and its remesh
    read; where its light leaves the part, the stroke is backed out, the 3x3 lit and
    the stroke applied again: every lit chunk equals the full solve either way."""
    stone = REGISTRY.id("stone")
    model: dict = {}
    with World.create(world_path, seed=SEED, loader=False) as w:
        w.load([(x, y) for y in range(-1, 4) for x in range(-1, 4)])
        x, y = 24, 24                                   # chunk (1, 1), its middle
        z = top(w, x, y)
        # a capped shaft down into a dark room, not relit
        dug = [(x, y, zz, 0) for zz in range(z - 10, z + 1)] + [(x, y, z + 1, stone)] + [
            (i, j, zz, 0) for i in range(18, 31) for j in range(18, 31)
            for zz in range(z - 14, z - 10)]
        for vx, vy, vz, b in dug:
            w.set_block(vx, vy, vz, b)
            model[(vx, vy, vz)] = (b, 0)
        build.light_and_mesh(w, 1, 1, 2, 2)             # only chunk (1, 1) lit
        zs = top(w, 25, 26)
        edit(w, (25, 26, zs + 1, stone))                # stays near: nothing more lit
        model[(25, 26, zs + 1)] = (stone, 0)
        assert [k for k, c in w.chunks.items() if c.has_light] == [(1, 1)]
        assert check_against_full(w, world_path, model, 0, 0, 3, 3) == 1
        payloads, rec = edit(w, (x, y, z + 1, 0))       # daylight fills the room
        model[(x, y, z + 1)] = (0, 0)
        assert rec == Record(((x, y, z + 1),), ((stone, 0),), ((0, 0),))
        assert (1, 1) in {p.key for p in payloads}
        assert all(w.chunks[(i, j)].has_light for i in range(3) for j in range(3))
        assert check_against_full(w, world_path, model, 0, 0, 3, 3) == 9
    with World.open(world_path) as w:                   # written once, as it is now
        assert w.chunk_at(1, 1).get(8, 8, z + 1) == 0


def test_coloured_voxels_mesh_by_colour(world_path):
    """The `color` block's faces follow its data through streaming (build) and edits:
    two neighbours of different colours are two quads, the same colour one."""
    color = REGISTRY.id("color")
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.set_block(3, 3, 100, color, 5)
        w.set_block(4, 3, 100, color, 6)
        from voxel_addon.world import build
        build.light_and_mesh(w, 0, 0, 1, 1)
        m = w.chunk_at(0, 0).mesh
        top = m.quads[(m.quads["block"] == color) & (m.quads["face"] == 5)]
        assert sorted(top["color"].tolist()) == [5, 6] and m.colors is not None
        edit(w, (4, 3, 100, color, 5))                     # same colour now: one quad
        m = w.chunk_at(0, 0).mesh
        top = m.quads[(m.quads["block"] == color) & (m.quads["face"] == 5)]
        assert top["color"].tolist() == [5] and top["w"].tolist() == [2]


def test_patched_remesh_reads_only_what_it_gathers(world_path):
    """Small strokes remesh by meshing.patch from a window of which edit.py gathers
    only the slices through the changed voxels: with the rest of that window made
    garbage before every stroke, the meshes still equal a full recompute."""
    from voxel_addon.world import edit as E
    rng = np.random.default_rng(5)
    model: dict = {}
    with World.create(world_path, seed=SEED, loader=False) as w:
        for _ in range(14):
            # near chunk borders (x, y = 15/16) half the time: the ring and neighbours
            cx = int(rng.choice([15, 16, 17, 8])) + 16 * int(rng.integers(0, 2))
            cy = int(rng.choice([15, 16, 9])) + 16 * int(rng.integers(0, 2))
            stroke = []
            for _ in range(int(rng.integers(1, 4))):
                x, y = cx + int(rng.integers(-1, 2)), cy + int(rng.integers(-1, 2))
                stroke.append((x, y, top(w, x, y) + int(rng.integers(-1, 2)),
                               int(rng.choice(PALETTE)), 0))
            for buf in getattr(E._scratch, "exact", {}).values():
                buf[...] = rng.choice(PALETTE, size=buf.shape)
            edit(w, stroke)
            for x, y, z, b, d in stroke:
                model[(x, y, z)] = (b, d)
        assert check_against_full(w, world_path, model, 0, 0, 3, 3) >= 9


def test_relit_light_is_a_new_array_from_packed_and_hot_chunks(world_path, monkeypatch):
    """An edit writes relit light into a new array (Chunk.light_copy): a payload
    handed out before keeps its light, whether the chunk's light was hot or packed,
    and the result equals a full recompute."""
    from voxel_addon.core import chunk as C
    monkeypatch.setattr(C, "HOT_S", -1.0)   # compact() packs whatever was read
    lamp = REGISTRY.id("lamp_red")
    model: dict = {}
    with World.create(world_path, seed=SEED, loader=False) as w:
        for i, (x, y) in enumerate([(15, 16), (16, 15), (8, 8), (15, 16)]):
            z = top(w, x, y) + 1
            payloads, _ = edit(w, (x, y, z, lamp))
            model[(x, y, z)] = (lamp, 0)
            held = {p.key: (p.light, p.light.copy()) for p in payloads}
            if i % 2:    # every other stroke on packed light
                with w.locked():
                    for c in w.chunks.values():
                        c.compact()
            z = top(w, x + 1, y) + 1
            edit(w, (x + 1, y, z, lamp))
            model[(x + 1, y, z)] = (lamp, 0)
            for a, was in held.values():
                assert np.array_equal(a, was)
        assert check_against_full(w, world_path, model, 0, 0, 2, 2) >= 4
