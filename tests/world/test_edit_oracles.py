"""Edits, bulk sets, undo records and eviction checked against plain oracles: the same
changes made one voxel at a time, snapshots taken before and after, a re-read of the
file. Small flat worlds, no loader thread."""
from __future__ import annotations

import numpy as np

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.world import World, build
from voxel_addon.world.edit import edit, redo, undo

COLOR, GLASS, STONE = REGISTRY.id("color"), REGISTRY.id("glass"), REGISTRY.id("stone")


def snapshot(w, cx0=-1, cy0=-1, cx1=2, cy1=2):
    """Blocks and small data of chunks [cx0, cx1) x [cy0, cy1) (data 0 where none)."""
    b = w.region_blocks(cx0, cy0, cx1, cy1)
    d = np.zeros_like(b)
    for cy in range(cy0, cy1):
        for cx in range(cx0, cx1):
            c = w.chunk_at(cx, cy)
            if c.data is not None:
                d[16 * (cx - cx0):16 * (cx - cx0 + 1), 16 * (cy - cy0):16 * (cy - cy0 + 1)] = c.data
    return b, d


def test_recolouring_a_voxel_is_a_new_mesh(world_path):
    """Only the data of a `color` voxel changes: the packed vertices stay the same, its
    colour does not, so the edit must hand out the new mesh (the live view draws it)."""
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.set_block(3, 3, 100, COLOR, 5)
        build.light_and_mesh(w, -1, -1, 2, 2)
        assert 5 in w.chunk_at(0, 0).mesh.colors
        payloads, rec = edit(w, (3, 3, 100, COLOR, 6))
        assert [p.key for p in payloads] == [(0, 0)]
        assert 6 in payloads[0].mesh.colors and 5 not in payloads[0].mesh.colors
        assert rec.before == ((COLOR, 5),) and rec.after == ((COLOR, 6),)
        p = undo(w, rec)
        assert 5 in p[0].mesh.colors and 6 not in p[0].mesh.colors


def test_undo_redo_restore_snapshots(world_path):
    """A stroke touching some voxels twice (block and data), across chunk borders:
    undo gives back the blocks and data from before, redo those from after, and the
    record holds each voxel once (first before, last after)."""
    rng = np.random.default_rng(3)
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        edit(w, (0, 0, 100, STONE))             # lights the 3x3 first
        before = snapshot(w)
        pts = [(int(x), int(y), int(z)) for x, y, z in
               zip(rng.integers(-6, 6, 25), rng.integers(-6, 6, 25), rng.integers(60, 70, 25))]
        ids = [GLASS, STONE, COLOR, 0]
        stroke = [(*p, int(rng.choice(ids)), int(rng.integers(0, 4))) for p in pts + pts[:8]]
        stroke = [(x, y, z, b, d if b == COLOR else 0) for x, y, z, b, d in stroke]
        _, rec = edit(w, stroke)
        after = snapshot(w)
        assert len(set(rec.voxels)) == len(rec.voxels)
        for v, b, a in zip(rec.voxels, rec.before, rec.after):
            i = (v[0] + 16, v[1] + 16, v[2])
            assert (int(before[0][i]), int(before[1][i])) == b
            assert (int(after[0][i]), int(after[1][i])) == a
        undo(w, rec)
        assert all(np.array_equal(s, t) for s, t in zip(snapshot(w), before))
        redo(w, rec)
        assert all(np.array_equal(s, t) for s, t in zip(snapshot(w), after))
        w.flush()
    with World.open(world_path, loader=False) as w:   # and the file agrees
        assert all(np.array_equal(s, t) for s, t in zip(snapshot(w), after))


def test_set_blocks_equals_set_block_one_by_one(tmp_path):
    """The bulk form against the single one, on two worlds: same blocks, data,
    pending edits and stored light dropped the same way; both survive eviction
    and a re-read of the file."""
    rng = np.random.default_rng(5)
    n = 200
    xyz = np.stack([rng.integers(-20, 20, n), rng.integers(-20, 20, n),
                    rng.integers(50, 120, n)], 1)
    xyz[-20:] = xyz[:20]                    # some voxels set twice: the last one wins
    ids = rng.choice([COLOR, GLASS, STONE, 0], n)
    data = np.where(ids == COLOR, rng.integers(0, 9, n), 0)
    a, b = tmp_path / "a.sqlite", tmp_path / "b.sqlite"
    with World.create(a, seed=1, generator="flat", loader=False) as wa, \
            World.create(b, seed=1, generator="flat", loader=False) as wb:
        for w in (wa, wb):
            build.light_and_mesh(w, -3, -3, 3, 3)
        wa.set_blocks(xyz, ids, data)
        for (x, y, z), i, d in zip(xyz.tolist(), ids.tolist(), data.tolist()):
            wb.set_block(x, y, z, i, d)
        assert sorted(wa.unsaved_edits()) == sorted(wb.unsaved_edits())
        for w in (wa, wb):
            assert all(w.chunk_at(cx, cy).light is None for cx in range(-3, 3) for cy in range(-3, 3))
        sa, sb = snapshot(wa, -3, -3, 3, 3), snapshot(wb, -3, -3, 3, 3)
        assert all(np.array_equal(s, t) for s, t in zip(sa, sb))
        for w in (wa, wb):
            w.unload_all()                     # evicted: saved, then read back
        assert all(np.array_equal(s, t) for s, t in zip(snapshot(wa, -3, -3, 3, 3), sa))
    with World.open(a, loader=False) as wa, World.open(b, loader=False) as wb:
        assert all(np.array_equal(s, t) for s, t in zip(snapshot(wa, -3, -3, 3, 3), sa))
        assert sorted(wa.file.edits_in((0, 0))) == sorted(wb.file.edits_in((0, 0)))
        wa.recreate(keep_edits=True)           # generated chunks forgotten, edits kept
        assert all(np.array_equal(s, t) for s, t in zip(snapshot(wa, -3, -3, 3, 3), sa))
