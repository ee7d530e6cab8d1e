"""Streaming around a moving view point (SPEC F2, thesis §5.2, issue 11 §2).

Background workers keep every chunk within `distance` (Chebyshev, in chunks) of the
view chunk generated or loaded, lit and meshed, and queue its Payload. Work goes in
batches: a rectangle of up to `tile` x `tile` chunks (aligned, so neighbouring views
share them) is generated/loaded with its one-chunk ring in one call, lit in one
solve and meshed in one build_chunks call; batching is what makes it fast on few
cores. Nearest rectangles first, and in-view before behind when a direction is
given; near the view the rectangles are smaller so the first payloads come soon.
A payload comes out only when the chunk's light is final (its 8 neighbours' blocks
were known), so the result is the same whatever the order (tests compare it with
the one-shot path).

Chunks that fell out of range: their queued payloads are dropped at drain, drawn ones
are reported in `gone`, and chunks farther than distance + 1 + margin are unloaded by
the world (saved first if changed). The consumer calls `drain(budget_s)` from its
own thread; it only pops a queue, so it stays within its budget.

Edits: world.edit.edit() returns the new payloads, and every Stream of that world
also queues them, so a consumer that only drains stays right too (applying a payload
twice is harmless: same key, same version).
"""
from __future__ import annotations

import math
import threading
import time
from collections import deque

import numpy as np

from .. import opencl
from ..core import ending
from ..core.errors import VoxelError
from . import build

NEAR = 6  # chunks: closer than this, work in half tiles (first payloads sooner)
FIRST = 2  # ... and closer than this in quarter tiles: the first picture of a fresh
# install comes from NumPy while OpenCL builds (2 x 2 chunks: ~0.5 s against ~1.5 s)
MAINTAIN_S = 1.0  # seconds between keep-alive/unload/compact sweeps for one view


class Stream:
    def __init__(self, world, distance: int, *, tile: int = 8, margin: int = 2, backends=None,
                 workers: int = 2):
        if int(distance) < 0:
            raise VoxelError(f"view distance must be 0 or more, got {distance}")
        if tile < 1:
            raise VoxelError(f"tile must be at least 1, got {tile}")
        self.world = world
        self.distance = int(distance)
        self.tile = int(tile)
        self.margin = int(margin)
        # None: build.backends() per batch, so the first batches run NumPy while an
        # OpenCL warm-up (build.warm) builds the kernels
        self.backends = backends
        # Two workers: while one waits on OpenCL (one queue: generation, meshing) the
        # other lights on the CPU (bench world: stream_view32_s per worker count).
        self._worker_backends = [self.backends] * max(1, int(workers))
        self.error: BaseException | None = None
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._view = None           # (cx, cy, (dx, dy) or None)
        self._changes = 0           # bumped by set_view and finished jobs: the worker rechecks
        self._ready: deque = deque()
        self._gone: deque = deque()
        self._emitted: dict = {}    # key in range -> version of its queued/drawn payload
        self._drawn: set = set()
        self._busy: set = set()     # keys a worker is doing now
        self._stop = False
        self.first_at = None        # time.monotonic() of the first payload queued
        self.first_backends = None  # (light, meshing) of the first batch made
        self._kept = (None, 0.0)  # view chunk and time of the last full _maintain
        self._area = (None, [])   # (view chunk, distance) and the keys in range
        world.streams.add(self)
        ending.close_at_exit(self)  # (a worker in a kernel at exit aborted the process)
        self._threads = [threading.Thread(target=self._run, args=(be,), daemon=True,
                                          name=f"voxel-stream-{i}")
                         for i, be in enumerate(self._worker_backends)]
        for t in self._threads:
            t.start()

    # ---- consumer side -----------------------------------------------------
    def set_view(self, x: float, y: float, direction=None) -> None:
        """View point in world units (voxels); direction: optional (dx, dy[, dz])."""
        cx, cy = math.floor(x) >> 4, math.floor(y) >> 4
        d = None
        if direction is not None:
            dx, dy = float(direction[0]), float(direction[1])
            n = math.hypot(dx, dy)
            d = (dx / n, dy / n) if n > 1e-9 else None
        with self._lock:
            old = self._view
            self._view = (cx, cy, d)
            if old is None or old[:2] != (cx, cy):
                self._prune()
            else:
                # the same chunk (a live view's redraws: orbiting turns the direction
                # only): a worker at work reads the view again for its next batch, an
                # idle one has nothing in range left to make, so none is woken (each
                # woken worker copied the chunk map and scanned the range, holding the
                # GIL beside every redraw: issue 29)
                return
            self._changes += 1
            self._wake.notify_all()

    def set_distance(self, distance: int) -> None:
        """Change the view distance (chunks); what falls outside goes as in set_view."""
        if int(distance) < 0:
            raise VoxelError(f"view distance must be 0 or more, got {distance}")
        with self._lock:
            self.distance = int(distance)
            self._prune()
            self._changes += 1
            self._wake.notify_all()

    def _prune(self) -> None:
        """Forget payloads of chunks now out of range; drawn ones are reported gone."""
        if self._view is None:
            return
        cx, cy, _ = self._view
        r = self.distance
        for k in [k for k in self._emitted if max(abs(k[0] - cx), abs(k[1] - cy)) > r]:
            del self._emitted[k]
            if k in self._drawn:
                self._drawn.discard(k)
                self._gone.append(k)

    def drain(self, budget_s: float = 0.004):
        """(ready payloads, gone keys) since the last call, popping for at most
        budget_s. Drained payloads count as drawn (see mark_drawn)."""
        # No lock here: a lock the worker holds would hand the GIL to it and the
        # consumer might wait a switch interval (5 ms) to get it back. deque pops,
        # dict reads and set adds are atomic; a race only drops a stale payload.
        end = time.perf_counter() + budget_s
        out = []
        pver, emitted, ready = self.world.pver, self._emitted, self._ready
        gone = []
        while self._gone:
            try:
                gone.append(self._gone.popleft())
            except IndexError:
                break
        while ready:
            try:
                p = ready.popleft()
            except IndexError:
                break
            if emitted.get(p.key) == p.version and pver.get(p.key) == p.version:
                out.append(p)
                self._drawn.add(p.key)
            if time.perf_counter() >= end:
                break
        if out and gone:
            keys = {p.key for p in out}
            gone = [k for k in gone if k not in keys]
        return out, gone

    def mark_drawn(self, keys) -> None:
        """For consumers that draw later than they drain: count these as drawn."""
        with self._lock:
            self._drawn.update(k for k in map(tuple, keys) if k in self._emitted)

    @property
    def counts(self) -> tuple[int, int, int]:
        """(wanted, ready, drawn): chunks in range, of them with a payload made,
        of them handed to the consumer."""
        n = 2 * self.distance + 1
        with self._lock:
            return n * n - self._corrupt_in_range(), len(self._emitted), len(self._drawn)

    def _corrupt_in_range(self) -> int:
        if self._view is None or not self.world.corrupt:
            return 0
        cx, cy, _ = self._view
        return sum(max(abs(k[0] - cx), abs(k[1] - cy)) <= self.distance
                   for k in list(self.world.corrupt))

    def offer(self, payloads) -> None:
        """Queue current payloads (the workers', edits') of the chunks in range."""
        with self._lock:
            if self._view is None:
                return
            cx, cy, _ = self._view
            for p in payloads:
                if max(abs(p.key[0] - cx), abs(p.key[1] - cy)) <= self.distance \
                        and self.world.pver.get(p.key) == p.version:
                    self._emitted[p.key] = p.version
                    self._ready.append(p)
                    if self.first_at is None:
                        self.first_at = time.monotonic()
            # no wake-up: current payloads add no work (a worker's own job wakes the
            # others when it ends), and woken workers rescanning every key would take
            # the GIL from the editing thread (edit latency x2 at distance 32)

    @property
    def idle(self) -> bool:
        """Whether every chunk in range has a payload (nothing left to make)."""
        w, r, _ = self.counts
        return self._view is not None and r >= w

    @property
    def queued(self) -> int:
        """Payloads waiting for the consumer's drain (no lock: a deque's length)."""
        return len(self._ready)

    def wait_ready(self, timeout: float = 60.0) -> bool:
        """Block until every wanted chunk has a payload (tests, bench, CLI)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.error is not None:
                raise self.error
            w, r, _ = self.counts
            if r >= w and self._view is not None:
                return True
            time.sleep(0.005)
        return False

    def close(self) -> None:
        """Stop the worker (it finishes its batch first). Safe to call twice."""
        with self._lock:
            self._stop = True
            self._wake.notify_all()
        for t in self._threads:
            if t is not threading.current_thread():
                t.join()
        self._threads = []
        self.world.streams.discard(self)

    @property
    def running(self) -> bool:
        return any(t.is_alive() for t in self._threads)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ---- worker ------------------------------------------------------------
    def _run(self, backends) -> None:
        while True:
            with self._lock:
                while not self._stop and self._view is None:
                    self._wake.wait()
                if self._stop:
                    return
                cx, cy, d = self._view
                seen = self._changes
                em, busy = dict(self._emitted), set(self._busy)
            job = self._next(cx, cy, d, em, busy)
            if job is not None:
                with self._lock:  # another worker may have claimed or done some meanwhile
                    em, pv = self._emitted.get, self.world.pver.get
                    job = [k for k in job if k not in self._busy and em(k, -1) != pv(k, -2)]
                    self._busy.update(job)
                    if not job:
                        continue
            try:
                if job is not None:
                    self._do(job, backends)
                self._maintain(cx, cy)
            except BaseException as e:  # kept for the consumer; the worker goes on
                self.error = e
                job = None
            finally:
                if job is not None:
                    with self._lock:
                        self._busy.difference_update(job)
                        self._changes += 1
                        self._wake.notify_all()
            if job is None:
                with self._lock:
                    if self._changes == seen and not self._stop:
                        self._wake.wait(0.05 if opencl.warming() else 0.5)

    def _pending(self, cx, cy, em, busy):
        """Keys in range without a current payload, not being done."""
        r, bad = self.distance, self.world.corrupt
        area = self._area
        if area[0] != (cx, cy, r):  # every batch rescans the range: keep its keys
            area = self._area = ((cx, cy, r), [(x, y) for y in range(cy - r, cy + r + 1)
                                               for x in range(cx - r, cx + r + 1)])
        eg, pg = em.get, self.world.pver.get
        return [k for k in area[1]
                if eg(k, -1) != pg(k, -2) and k not in bad and k not in busy]

    def _next(self, cx, cy, d, em, busy):
        """The pending keys of the aligned tile holding the most urgent pending chunk,
        half a tile near the view (first payloads sooner); None when all is done.
        Larger tiles cut the light solve's ring overhead but the NumPy solve gets
        slower per chunk beyond ~12 chunks a side (cache): 8 is about the best."""
        pending = self._pending(cx, cy, em, busy)
        if not pending:
            return None
        # urgency of every pending key at once (thousands at view 32, every batch)
        p = np.array(pending, np.int64)
        vx, vy = p[:, 0] - cx, p[:, 1] - cy
        u = np.hypot(vx, vy)
        if d is not None:
            far = u > 0
            u[far] *= 1.5 - 0.5 * (vx[far] * d[0] + vy[far] * d[1]) / u[far]  # behind: x2
        i = int(np.argmin(u))
        if u[i] >= FIRST and self.backends is None and opencl.warming("meshing"):
            # the OpenCL kernels still build: NumPy made the first picture (the chunks
            # next to the view); more NumPy now takes the CPU from the build (one NumPy
            # worker during the warm-up: the build took 2x longer, the whole view came
            # later; niced to 19 it made few chunks and held the GIL from the others).
            # Meshing's too: batches with OpenCL generation but NumPy meshing while
            # meshing's kernels built cost ~1 s more CPU and the whole view came later
            # (issue 28, blender/README)
            return None
        t = max(1, self.tile // (4 if u[i] < FIRST else 2)) if u[i] < NEAR else self.tile
        r = self.distance
        tx, ty = _tiling(cx - r, cx + r, t)(p[:, 0]), _tiling(cy - r, cy + r, t)(p[:, 1])
        keys = [pending[j] for j in np.flatnonzero((tx == tx[i]) & (ty == ty[i])).tolist()]
        if u[i] >= FIRST and self.backends is None and opencl.warming("generation") and \
                not self._stored(keys):
            return None  # meshing is warm (build.warm meshed stored chunks first), but
            # these chunks need generating: as above, not on NumPy beside the build
        return keys

    def _stored(self, keys) -> bool:
        """Whether every chunk of keys is in memory or in the file (none to generate)."""
        world = self.world
        with world.locked():
            rest = [k for k in keys if k not in world.chunks]
        if not rest:
            return True
        xs, ys = [k[0] for k in rest], [k[1] for k in rest]
        have = world.file.chunks_in(min(xs), min(ys), max(xs), max(ys))
        return all(k in have for k in rest)

    def _do(self, keys, backends) -> None:
        from ..core import trace
        with trace.span("batch", n=len(keys), at=min(keys)):  # (VOXEL_TRACE)
            self._make(keys, backends)

    def _make(self, keys, backends) -> None:
        world = self.world
        done = [p for p in (build.payload(world, k) for k in keys) if p is not None]
        rest = {k for k in keys} - {p.key for p in done}
        if rest:
            xs, ys = [k[0] for k in rest], [k[1] for k in rest]
            backends = backends or build.backends()
            done += build.light_and_mesh(world, min(xs), min(ys), max(xs) + 1, max(ys) + 1,
                                         backends_=backends)
            if done and self.first_backends is None:
                self.first_backends = backends
        from ..core import trace
        # compact now: _maintain's sweep over all chunks is throttled
        with trace.span("batch.compact"):
            build.compact(world, [p.key for p in done])
        self.offer(done)

    def _maintain(self, cx, cy) -> None:
        """Keep chunks near the view alive (the world's idle unloading), unload far
        ones, keep their light compact."""
        world, keep, now = self.world, self.distance + 1 + self.margin, time.monotonic()
        # a sweep over every chunk after every batch cost ~7 % of the worker's CPU
        # at view 32; idle unloading waits seconds (idle_timeout), so a sweep a
        # second (and one whenever the view moved) keeps the same guarantees
        if self._kept[0] == (cx, cy) and now - self._kept[1] < min(MAINTAIN_S,
                                                                  world.idle_timeout / 4):
            return
        self._kept = ((cx, cy), now)
        far = []
        with world.locked():
            for k, c in world.chunks.items():
                if max(abs(k[0] - cx), abs(k[1] - cy)) > keep:
                    far.append(k)
                else:
                    c.last_use = now
                    c.compact()  # light an edit read or set (see Chunk.light)
        if far:
            world.evict(far)


def _tiling(lo: int, hi: int, t: int):
    """Tile index along one axis for keys in [lo, hi]: aligned tiles of t, but a
    range end that cuts a tile to less than half joins the tile next to it, so no
    thin strip pays a whole ring of light solve for a few chunks (view 32: 65 = 8 x 8
    + 1; the 1-wide strips cost 3 chunks solved per chunk kept)."""
    a, b = lo // t, hi // t
    thin_hi = b > a and 2 * (hi - b * t + 1) < t
    thin_lo = b > a + (1 if thin_hi else 0) and 2 * ((a + 1) * t - lo) < t

    def f(k: np.ndarray) -> np.ndarray:
        i = k // t
        if thin_hi:
            i = np.where(i == b, b - 1, i)
        if thin_lo:
            i = np.where(i == a, a + 1, i)
        return i
    return f
