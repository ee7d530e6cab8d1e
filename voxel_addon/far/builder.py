"""The far ring around a moving view, made in the background (like world.Stream).

A worker thread keeps the meshes of the tiles `grid.select` wants for the view: a
tile's samples come from the world file's `far_tiles` when it has them (a second
view is instant), else they are built (far/tiles.py) and stored; chunks written
since (the file's `far_dirty`, filled by triggers) make the tiles over them stale:
they are built again while the old mesh stays drawn. Nearest tile first.

The consumer calls `drain(budget_s)` from its own thread (it only pops a queue) and
gets new meshes and the keys to stop drawing. A tile that left the selection is
reported gone only once every wanted tile over its area was handed out, so a level
switch never opens a hole: the new tiles arrive first, the old go in the same drain.
"""
from __future__ import annotations

import json
import threading
import time
from collections import deque

from ..core import ending
from ..core.errors import VoxelError
from ..storage import CorruptChunk
from ..storage.far import FarStore
from . import grid, mesh, tiles

FORMAT = 1  # of the far data: another value rebuilds what a file holds
# tiles built per step: the generator's 2D passes on NumPy take ~40 % less CPU per
# column on 16 tiles' columns at once than tile by tile (issue 28: fewer Python
# steps, and execute.SPLIT); the nearest tile waits for 15 more (~0.1 s)
BATCH = 16


def signature(generator) -> str:
    """What far data depends on besides the chunks: another one clears it."""
    return json.dumps({"format": FORMAT, "tile": grid.TILE, "generator": generator.name,
                       "version": generator.version, "seed": generator.seed,
                       "params": generator.params}, sort_keys=True)


def _overlap(a, b) -> bool:
    ra, rb = grid.rect(a), grid.rect(b)
    return ra[0] < rb[2] and rb[0] < ra[2] and ra[1] < rb[3] and rb[1] < ra[3]


class Builder:
    def __init__(self, file, generator, lock=None):
        """lock: held around the generator's use (a World's, whose loader thread
        generates with the same generator: OpenCL queues are not re-entrant)."""
        self.file = file
        self.generator = generator
        self._gen_lock = lock
        self.store = FarStore(file, signature(generator))
        self.error: BaseException | None = None
        self.stats = {"built": 0, "loaded": 0, "from_chunks": 0, "build_s": 0.0}
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._view = None          # (x, y, far, near, detail)
        self._wanted: list = []    # keys, nearest first
        self._wset: set = set()
        self._changes = 0
        self._ver: dict = {}       # key -> version of its newest mesh
        self._emitted: dict = {}   # wanted key -> version queued or drawn
        self._drawn: set = set()   # keys handed to the consumer and not yet gone
        self._stale: set = set()   # keys whose stored samples are out of date
        self._ready: deque = deque()
        self._tick = 0
        self._stop = False
        ending.close_at_exit(self)  # (a worker in a kernel at exit aborted the process)
        self._thread = threading.Thread(target=self._run, name="voxel-far", daemon=True)
        self._thread.start()

    @classmethod
    def of(cls, world) -> "Builder":
        """The builder of a world.World (taken by duck typing: .file, .generator and
        .gen_lock, its loader's generator lock, shared so one generates at a time)."""
        return cls(world.file, world.generator, world.gen_lock)

    # ---- consumer side -----------------------------------------------------
    def set_view(self, x: float, y: float, far: int, near: int = 0,
                 detail: int = grid.DETAIL) -> None:
        """View point (blocks), far and near distances (chunks): the ring to draw."""
        far, near = int(far), int(near)
        if not 0 <= far <= grid.FAR_MAX:
            raise VoxelError(f"far distance must be 0..{grid.FAR_MAX} chunks, got {far}")
        view = (float(x), float(y), far, max(near, 0), int(detail))
        sel = [k for k, _ in grid.select(*view)]
        with self._lock:
            self._view = view
            self._wanted, self._wset = sel, set(sel)
            for k in [k for k in self._emitted if k not in self._wset]:
                del self._emitted[k]
            self._changes += 1
            self._wake.notify_all()

    def drain(self, budget_s: float = 0.004):
        """(new meshes, keys to stop drawing) since the last call."""
        end = time.perf_counter() + budget_s
        out = []
        with self._lock:
            while self._ready:
                m = self._ready.popleft()
                if self._emitted.get(m.key) == m.version and m.key in self._wset:
                    out.append(m)
                    self._drawn.add(m.key)
                if time.perf_counter() >= end:
                    break
            gone = []
            done = {k for k in self._wanted if k in self._drawn}
            for k in [k for k in self._drawn if k not in self._wset]:
                over = [w for w in self._wanted if _overlap(k, w)]
                if all(w in done for w in over):
                    gone.append(k)
            self._drawn.difference_update(gone)
        return out, gone

    @property
    def counts(self) -> tuple[int, int]:
        """(wanted, ready): tiles the view wants, of them with a mesh made."""
        with self._lock:
            return len(self._wanted), sum(1 for k in self._wanted if k in self._emitted)

    @property
    def queued(self) -> int:
        """Meshes made and not drained yet."""
        with self._lock:
            return len(self._ready)

    def wait_ready(self, timeout: float = 120.0) -> bool:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.error is not None:
                raise self.error
            w, r = self.counts
            if r >= w and self._view is not None:
                with self._lock:
                    if not self._stale & self._wset:
                        return True
            time.sleep(0.005)
        return False

    def close(self) -> None:
        with self._lock:
            self._stop = True
            self._wake.notify_all()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        self._thread = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- worker ------------------------------------------------------------
    def _run(self) -> None:
        while True:
            with self._lock:
                while not self._stop and self._view is None:
                    self._wake.wait()
                if self._stop:
                    return
                seen = self._changes
            try:
                self._invalidate()
                keys = self._next()
                key = keys[0] if keys else None
                if keys:
                    self._do(keys)
            except BaseException as e:  # kept for the consumer; the worker goes on
                self.error = e
                key = None
            if key is None:
                with self._lock:
                    if self._changes == seen and not self._stop:
                        self._wake.wait(0.5)

    def _invalidate(self) -> None:
        """Tiles over chunks written since: stored samples dropped, drawn ones rebuilt."""
        keys = self.store.take_dirty(lambda chunks: {k for c in chunks
                                                     for k in grid.touching(*c)})
        if not keys:
            return
        with self._lock:
            self._stale |= keys & (set(self._emitted) | self._wset)
            for k in keys:
                self._emitted.pop(k, None)

    def _next(self) -> list:
        """Up to BATCH wanted tiles without a mesh, nearest first."""
        with self._lock:
            return [k for k in self._wanted if k not in self._emitted][:BATCH]

    def _read_chunk(self, key):
        try:
            got = self.file.read_chunk(key)
        except CorruptChunk:
            return None
        return None if got is None else got[0]

    def _do(self, keys) -> None:
        """Tiles' samples (stored, else built: the ones to build together, so the
        generator runs larger steps), stored, meshed and queued one by one."""
        from ..core import trace
        got = {k: None if k in self._stale else self.store.tile(k, grid.N) for k in keys}
        build = [k for k in keys if got[k] is None]
        t0 = time.perf_counter()
        if build:
            with trace.span("far.build", n=len(build)):
                if self._gen_lock is None:
                    made = tiles.build_many(build, self.store, self.generator, self._read_chunk)
                else:
                    with self._gen_lock:
                        made = tiles.build_many(build, self.store, self.generator,
                                                self._read_chunk)
                self.store.put_tiles([(k, a) for k, (a, _) in zip(build, made)])
            for k, (a, n) in zip(build, made):
                got[k] = a
                self.stats["built"] += 1
                self.stats["from_chunks"] += n
        self.stats["build_s"] += time.perf_counter() - t0
        for k in keys:
            with trace.span("far.tile", key=k, built=k in build):
                self._mesh(k, got[k], k in build)

    def _mesh(self, key, a, built) -> None:
        t0 = time.perf_counter()
        if not built:
            self.stats["loaded"] += 1
        with self._lock:
            self._tick += 1
            ver = self._tick
        m = mesh.build(key, a, ver)
        self.stats["build_s"] += time.perf_counter() - t0
        with self._lock:
            self._stale.discard(key)
            self._ver[key] = ver
            if key in self._wset:
                self._emitted[key] = ver
                self._ready.append(m)


def ring(file, generator, x: float, y: float, far: int, near: int = 0,
         timeout: float = 600.0, lock=None) -> list:
    """The far meshes of a view, all of them, built now (renders: the CLI's
    `render --far`, Render Voxel View): [FarMesh]."""
    with Builder(file, generator, lock) as b:
        b.set_view(x, y, far, near)
        if not b.wait_ready(timeout):
            raise VoxelError(f"far terrain not built within {timeout:.0f} s")
        meshes, _ = b.drain(1e9)
    return meshes
