"""The world: a hash map of active chunks, their lifecycle and the loader thread (§5.2).

Three ways to ask for a chunk, as in the thesis:
- `maybe_chunk_at`      returns it if active, else None; never blocks.
- `maybe_load_chunk_at` the same, and queues it for the loader thread; keeps it alive.
- `chunk_at`            returns it, loading or generating in the caller's thread if needed.
Chunks not asked for during `idle_timeout` seconds are saved (if changed) and
unloaded by the loader thread. Unloading never loses an edit: a chunk leaves the map
and enters `_saving` (a snapshot) atomically under the lock, and loads look there
first, so a chunk re-requested before its write lands comes back with every edit.

A chunk row that cannot be decoded is reported once (`corrupt`, a log warning) and
treated as missing: never generated in its place, never written over.

Saving, unloading, imports and other writers of the same file (another Blender, a
command-line edit or import) are world/saving.py's (a mixin): every block writer
records its voxels through `blocks_changed`, so a stale copy is merged, not written
over, and `refresh()` takes in what other processes wrote.
Besides blocks, an active chunk may hold its final light and mesh (world.stream and
world.edit fill them); `tick` numbers every change so payload versions only grow.
"""
from __future__ import annotations

import itertools
import logging
import threading
import time
import weakref
from collections import OrderedDict

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY
from ..core.chunk import Chunk
from ..core.errors import VoxelError
from ..storage import CorruptChunk

log = logging.getLogger(__name__)

from .saving import BATCH, Saving


class World(Saving):
    def __init__(self, file, generator, *, idle_timeout: float = 5.0, loader: bool = True):
        self.file = file
        self.generator = generator
        self.idle_timeout = idle_timeout
        self.readonly = file.readonly
        self.chunks: dict[tuple[int, int], Chunk] = {}
        self._lock = threading.RLock()
        self._gen_lock = threading.Lock()   # generators (OpenCL queues) are not re-entrant
        self._flush_lock = threading.Lock()  # one flush at a time: an older snapshot never lands last
        self._wake = threading.Condition(self._lock)
        self._queue: OrderedDict[tuple[int, int], None] = OrderedDict()
        self._saving: dict[tuple[int, int], tuple] = {}
        self._evictions: dict[tuple[int, int], int] = {}
        self._edits: dict[tuple[int, int, int], tuple[int, int]] = {}  # unsaved user edits
        self._stale: set = set()  # chunks whose light in the file no longer holds
        self._held: set = set()   # chunks a stroke changed, written at its commit
        self._behind = None       # the writer thread's commit in flight (commit_behind)
        self._writer = None       # that thread (an executor), started by the first
        self.fver: dict = {}      # key -> stored version its active copy (or snapshot) was read at
        self._mine: dict = {}     # key -> {(x, y, z): (id, data)} own changes not known stored
        self.corrupt: dict[tuple[int, int], str] = {}  # key -> message, reported once
        self.bver: dict[tuple[int, int], int] = {}   # key -> tick of its last block change
        self.pver: dict[tuple[int, int], int] = {}   # key -> version of its newest payload
        self._tick = itertools.count(1)
        self.streams = weakref.WeakSet()  # closed before the world closes
        self._seen = file.top_version()   # newest stored version refresh() looked at
        file.data_changed()               # its baseline
        self._stop = False
        self.loader_error: BaseException | None = None
        self._thread = None
        if loader:
            self._thread = threading.Thread(target=self._loader, name="voxel-loader", daemon=True)
            self._thread.start()

    # ---- opening ----------------------------------------------------------
    @classmethod
    def create(cls, path, *, seed: int, generator: str = "overworld", params=None,
               backend=None, **kw) -> "World":
        from ..generation import make_generator
        from ..storage import WorldFile
        gen = make_generator(generator, seed, params, backend)
        wf = WorldFile.create(path, seed=seed, generator=gen.name,
                              generator_version=gen.version, params=gen.params)
        return cls(wf, gen, **kw)

    @classmethod
    def open(cls, path, *, backend=None, readonly: bool = False, **kw) -> "World":
        from ..generation import for_file
        from ..storage import WorldFile
        wf = WorldFile(path, readonly=readonly)
        try:
            gen = for_file(wf, backend)
        except (ValueError, TypeError, KeyError, IndexError, AttributeError) as e:
            wf.close()  # a hostile or damaged meta row: one line, not a traceback
            raise VoxelError(f"{path}: its generator settings are damaged "
                             f"({type(e).__name__}: {e})") from None
        except BaseException:
            wf.close()
            raise
        return cls(wf, gen, **kw)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def seed(self) -> int:
        return self.file.seed

    def model_quads(self, blocks, data, cx0: int, cy0: int) -> dict:
        """{key: Minecraft model quads} of an area's chunks with the world's resource
        stack, their voxels set to air in BLOCKS (world/models.py; {} without one)."""
        from . import models
        return models.build(self, blocks, data, cx0, cy0)

    def light_blocks(self, blocks, data):
        """BLOCKS as the light solve sees them: with the world's resource stack its
        model blocks that are no whole cube pass light (world/models.py)."""
        from . import models
        return models.light_blocks(self, blocks, data)

    def colors(self):
        """The world's colour palette ((n, 3) uint8, core.colors): the `color` block's
        data indexes it (meshes carry the index per vertex, ChunkMesh.colors). Parsed
        once per change of the file's meta value."""
        from ..core import colors
        raw = self.file.meta.get(colors.KEY)
        cached = getattr(self, "_colors", None)
        if cached is None or cached[0] != raw:
            cached = self._colors = (raw, colors.parse(self.file.meta))
        return cached[1]

    @property
    def gen_lock(self):
        """Held around every use of the world's generator (OpenCL queues are not
        re-entrant): give it to whatever else generates with it (far.Builder)."""
        return self._gen_lock

    def writable(self) -> None:
        """A VoxelError when the world is open read-only (checked before any change)."""
        if self.readonly:
            raise VoxelError(f"{self.file.path} is open read-only")

    def tick(self) -> int:
        """A new number, larger than every one before (versions, block changes)."""
        return next(self._tick)

    # ---- the three access functions ----------------------------------------
    def maybe_chunk_at(self, cx: int, cy: int) -> Chunk | None:
        return self.chunks.get((cx, cy))

    def maybe_load_chunk_at(self, cx: int, cy: int) -> Chunk | None:
        key = (cx, cy)
        with self._lock:
            c = self.chunks.get(key)
            if c is not None:
                c.last_use = time.monotonic()
                return c
            if key not in self._queue:
                self._queue[key] = None
                self._wake.notify()
        return None

    def chunk_at(self, cx: int, cy: int) -> Chunk:
        key = (int(cx), int(cy))   # NumPy ints activated an empty chunk (read-only)
        c = self.chunks.get(key)
        if c is None:
            c = self._activate([key])[0]
        c.last_use = time.monotonic()
        return c

    # ---- blocks -----------------------------------------------------------
    def get_block(self, x: int, y: int, z: int) -> int:
        C.check_z(z)
        return self.chunk_at(x >> 4, y >> 4).get(x & 15, y & 15, z)

    def set_block(self, x: int, y: int, z: int, block: int | str, data: int = 0) -> int:
        """Place (or, with air, clear) a block; returns the id that was there.

        The bulk form of world.edit.edit: the same checks and the same write, kept
        like an edit until the next flush, but no relight and no undo record: the
        light and meshes of the 3x3 around are dropped and made again by whoever
        needs them (streams, build.light_and_mesh), as for a chunk loaded without
        light. Tests and importers set many voxels this way; strokes use edit()."""
        from .edit import check
        ((x, y, z, bid, data),) = check(self, [(x, y, z, block, data)])
        with self._lock:
            c = self.chunk_at(x >> 4, y >> 4)
            old = c.get(x & 15, y & 15, z)
            c.data = C.put(c.blocks, c.data, x & 15, y & 15, z, bid, data)
            self.blocks_changed(c.key, {(x, y, z): (bid, data)})
        return old

    def blocks_changed(self, key, voxels: dict, *, edits: bool = True, tick=None,
                       relit: bool = False) -> None:
        """The one bookkeeping of every block writer (set_block, set_blocks, edits,
        imports), called under the lock once `voxels` ({(x, y, z): (id, data)} in
        chunk `key`) are in the active chunk: it is marked changed, its block version
        ticks, the voxels count as this session's own (re-applied over another
        writer's copy, see the module docstring) and, with `edits`, as user edits
        kept for the file's edits table; unless `relit` (world.edit relights
        itself) the light and meshes of its 3x3 are dropped. No voxels: the chunk
        was replaced as a whole (an import), only versions and light follow."""
        if voxels:
            self.chunks[key].dirty = True
            self._mine.setdefault(key, {}).update(voxels)
            if edits:
                self._edits.update(voxels)
        self.bver[key] = self.tick() if tick is None else tick
        if not relit:
            self.drop_light(key)

    def drop_light(self, key) -> None:
        """Light and meshes of the 3x3 around chunk `key` no longer hold (in memory
        and in the file); streams make them again."""
        with self._lock:
            for i in (-1, 0, 1):
                for j in (-1, 0, 1):
                    k = (key[0] + i, key[1] + j)
                    self.pver.pop(k, None)
                    self._stale.add(k)
                    n = self.chunks.get(k)
                    if n is not None:
                        n.light = n.mesh = None

    def locked(self):
        """The world's lock, for code that reads or changes active chunks together
        (`with world.locked(): ...`); re-entrant."""
        return self._lock

    def region_blocks(self, cx0: int, cy0: int, cx1: int, cy1: int) -> np.ndarray:
        """Blocks of chunks [cx0, cx1) x [cy0, cy1) as one (W, H, 256) array."""
        keys = [(cx, cy) for cy in range(cy0, cy1) for cx in range(cx0, cx1)]
        out = C.empty(width=C.SIZE * (cx1 - cx0), depth=C.SIZE * (cy1 - cy0))
        got = self.load(keys)
        for (cx, cy), c in got.items():
            x, y = (cx - cx0) * C.SIZE, (cy - cy0) * C.SIZE
            out[x:x + C.SIZE, y:y + C.SIZE] = c.blocks
        return out

    # ---- loading, generating ------------------------------------------------
    def _activate(self, keys) -> list[Chunk]:
        """Make `keys` active and return them; a corrupt one raises CorruptChunk."""
        got = self.load(keys)
        for k in keys:
            if k not in got:
                raise CorruptChunk(self.corrupt[k])
        return [got[k] for k in keys]

    def load(self, keys, hot: bool = False) -> dict:
        """Make `keys` active (load, or generate + apply stored edits); returns
        {key: Chunk} without the corrupt ones (shown as missing). `hot`: the caller
        hands the light on (a stream's batch: its payloads) and compacts the chunks
        after, so light read from the file stays an array (packed here, it would be
        rebuilt for the payload at once).

        Reading happens outside the lock, so another thread may load, edit and evict
        the same chunk meanwhile; the eviction counter catches that and the stale
        read is thrown away and redone.
        """
        out: dict = {}
        pending = [k for k in dict.fromkeys(map(tuple, keys)) if k not in self.corrupt]
        while pending:
            with self._lock:
                epochs = {k: self._evictions.get(k, 0) for k in pending}
            found, vers = self._fetch([k for k in pending if k not in self.chunks], hot)
            retry = []
            with self._lock:
                now = time.monotonic()
                for k in pending:
                    c = self.chunks.get(k)
                    if c is None and k in self.corrupt:
                        continue
                    if c is None:
                        if k not in found or self._evictions.get(k, 0) != epochs[k]:
                            retry.append(k)
                            continue
                        c = self.chunks[k] = found[k]
                        if vers[k] is not None:  # read from the file: what it holds now
                            self.fver[k] = vers[k]
                            self._mine.pop(k, None)
                    c.last_use = now
                    out[k] = c
            pending = retry
        return out

    def _fetch(self, keys, hot: bool = False) -> tuple[dict, dict]:
        """New Chunk objects for keys: from an unsaved snapshot, the file, or the
        generator; and the stored version each stands on ({key: version}; None for
        a snapshot: its own stays)."""
        found: dict = {}
        vers: dict = {}
        to_make, read, bad = [], [], []
        with self._lock:
            snaps = {key: self._saving.get(key) for key in keys}
        for key, snap in snaps.items():
            if snap is None:
                read.append(key)
                continue
            b = snap[0]  # a Packed one (Chunk.saved) never changes: no copy
            c = found[key] = Chunk(key, b if isinstance(b, C.Packed) else b.copy(order="F"),
                                   None if snap[1] is None else snap[1].copy(order="F"))
            c.light = snap[2]  # light arrays are replaced, never changed in place
            vers[key] = None
        # the batch read at one instant (a snapshot made meanwhile: load()'s eviction
        # count sees it)
        for key, got in (self.file.fetch_many(read) if read else {}).items():
            if isinstance(got, CorruptChunk):
                bad.append((key, str(got)))
                continue
            vers[key] = got[3]
            if got[0] is None:
                to_make.append(key)
            else:
                found[key] = got
        for key, msg in bad:
            self._report_corrupt(key, msg)
        for key in read:
            got = found.get(key)
            if got is not None:
                c = found[key] = Chunk(key, got[0], got[1])
                c.light = got[2]
                if not hot:
                    c.compact()
        if to_make:
            with self._gen_lock:
                # another thread may have made some while this one waited for the lock
                to_make = [k for k in to_make if k not in self.chunks]
                arrays = self.generator.generate(to_make) if to_make else []
            for key, blocks in zip(to_make, arrays):
                c = Chunk(key, *self.apply_stored_edits(key, blocks))
                c.dirty = not self.readonly
                found[key] = c
        return found, vers

    def apply_stored_edits(self, key, blocks, data=None):
        """The file's edits inside chunk `key` applied to freshly generated arrays
        (in place, data values included: the one place that does it); (blocks, data)."""
        for x, y, z, b, d in self.file.edits_in(key):
            data = C.put(blocks, data, x & 15, y & 15, z, b, d)
        return blocks, data

    def _report_corrupt(self, key, msg: str) -> None:
        with self._lock:
            if key in self.corrupt:
                return
            self.corrupt[key] = msg
        log.warning("%s (shown as missing)", msg)

    def _loader(self) -> None:
        while True:
            with self._lock:
                if not self._queue and not self._stop:
                    self._wake.wait(timeout=min(1.0, self.idle_timeout / 2))
                if self._stop:
                    return
                keys = []
                while self._queue and len(keys) < BATCH:
                    keys.append(self._queue.popitem(last=False)[0])
            try:
                if keys:
                    self._activate(keys)
                self.unload_idle()
            except BaseException as e:  # kept for the UI to show; the thread goes on
                self.loader_error = e

    def unload_all(self) -> None:
        with self._lock:
            keys = list(self.chunks)
        self.evict(keys)

    def close(self) -> None:
        """Stop streams and the loader, save everything, close the file. Safe to
        call twice. When the save fails (disk full, file-size limit, a vanished
        drive) it raises and the file stays open with every unsaved edit kept in
        memory (`unsaved_edits`): calling close again retries."""
        self._stop_threads()
        if self.file.db is not None:
            self.flush()
            self.file.close()

    def _stop_threads(self) -> None:
        for s in list(self.streams):
            s.close()
        with self._lock:
            self._stop = True
            self._wake.notify_all()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        self._stop_writer()

    def discard(self) -> None:
        """Stop streams and the loader and close the file without saving (its file
        is gone: nothing can be written; the unsaved edits were rescued first)."""
        self._stop_threads()
        self.file.close()

    def forget_unsaved(self) -> None:
        """Drop the unsaved edits from the list of edits to save (they were kept
        elsewhere: world/rescue.py); the chunks keep showing them."""
        with self._lock:
            self._edits.clear()

    def unsaved_edits(self) -> list[tuple[int, int, int, int, int]]:
        """The user's edits (x, y, z, block id, data) not yet in the file. Generated
        chunks and light are not listed: they come back from the seed."""
        with self._lock:
            return [(x, y, z, b, d) for (x, y, z), (b, d) in self._edits.items()]

    def set_blocks(self, xyz, ids, data=None) -> None:
        """set_block for many voxels at once ((n, 3) positions, n ids, n data values
        or None), kept like edits until the next flush or commit (a .vox stamp)."""
        self.writable()
        xyz = np.asarray(xyz, np.int64).reshape(-1, 3)
        ids = np.asarray(ids, np.uint16)
        vals = np.zeros(len(ids), np.uint16) if data is None else np.asarray(data, np.uint16)
        if len(xyz) and (xyz[:, 2].min() < 0 or xyz[:, 2].max() >= C.HEIGHT):
            raise VoxelError(f"z outside the world (0..{C.HEIGHT - 1})")
        if len(ids) and int(ids.max()) >= len(REGISTRY):
            raise VoxelError(f"unknown block id {int(ids.max())}")
        keys = np.stack([xyz[:, 0] >> 4, xyz[:, 1] >> 4], 1)
        for k in {tuple(v) for v in keys.tolist()}:
            if k in self.corrupt:
                raise VoxelError(f"chunk {k} is damaged in the file; it cannot be edited")
        order = np.lexsort((keys[:, 1], keys[:, 0]))
        xyz, ids, vals, keys = xyz[order], ids[order], vals[order], keys[order]
        cut = np.flatnonzero(np.any(np.diff(keys, axis=0) != 0, axis=1)) + 1
        for part in np.split(np.arange(len(ids)), cut):
            if not len(part):
                continue
            k = tuple(int(v) for v in keys[part[0]])
            with self._lock:
                c = self.chunk_at(*k)
                lx, ly, z = xyz[part, 0] & 15, xyz[part, 1] & 15, xyz[part, 2]
                c.data = C.put(c.blocks, c.data, lx, ly, z, ids[part], vals[part])
                self.blocks_changed(k, {tuple(v): (b, d) for v, b, d in zip(
                    xyz[part].tolist(), ids[part].tolist(), vals[part].tolist())})

    def recreate(self, keep_edits: bool = True) -> None:
        """Forget every generated chunk (they regenerate on demand from the seed)."""
        with self._lock:
            self.chunks.clear()
            self._saving.clear()
            self._queue.clear()
            self.corrupt.clear()
        self.flush()
        self.file.delete_chunks()
        if not keep_edits:
            self.file.clear_edits()
