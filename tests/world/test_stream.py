"""Streaming with the real worker thread, real SQLite, real OpenCL (and NumPy)."""
from __future__ import annotations

import time

import numpy as np
import pytest

from voxel_addon import meshing
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.render.source import world_area
from voxel_addon.world import Payload, Stream, World

SEED = 7


def collect(stream, timeout=120.0):
    """Drain until every wanted chunk came out; {key: Payload}."""
    assert stream.wait_ready(timeout), stream.counts
    got = {}
    for _ in range(10000):
        ready, gone = stream.drain(0.004)
        for k in gone:
            got.pop(k, None)
        got.update((p.key, p) for p in ready)
        w, r, d = stream.counts
        if d >= w and not ready:
            break
    return got


def same_mesh(a, b):
    return np.array_equal(a.vertices, b.vertices) and np.array_equal(a.ranges, b.ranges)


def one_shot(path, x, y, distance):
    """The reference: render.source.world_area (blocks + exact light) and one
    meshing.build_chunks call over the whole area, on a fresh World."""
    with World.open(path, loader=False) as w:
        area = world_area(w, x, y, distance, light_radius=distance)
        meshes = meshing.build_chunks(area.blocks, (area.cx0, area.cy0), backend="numpy")
    return area, meshes


def check_equal(got, area, meshes):
    s = 16
    assert set(got) == set(meshes)
    for k, p in got.items():
        assert isinstance(p, Payload) and p.key == k
        i, j = (k[0] - area.light_at[0]) * s, (k[1] - area.light_at[1]) * s
        assert p.light.shape == (16, 16, 256) and p.light.dtype == np.uint16
        assert np.array_equal(p.light, area.light[i:i + s, j:j + s]), k
        assert same_mesh(p.mesh, meshes[k]), k


@pytest.mark.parametrize("backend", ["opencl", "numpy"])
def test_stream_equals_one_shot(world_path, backend, request):
    if backend == "opencl":
        request.getfixturevalue("cl_device")
    with World.create(world_path, seed=SEED) as w:
        # a small tile so the area is done in several batches, in some order
        with Stream(w, 3, tile=4, backends=(backend, backend)) as s:
            s.set_view(40.0, -20.0, direction=(1, 1, 0))
            got = collect(s)
            assert s.counts == (49, 49, 49)
    area, meshes = one_shot(world_path, 40.0, -20.0, 3)
    check_equal(got, area, meshes)


def test_moving_view_drops_reloads_and_keeps_edits(world_path):
    from voxel_addon.world.edit import edit
    glass = REGISTRY.id("glass")
    with World.create(world_path, seed=SEED) as w:
        with Stream(w, 2, tile=4, margin=0) as s:
            s.set_view(8, 8)
            collect(s)
            top = int(np.flatnonzero(w.chunk_at(0, 0).blocks[3, 4])[-1])
            payloads, _ = edit(w, (3, 4, top + 1, "glass"))
            assert (0, 0) in {p.key for p in payloads}
            s.set_view(8 + 16 * 12, 8)           # far away: old chunks gone, unloaded
            got = collect(s)
            assert all(k[0] >= 10 for k in got)
            assert (0, 0) not in w.chunks        # unloaded (and saved)
            s.set_view(8, 8)                      # back: reloaded from the file
            got = collect(s)
            assert set(got) == {(x, y) for x in range(-2, 3) for y in range(-2, 3)}
            assert w.chunk_at(0, 0).get(3, 4, top + 1) == glass
    area, meshes = one_shot(world_path, 8, 8, 2)
    assert area.blocks[1 + 32 + 3, 1 + 32 + 4, top + 1] == glass  # area from chunk -2, ring
    check_equal(got, area, meshes)


def test_drain_respects_budget_and_counts(world_path):
    with World.create(world_path, seed=SEED, generator="flat") as w:
        with Stream(w, 1) as s:
            assert s.counts[1:] == (0, 0)
            s.set_view(0, 0)
            assert s.wait_ready(60)
            ready, gone = s.drain(0.0)            # a zero budget still hands out one
            assert len(ready) == 1 and gone == []
            assert s.counts == (9, 9, 1)
            rest, _ = s.drain(1.0)
            assert len(rest) == 8 and s.counts == (9, 9, 9)
            s.set_distance(0)
            _, gone = s.drain(0.0)
            assert len(gone) == 8 and (0, 0) not in gone and s.counts == (1, 1, 1)
            s.set_distance(1)
            assert s.wait_ready(60) and len(s.drain(1.0)[0]) == 8
            s.set_view(16 * 10, 0)
            _, gone = s.drain(0.0)
            assert sorted(gone) == sorted((x, y) for x in (-1, 0, 1) for y in (-1, 0, 1))


def test_corrupt_chunk_shown_missing_reported_once(world_path, caplog):
    import sqlite3
    with World.create(world_path, seed=1, generator="flat", loader=False) as w:
        w.generate_area([(x, y) for x in range(-2, 3) for y in range(-2, 3)])
    db = sqlite3.connect(world_path)
    db.execute("UPDATE chunks SET blocks=X'deadbeef' WHERE cx=1 AND cy=0")
    db.commit()
    db.close()
    with World.open(world_path) as w:
        with Stream(w, 1) as s:
            s.set_view(0, 0)
            got = collect(s)
            assert (1, 0) not in got and len(got) == 8
            assert s.counts == (8, 8, 8)
            w.region_blocks(0, 0, 3, 1)          # asked again: not reported again
        assert list(w.corrupt) == [(1, 0)]
    assert sum("(1, 0)" in r.getMessage() for r in caplog.records) == 1
    db = sqlite3.connect(world_path)
    assert db.execute("SELECT blocks FROM chunks WHERE cx=1 AND cy=0").fetchone()[0] == \
        b"\xde\xad\xbe\xef"


def test_edits_while_streaming_end_equal_one_shot(world_path):
    """Edits race the workers (same chunks, any order): what the consumer ends up
    with (drained payloads, newest version per chunk) equals the one-shot path."""
    from voxel_addon.world.edit import edit
    rng = np.random.default_rng(5)
    got = {}
    with World.create(world_path, seed=SEED) as w:
        with Stream(w, 3, tile=4) as s:
            s.set_view(8, 8, direction=(0, 1))
            for i in range(25):
                x, y = int(rng.integers(-40, 56)), int(rng.integers(-40, 56))
                z = int(rng.integers(60, 110))
                b = ["air", "glass", "lamp_red", "stone"][i % 4]
                payloads, _ = edit(w, [(x, y, z, b), (x + 1, y, z, b)])
                got.update((p.key, p) for p in payloads)   # as a consumer would
                ready, _ = s.drain(0.004)
                got.update((p.key, p) for p in ready if p.version >= got.get(p.key, p).version)
            for k, p in collect(s).items():
                if p.version >= got.get(k, p).version:
                    got[k] = p
    area, meshes = one_shot(world_path, 8, 8, 3)
    check_equal({k: p for k, p in got.items() if k in meshes}, area, meshes)


@pytest.mark.parametrize("t", [1, 2, 4, 8])
def test_tiles_cover_the_range_without_thin_strips(t):
    """Batches: contiguous tiles that cover the range once, none wider than 2 tiles,
    and a range end never leaves a strip under half a tile next to a full one."""
    from voxel_addon.world.stream import _tiling
    for lo in range(-20, -8):
        for hi in range(lo, lo + 40):
            k = np.arange(lo, hi + 1)
            ids = _tiling(lo, hi, t)(k)
            assert (np.diff(ids) >= 0).all()  # contiguous, in order
            _, width = np.unique(ids, return_counts=True)
            assert width.max() <= 2 * t
            if len(width) > 1:
                assert 2 * width.min() >= t, (lo, hi, width)


def test_stored_chunks_reach_a_live_stream(world_path):
    """World.store_chunks (an import into the world a view shows) replaces the active
    chunk and the stream hands out its new mesh without being told."""
    from voxel_addon.core import chunk as C
    from voxel_addon.core.blocks import REGISTRY
    with World.create(world_path, seed=SEED, generator="flat") as w:
        with Stream(w, 1) as s:
            s.set_view(8, 8)
            assert s.wait_ready(60)
            old = {p.key: p for p in s.drain(1.0)[0]}
            assert (0, 0) in old
            tower = C.empty()
            tower[:, :, :3] = REGISTRY.id("stone")
            tower[4:8, 4:8, 3:100] = REGISTRY.id("bricks")
            w.store_chunks([((0, 0), tower, None)])
            assert w.chunk_at(0, 0).get(5, 5, 50) == REGISTRY.id("bricks")
            end = time.monotonic() + 60
            new = None
            while new is None and time.monotonic() < end:
                new = next((p for p in s.drain(1.0)[0] if p.key == (0, 0)), None)
                time.sleep(0.05)
            assert new is not None and new.version > old[(0, 0)].version
            assert (new.mesh.quads["block"] == REGISTRY.id("bricks")).any()
    with World.open(world_path, loader=False) as w:
        assert w.get_block(5, 5, 50) == REGISTRY.id("bricks")


def test_stream_during_the_opencl_warm_up_equals_one_shot(world_path, cl_device, monkeypatch):
    """build.warm (the live view's first Show): NumPy while the kernels build, OpenCL
    after; the payloads are those of the one-shot path all the same."""
    from voxel_addon import opencl
    from voxel_addon.world import build
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))  # never warmed
    with World.create(world_path, seed=SEED) as w:
        assert build.warm(w)
        assert build.backends() == ("numpy", "numpy") and w.generator.backend_used == "numpy"
        with Stream(w, 3, tile=4) as s:
            s.set_view(40.0, -20.0, direction=(1, 1, 0))
            got = collect(s)
            assert s.first_backends == ("numpy", "numpy") and s.first_at is not None
        opencl._warm["thread"].join(120)
        assert opencl.warm_state()["error"] is None
        assert build.backends() == ("numpy", "opencl") and w.generator.backend_used == "opencl"
    area, meshes = one_shot(world_path, 40.0, -20.0, 3)
    check_equal(got, area, meshes)


def test_warm_up_once_per_generator(world_path, tmp_path, cl_device, monkeypatch):
    from voxel_addon import opencl
    from voxel_addon.world import build
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))  # never warmed
    with World.create(world_path, seed=SEED, generator="flat") as a, \
            World.create(tmp_path / "b.sqlite", seed=SEED, generator="flat") as b:
        assert build.warm(a) and not build.warm(b)     # one at a time
        opencl._warm["thread"].join(60)
        assert not build.warm(a) and build.warm(b)     # each world's generator once
        opencl._warm["thread"].join(60)
        assert opencl.warm_state()["error"] is None


def test_reload_meshes_with_a_one_voxel_ring_equal_one_shot(world_path, monkeypatch):
    """A reopened file's chunks come with their light: the stream's batches then only
    mesh, from a snapshot with one voxel of the ring (build.snapshot's pad). Coloured
    blocks (small data) on both sides of chunk and batch borders: the ring's blocks
    and data must land on the right voxels; the result is the one-shot path's."""
    from voxel_addon import light
    from voxel_addon.world.edit import edit
    with World.create(world_path, seed=SEED) as w:
        with Stream(w, 3, tile=2) as s:
            s.set_view(8, 8)
            collect(s)
            cols = []
            for i, x in enumerate((-17, -16, -1, 0, 15, 16, 31, 32)):
                y = (3 * i) % 40 - 20
                top = int(np.flatnonzero(w.chunk_at(x >> 4, y >> 4).blocks[x & 15, y & 15])[-1])
                cols += [(x, y, top + 1, "color", 1000 + 77 * i), (y, x, top + 2, "stone")]
            edit(w, cols)
    solves = []
    real = light.region_light
    monkeypatch.setattr(light, "region_light", lambda *a, **kw: solves.append(1) or real(*a, **kw))
    with World.open(world_path) as w:
        with Stream(w, 2, tile=2) as s:
            s.set_view(8, 8)
            got = collect(s)
    assert not solves  # every batch only meshed (the light came from the file)
    area, meshes = one_shot(world_path, 8, 8, 2)
    check_equal(got, area, meshes)


def test_past_the_first_chunks_the_stream_waits_for_every_kernel(world_path, monkeypatch):
    """While a warm-up runs (here one that has built the generator's kernels and not
    meshing's), the stream makes only the chunks next to the view (stream.FIRST: the
    first picture, NumPy); the rest once every kernel is built (issue 28: OpenCL
    generation with NumPy meshing cost more CPU and a later whole view). The payloads
    are the one-shot path's."""
    import threading
    from voxel_addon import opencl
    from voxel_addon.world import stream
    hold = threading.Event()
    t = threading.Thread(target=hold.wait, daemon=True)
    t.start()
    monkeypatch.setattr(opencl, "_warm", {**dict.fromkeys(opencl._warm), "thread": t,
                                          "ready": {"generation": time.monotonic()}})
    try:
        with World.create(world_path, seed=SEED) as w:
            with Stream(w, 3) as s:
                s.set_view(8.0, 8.0)
                got, end = {}, time.monotonic() + 3.0
                while time.monotonic() < end:
                    got.update((p.key, p) for p in s.drain(0.004)[0])
                    time.sleep(0.01)
                assert got and max(max(abs(x), abs(y)) for x, y in got) < stream.FIRST + 1
                hold.set()
                t.join()
                got.update(collect(s))
    finally:
        hold.set()
    assert len(got) == 49
    area, meshes = one_shot(world_path, 8.0, 8.0, 3)
    check_equal(got, area, meshes)


def test_stored_chunks_stream_once_meshing_is_warm(world_path, cl_device, monkeypatch):
    """build.warm meshes a stored view's chunks before building the generator's kernels
    (opencl.ready("meshing")): the stream then goes past its first chunks for tiles
    the file has, while a tile with chunks to generate still waits for the
    generator's kernels (no NumPy generation beside their build; issue 28)."""
    import threading
    from voxel_addon import opencl
    from voxel_addon.core import chunk as C
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))  # never warmed
    stored = {(x, y) for x in range(-4, 4) for y in range(-4, 4)}  # whole tiles of 4
    blocks = np.zeros(C.SHAPE, np.uint16)
    blocks[:, :, :20] = REGISTRY.id("stone")
    near = {(x, y): -2 for x in range(-1, 2) for y in range(-1, 2)}  # done (FIRST)
    done = {**near, **{k: -2 for k in stored}}
    gate, went = threading.Event(), threading.Event()

    def job():
        opencl.ready("meshing")
        went.set()
        gate.wait(30)
    with World.create(world_path, seed=SEED, generator="flat") as w:
        w.file.write_chunks([(k, blocks, None) for k in sorted(stored)])
        with Stream(w, 6) as s:  # no view: its worker waits
            assert opencl.warm(job) and went.wait(30)
            try:
                got = s._next(0, 0, None, near, set())
                assert got and set(got) <= stored
                assert s._next(0, 0, None, done, set()) is None
            finally:
                gate.set()
                opencl._warm["thread"].join(30)
            got = s._next(0, 0, None, done, set())
            assert got and not set(got) & stored
