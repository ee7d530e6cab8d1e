"""Saving and unloading, and other writers of the same file: the World's half that
writes (a mixin of world.World, which holds the state it uses).

Every active chunk remembers the stored version it was read at (`fver`) and this
session's own changes to it since (`_mine`: voxel -> (id, data)), which every block
writer records through World.blocks_changed. A write checks inside its transaction
(storage.WorldFile.save's resolve: one indexed lookup per chunk) whether another
writer stored the chunk since; then the stored chunk is written with the own
changes applied again instead of the stale copy (a chunk generated or relit only:
the stored one is kept), and the active chunk takes the result, its light and mesh
made again. Imports (`store_chunks`) decide per chunk inside the transaction too.
`refresh()` takes in what other processes wrote (a pragma when nothing changed).
"""
from __future__ import annotations

import os
import time

from ..core import chunk as C
from ..core import ending
from ..storage import CorruptChunk

BATCH = 32  # chunks generated per loader step: amortises kernel launches


class Saving:
    """World's writing half (see the module docstring); World holds its state."""

    # ---- saving, unloading ---------------------------------------------------
    def unload_idle(self, now: float | None = None) -> int:
        """Save and drop chunks idle longer than idle_timeout; returns how many."""
        now = time.monotonic() if now is None else now
        with self._lock:
            idle = [k for k, c in self.chunks.items() if now - c.last_use > self.idle_timeout]
        return self.evict(idle)

    def evict(self, keys) -> int:
        """Save (if changed) and drop chunks `keys` from memory; returns how many
        were asked. A chunk asked for again meanwhile comes back with every edit."""
        if not keys:
            return 0
        with self._lock:
            for k in keys:
                c = self.chunks.pop(k, None)
                if c is None:
                    continue
                self._evictions[k] = self._evictions.get(k, 0) + 1
                if c.dirty and not self.readonly:
                    self._saving[k] = self._snapshot(k, c.blocks, c.data, c.light)
                elif k not in self._saving:
                    self.fver.pop(k, None)
        self.flush(only=keys)
        return len(keys)

    def at_exit(self) -> None:
        """The interpreter exits with this world open (core/ending.py): what its user
        changed (edits, blocks set, chunks with own changes) is written, not the
        generated terrain and light (they come back from the seed), so the exit is
        quick. A write that fails is said on stderr in one line, the edits kept as
        a failed save in Blender keeps them (world/rescue.py)."""
        if self.file.db is None or self.pid != os.getpid():
            return  # (a forked child's exit: its parent's connection and locks, not its own)
        self._stop_threads()
        try:
            with self._lock:
                own = list(self._mine)
                idle = not (own or self._saving or self._edits or self._stale)
            if not idle:  # (a script that only read waits for no other writer's lock)
                self.flush(only=own)
        except Exception as e:  # noqa: BLE001 - the exit goes on: say it, keep what we can
            from . import rescue
            rescue.at_exit(self, e)
        self.file.close()
        self._unkeep()

    def flush(self, only=None) -> None:
        """Write every changed chunk (or those of `only` and the unloaded ones) and
        every pending edit in one transaction."""
        if self.readonly:
            return
        with self._flush_lock:
            if only is None:
                with self._lock:
                    self._held = set()  # written now with everything else
            self._write(only)

    def commit(self, keys=(), edits=(), stale_light=()) -> None:
        """Write chunks `keys` (if changed), `edits` ((x, y, z, block, data) rows) and
        what is pending or held in one transaction; other changed chunks stay for
        later. `stale_light`: chunks whose stored light no longer holds."""
        if self.readonly:
            return
        with self._flush_lock:
            with self._lock:
                self._stale.update(stale_light)
                keys, self._held = set(keys) | self._held, set()
            self._write(keys, edits)

    def hold(self, keys, edits, stale_light=()) -> None:
        """`commit` later: keep chunks `keys`, `edits` and `stale_light` pending until
        the next commit (or flush, or close) writes them all in one transaction, so a
        stroke of many parts is one transaction when it ends."""
        if self.readonly:
            return
        with self._lock:
            self._stale.update(stale_light)
            self._held.update(keys)
            for x, y, z, b, d in edits:
                self._edits[(x, y, z)] = (b, d)

    def commit_behind(self, keys, edits, stale_light=()) -> None:
        """`commit` on the world's writer thread: held now, written right after, so
        an edit's payloads do not wait for SQLite (issue 29). `settle()` waits for it
        and raises what it raised; commit, flush and close write what it did not."""
        if self.readonly:
            return
        self.hold(keys, edits, stale_light)
        with self._lock:
            f = self._behind
            if f is not None and not f.done() and not f.running():
                return  # queued, not started yet: it takes this hold too
            if self._writer is None:
                from concurrent.futures import ThreadPoolExecutor
                self._writer = ThreadPoolExecutor(1, thread_name_prefix="voxel-writer")
            self._behind = self._writer.submit(self._commit_behind)

    def _commit_behind(self) -> None:
        self.commit()
        C.make_spares()   # the next edit's new light arrays, faulted in here

    def settle(self) -> None:
        """Wait for the writer thread's commit (commit_behind) and raise its error
        (once); its edits then wait in memory for the next write (unsaved_edits)."""
        f, self._behind = self._behind, None
        if f is not None:
            f.result()

    def _stop_writer(self) -> None:
        """Let the writer thread finish (an error is left for the flush that follows)."""
        f, self._behind = self._behind, None
        if f is not None:
            f.exception()
        if self._writer is not None:
            self._writer.shutdown()
            self._writer = None

    @property
    def held(self) -> bool:
        """Whether a stroke's changes wait for a commit."""
        return bool(self._held)

    def _write(self, keys, extra=()) -> None:
        # Snapshots go into _saving before the write so a chunk evicted and reloaded
        # while this write is in flight is rebuilt from them, not from the stale file.
        # A chunk's light is written with it: in memory it is final or None. Each
        # snapshot carries the stored version it stands on and the own changes in
        # it: a chunk another writer changed meanwhile is merged (_resolve).
        with self._lock:
            for k in self.chunks if keys is None else [k for k in keys if k in self.chunks]:
                c = self.chunks[k]
                if c.dirty:  # packed blocks and light go as they are: decoded outside
                    b, light = c.saved()  # the lock, into one buffer (storage/rows.py)
                    self._saving[k] = self._snapshot(k, b, None if c.data is None
                                                     else c.data.copy(order="F"), light)
                    c.dirty = False
            saving = dict(self._saving)
            edits = [(x, y, z, b, d) for (x, y, z), (b, d) in self._edits.items()]
            edits += list(extra)
            self._edits.clear()
            stale, self._stale = self._stale, set()
        merged: dict = {}
        try:
            rows = [self.file.encode_chunk(k, *snap[:2], light=snap[2])
                    for k, snap in saving.items()]
            by = {(r[0], r[1]): r for r in rows}
            new = self.file.save(rows, edits, [k for k in stale if k not in saving],
                                 resolve=lambda k, v: self._resolve(k, v, saving[k], by[k],
                                                                    merged))
        except BaseException:
            with self._lock:  # keep the edits for the next try; snapshots stay in _saving
                for x, y, z, b, d in edits:
                    self._edits.setdefault((x, y, z), (b, d))
                self._stale |= stale
            raise
        with self._lock:
            for k, snap in saving.items():
                if self._saving.get(k) is snap:
                    del self._saving[k]
                self._stored(k, new.get(k), snap[4], merged.get(k))
            if not (self._mine or self._edits or self._saving):
                self._unkeep()

    def _unkeep(self) -> None:
        """Nothing of its user's left to save: the world no longer stays alive for
        the exit (World.blocks_changed keeps it)."""
        if self._kept:
            self._kept = False
            ending.save_at_exit(self, keep=False)

    def _snapshot(self, key, blocks, data, light) -> tuple:
        """What _saving holds for a chunk: (blocks, data, light, stored version it
        stands on, its own changes {voxel: (id, data)} at this moment)."""
        return (blocks, data, light, self.fver.get(key, 0), dict(self._mine.get(key, ())))

    def _resolve(self, key, version, snap, row, merged):
        """Inside the write transaction: the row to write for snapshot `snap` of
        chunk `key` when the file holds `version` of it (storage's resolve); a merge
        goes into `merged` as (blocks, data, version kept or None)."""
        if version == snap[3]:
            return row  # nobody wrote it since it was read: the common case
        stored = self.file.read_chunk(key)
        if stored is None:  # deleted meanwhile (recreate): this copy is all there is
            return row
        if not snap[4]:     # generated or relit only: the stored one stays
            merged[key] = (*stored, version)
            return None
        blocks, data = stored
        for (x, y, z), (b, d) in snap[4].items():
            data = C.put(blocks, data, x & 15, y & 15, z, b, d)
        merged[key] = (blocks, data, None)
        return self.file.encode_chunk(key, blocks, data)

    def _stored(self, key, version, written: dict, merged) -> None:
        """After a write (lock held): the own changes now stored are no longer own,
        the version moves on, and a merged chunk shows the merge (with the own
        changes made while it was written on top)."""
        mine = self._mine.get(key)
        if mine:
            for v, val in written.items():
                if mine.get(v) == val:
                    del mine[v]
            if not mine:
                del self._mine[key]
        if version is None and merged is not None:
            version = merged[2]  # the stored one was kept
        c = self.chunks.get(key)
        if merged is not None and c is not None:
            blocks, data = merged[0].copy(order="F"), \
                None if merged[1] is None else merged[1].copy(order="F")
            for (x, y, z), (b, d) in self._mine.get(key, {}).items():
                data = C.put(blocks, data, x & 15, y & 15, z, b, d)
            c.blocks, c.data, c.light, c.mesh = blocks, data, None, None
            c.dirty = key in self._mine
            self.bver[key] = self.tick()
            self.drop_light(key)
        if version is not None:
            if c is None and key not in self._saving:
                self.fver.pop(key, None)  # gone from memory: read again when loaded
            else:
                self.fver[key] = version

    def refresh(self) -> set:
        """Take in what other processes wrote: active chunks whose stored version
        moved on are read again, own unsaved changes applied on top, their light and
        meshes dropped (streams and the live view make them again). Cheap when
        nothing changed (one pragma). Returns the keys reloaded."""
        if self.file.db is None or not self.file.data_changed():
            return set()
        out = set()
        with self._lock:
            changed = self.file.versions_since(self._seen)
            self._seen = max([self._seen] + [v for _, v in changed])
            for key, v in changed:
                c = self.chunks.get(key)
                if c is None or self.fver.get(key) == v or key in self._saving:
                    continue
                try:
                    blocks, data, _, v = self.file.fetch(key)
                except CorruptChunk as e:
                    self._report_corrupt(key, str(e))
                    continue
                if blocks is None:
                    continue  # deleted (recreate): this copy stays
                for (x, y, z), (b, d) in self._mine.get(key, {}).items():
                    data = C.put(blocks, data, x & 15, y & 15, z, b, d)
                c.blocks, c.data, c.light, c.mesh = blocks, data, None, None
                c.dirty = key in self._mine
                self.fver[key] = v
                self.bver[key] = self.tick()
                self.drop_light(key)
                out.add(key)
        return out

    def generate_area(self, keys, progress=None) -> int:
        """Generate and store every key not yet in the file; returns how many were new.

        Streams in batches straight to the file (nothing stays resident), each batch
        one transaction, so an interrupted run keeps what it finished; a chunk
        another writer stored meanwhile is kept as it is.
        """
        self.writable()
        have = set(self.file.chunk_keys())
        todo = [k for k in keys if k not in have and k not in self.chunks]
        done = 0
        for i in range(0, len(todo), BATCH):
            batch = todo[i:i + BATCH]
            with self._gen_lock:
                arrays = self.generator.generate(batch)
            rows = [self.file.encode_chunk(key, *self.apply_stored_edits(key, blocks))
                    for key, blocks in zip(batch, arrays)]
            by = {(r[0], r[1]): r for r in rows}
            self.file.save(rows, resolve=lambda k, v: None if self.file.has_chunk(k) else by[k])
            done += len(batch)
            if progress:
                progress(done, len(todo))
        return len(todo)

    def store_chunks(self, items, *, replace: bool = True, since: float | None = None) -> list:
        """Write whole chunks ((key, blocks, data-or-None) triples: an import) in one
        transaction; the stored light of their 3x3 is dropped, active copies show
        them (a live view too). Decided per chunk inside the transaction (another
        writer may have stored it meanwhile): without `replace` a chunk the file
        holds is kept; with it the chunk is written, and edits saved since time
        `since` (made while the import ran, by any process) are applied again over
        it. This session's own unsaved changes stay on top. Returns the keys kept."""
        items = {tuple(k): (b, d) for k, b, d in items}
        rows = [self.file.encode_chunk(k, b, d) for k, (b, d) in items.items()]
        return self.store_rows(rows, items, replace=replace, since=since)

    def store_rows(self, rows, items=None, *, replace: bool = True,
                   since: float | None = None, also=None) -> list:
        """store_chunks for rows encoded elsewhere (WorldFile.encoder: a cluster
        worker), decided the same way; `items` {key: (blocks, data)} their arrays
        when at hand, else a row is decoded only where arrays are needed (edits to
        apply again, an active copy); `also`: WorldFile.save's. Returns the keys kept."""
        self.writable()
        rows = {(int(r[0]), int(r[1])): r for r in rows}
        arrays = dict(items or {})
        stale = {(k[0] + i, k[1] + j) for k in rows for i in (-1, 0, 1) for j in (-1, 0, 1)}
        kept, final = [], {}

        def of(key):
            got = arrays.get(key)
            if got is None:
                got = arrays[key] = self.file.decode_row(rows[key])
            return got

        def resolve(key, version):
            if not replace and self.file.has_chunk(key):
                kept.append(key)
                return None
            later = self.file.edits_in(key, since) if replace and since is not None else ()
            if not later:
                final[key] = None  # the row's own arrays (decoded when needed)
                return rows[key]
            b, d = of(key)
            b, d = b.copy(order="F"), None if d is None else d.copy(order="F")
            for x, y, z, bid, v in later:
                d = C.put(b, d, x & 15, y & 15, z, bid, v)
            final[key] = (b, d)
            return self.file.encode_chunk(key, b, d)

        with self._flush_lock:
            new = self.file.save(list(rows.values()), stale_light=stale, resolve=resolve,
                                 also=also)
            with self._lock:
                for k, got in final.items():
                    mine = self._mine.get(k)
                    if not mine:  # an own snapshot would be merged over the import anyway
                        self._saving.pop(k, None)
                    self.corrupt.pop(k, None)
                    c = self.chunks.get(k)
                    if c is not None:
                        b, d = got or of(k)
                        b, d = b.copy(order="F"), None if d is None else d.copy(order="F")
                        for (x, y, z), (bid, v) in (mine or {}).items():
                            d = C.put(b, d, x & 15, y & 15, z, bid, v)
                        c.blocks, c.data, c.dirty = b, d, bool(mine)
                    if c is not None or k in self._saving:
                        self.fver[k] = new[k]
                    self.blocks_changed(k, {}, edits=False)
                self._stale -= stale  # the file's light rows are gone already
        return kept
