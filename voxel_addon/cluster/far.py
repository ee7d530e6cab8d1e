"""`far`: the far-terrain tiles of a ring built and kept in the world file, so a
vista opens at once in Blender. Workers run far.tiles.build, the very function the
Blender builder runs, on a stand-in store that holds what the writer read from the
file for that tile (which stored chunks it samples, their column summaries, the
edits over it), so a worker needs no file and the tiles are the builder's bit for
bit. The writer commits tiles in batches; tiles already in the file are kept, so
a run killed and started again builds only what is missing."""
from __future__ import annotations

import time

import numpy as np

from . import knob

COMMIT = 16    # tiles per transaction (or what arrived within COMMIT_S)
COMMIT_S = 1.0


class _Store:
    """The part of storage.far.FarStore that far.tiles.build reads, from a task."""

    def __init__(self, have, cols, edits):
        self.have, self.cols, self.e = have, cols, edits

    def chunks_in(self, cx0, cy0, cx1, cy1) -> set:
        return self.have

    def columns(self, key):
        return self.cols.get(tuple(key))

    def put_columns(self, items) -> None:
        pass  # the writer made and stored every summary the task needs

    def edits(self, x0, y0, x1, y1) -> np.ndarray:
        return self.e


def build(item, shared):
    """Worker: the samples of one tile ((key, have, cols, edits) from the writer)."""
    from ..far import tiles
    from .generate import generator
    key, have, cols, edits = item
    a, _ = tiles.build(key, _Store(have, cols, edits), generator(shared["generator"]),
                       lambda k: None)
    return a


def _inputs(key, store, file, made: dict):
    """What tiles.build reads from the store for tile `key`: the stored chunks in its
    sample box, the summaries of those it samples (made here and stored when the
    file has none, as the builder does), the edits over its cells."""
    from ..far import grid, tiles
    X, Y = grid.columns(key)
    ck = np.stack([X >> 4, Y >> 4], -1).reshape(-1, 2)
    have = store.chunks_in(int(ck[:, 0].min()), int(ck[:, 1].min()),
                           int(ck[:, 0].max()), int(ck[:, 1].max()))
    cols, read = {}, []
    for k in {tuple(v) for v in ck.tolist()} & have:
        col = made.get(k) or store.columns(k)
        if col is None:
            read.append(k)
        else:
            cols[k] = col
    for k, got in file.read_many(read):  # each array dropped once summed up
        if isinstance(got, tuple):  # damaged or gone: the builder skips it too
            cols[k] = made[k] = tiles.summary(got[0])
    s = grid.spacing(key[0])
    x0, y0 = grid.origin(key)
    bx0, by0 = x0 - s, y0 - s
    edits = store.edits(bx0, by0, bx0 + grid.N * s, by0 + grid.N * s)
    return have, cols, edits


def run(world, pool, x, y, far, near=0, backend=None, progress=None) -> tuple[int, int, int]:
    """Build and store the missing tiles of the ring; (tiles wanted, already stored,
    built now)."""
    from ..core.errors import VoxelError
    from ..far import grid
    from ..far.builder import signature
    from ..storage.far import FarStore
    world.writable()
    if not 0 <= far <= grid.FAR_MAX:
        raise VoxelError(f"--far must be 0..{grid.FAR_MAX} chunks (got {far})")
    f, gen = world.file, world.generator
    store = FarStore(f, signature(gen))
    while store.take_dirty(lambda chunks: {k for c in chunks for k in grid.touching(*c)}):
        pass  # tiles over chunks written since they were made are stale: dropped
    keys = [k for k, _ in grid.select(x, y, far, near)]
    stored = set(store.tile_keys())
    todo = [k for k in keys if k not in stored]
    made: dict = {}

    def items():
        for k in todo:
            yield (k, *_inputs(k, store, f, made))
            if len(made) >= 256:
                store.put_columns(list(made.items()))
                made.clear()

    from .generate import spec
    shared = {"generator": spec(gen, backend)}
    buf, done, t = [], 0, time.monotonic()
    every = knob("COMMIT", COMMIT)

    def commit():
        nonlocal buf, done, t
        if made:
            store.put_columns(list(made.items()))
            made.clear()
        if buf:
            store.put_tiles(buf)
            done += len(buf)
        buf, t = [], time.monotonic()
        if progress:
            progress(done, len(todo))

    try:
        for item, a in pool.map(build, items(), shared=shared):
            buf.append((item[0], a))
            if len(buf) >= every or time.monotonic() - t > COMMIT_S:
                commit()
    finally:
        commit()
    return len(keys), len(keys) - len(todo), done
