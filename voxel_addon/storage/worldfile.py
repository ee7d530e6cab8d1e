"""One world = one SQLite file (SPEC §3).

Block ids in the file are the file's own (table `block_types`); they are translated
to and from the running registry's ids here, so nothing above storage ever sees
file ids. Every write is one transaction (WAL journal), so a killed writer leaves
the last committed state: a chunk row is either the old blob or the new one.

Several writers (two Blenders, Blender and a command-line import): triggers number
every write of a chunk row in `chunk_versions` (a file-wide sequence, whoever
writes, older versions of this program included), so a writer can tell inside its
write transaction whether the row changed since it read it (`save(resolve=...)`: one
indexed lookup per chunk), and a reader can list what others wrote since a version
it saw (`versions_since`, polled when `data_changed()`). The file's identity (device,
inode) is kept when it opens: a file deleted or moved away while open fails the next
write with a VoxelError instead of writing into a file nobody will see.
"""
from __future__ import annotations

import functools
import json
import sqlite3
import sys
import threading
import time
from itertools import chain
from pathlib import Path

import numpy as np

from ..core import chunk as C
from ..core.errors import VoxelError
from . import codecs
from .decode import CorruptChunk, Decoding
from .meta import Meta, MetaMoved
from .opening import Opening, wal
from .rows import Encoder
from .schema import lock_timeout, open_error
from .transactions import Reading, Transaction

_R = C.REACH // C.SIZE
# a chunk row keyed by whole numbers inside the world (chunk_keys)
_KEYED = (f"typeof(cx) = 'integer' AND typeof(cy) = 'integer' AND cx BETWEEN {-_R} AND {_R - 1} "
          f"AND cy BETWEEN {-_R} AND {_R - 1}")
_MANY = 64  # keys per statement of a batch read (128 parameters: any SQLite's limit)
_READ_MANY = ("SELECT k.column1, k.column2, c.codec, c.blocks, c.data FROM {k} k "
              "LEFT JOIN chunks c ON c.cx = k.column1 AND c.cy = k.column2")
# a batch that is every chunk of a box (columns cx, one run of cy): an index range per
# column. A VALUES table of 32 keys costs SQLite ~300k instructions to compile, once
# per connection and batch size (~30 us warm, more on a cold pass); this ~1/3 of it,
# and it runs ~8 % faster (issue 29)
_BOX = "SELECT cx, cy, codec, blocks, data FROM chunks WHERE cx IN ({xs}) AND cy BETWEEN ? AND ?"


@functools.lru_cache(maxsize=256)
def _sql(template: str, n: int) -> str:
    """TEMPLATE with {k} as a table of n bound keys (columns column1, column2: cx,
    cy, as SQLite names a VALUES table's); n = 0: of one, bound as (cx, cy)."""
    if n == 0:
        return template.format(k="(SELECT ? AS column1, ? AS column2)")
    return template.format(k="(VALUES " + ", ".join(["(?, ?)"] * n) + ")")


@functools.lru_cache(maxsize=_MANY)
def _box_sql(n: int) -> str:
    return _BOX.format(xs=", ".join("?" * n))


_NONE = (None,) * 5  # read_many's row of a chunk the file does not have
_ZYX, _refs = (C.HEIGHT, C.SIZE, C.SIZE), sys.getrefcount  # read_many's arrays


def check_path(path, exists: bool = True) -> None:
    """A one-line VoxelError when PATH can hold no world file (a folder, a pipe or
    device, a link to nothing or a loop of links) or, with EXISTS, holds none: what
    is there said in words ('no world file' for a pipe or a dangling link misled)."""
    import os
    p = Path(path)
    if p.is_dir():
        raise VoxelError(f"{p} is a folder, not a world file")
    if p.is_file():
        return
    if p.is_symlink():
        raise VoxelError(f"{p} is a symbolic link to nothing (or a loop of links), "
                         "not a world file")
    if os.path.lexists(p):
        raise VoxelError(f"{p} is a pipe, a device or a socket, not a world file")
    if exists:
        raise VoxelError(f"no world file at {p}")


class WorldFile(Decoding, Opening, Meta):
    """A world file opened for reading (and writing unless `readonly`). `created`:
    this object made the file (create), so a command that fails may remove it."""

    def __init__(self, path, *, readonly: bool = False, _create: dict | None = None):
        self.path = Path(path)
        self.readonly = readonly
        self._lock = threading.RLock()
        self._identity_at_open = None
        self._cursor = None  # read_chunk's
        self._staged: dict[str, str] = {}  # meta values written by the next save
        self._bases: dict[str, str | None] = {}  # what a staged value was built on
        self.db = None
        self.created = False
        check_path(self.path, exists=_create is None)
        if _create is not None:
            self._make(_create)
            self.created = True
        try:
            self._open(readonly)
        except BaseException:
            if self.created:  # made here, refused on opening (a full disk): not left behind
                self._unmake()
            raise

    def _open(self, readonly: bool) -> None:
        try:
            if readonly:
                # as_uri escapes what a URI would misread (#, ?, %, spaces) and spells
                # Windows paths file:///C:/...
                uri = self.path.resolve().as_uri() + "?mode=ro"
                self.db = sqlite3.connect(uri, uri=True, check_same_thread=False)
            else:
                self.db = sqlite3.connect(self.path, check_same_thread=False,
                                          timeout=lock_timeout())
            self.db.isolation_level = None  # explicit BEGIN/COMMIT below
            self._identity_at_open = self._stat()
            # Read before any pragma that writes, so a foreign file is never touched.
            self.meta = dict(self.db.execute("SELECT key, value FROM meta"))
            file_names = dict(self.db.execute("SELECT id, name FROM block_types"))
            tables = {r[0] for r in self.db.execute(
                "SELECT name FROM sqlite_master WHERE type='table'")}
            self.db.execute("PRAGMA synchronous=NORMAL")
        except sqlite3.DatabaseError as e:
            if self.db is not None:
                self.db.close()
            raise open_error(self.path, e) from None
        try:
            self._check_version()
            if "chunks" not in tables:  # another program's file: refused before any write
                raise VoxelError(f"{self.path} is not a Voxel Worlds file (it has no "
                                 "chunks table)")
            if not self._chunks_keyed():  # every write would add a row, reads pick one
                raise VoxelError(f"{self.path} is not a readable world file (its chunks "
                                 "table has no key on cx, cy)")
            if not readonly:  # files made by other programs or versions: rollback mode
                wal(self.db, lock_timeout())
            self._map_ids(file_names)
            self._edits_table(readonly, tables)
            self._light_table(readonly)
            self._version_table(readonly)
        except BaseException:
            self.db.close()  # no handle on a file it refused (Blender goes on running)
            raise
        # {k}: the keys' table (column1, column2 = cx, cy): one key or many (_sql)
        self._fetch_sql = (
            "SELECT k.column1, k.column2, {v}, c.codec, c.blocks, c.data, {l} FROM {{k}} k "
            "LEFT JOIN chunks c ON c.cx = k.column1 AND c.cy = k.column2 {vj} {lj}").format(
            v="COALESCE(v.v, 0)" if self._has_versions else "0",
            vj="LEFT JOIN chunk_versions v ON v.cx = k.column1 AND v.cy = k.column2"
            if self._has_versions else "",
            l="l.codec, l.light" if self._has_light else "NULL, NULL",
            lj="LEFT JOIN light l ON l.cx = k.column1 AND l.cy = k.column2"
            if self._has_light else "")

    # ---- creation and checks -------------------------------------------------
    def _chunks_keyed(self) -> bool:
        """Whether the chunks table holds one row per (cx, cy) (SPEC: its primary
        key; a unique index another program made counts too)."""
        for _, name, unique, *_ in self.db.execute("PRAGMA index_list(chunks)").fetchall():
            quoted = name.replace('"', '""')
            cols = {r[2] for r in self.db.execute(f'PRAGMA index_info("{quoted}")')}
            if unique and cols == {"cx", "cy"}:
                return True
        return False

    @classmethod
    def create(cls, path, *, seed: int, generator: str, generator_version: int,
               params: dict | None = None) -> "WorldFile":
        return cls(path, _create={"seed": str(int(seed)), "generator": generator,
                                  "generator_version": str(generator_version),
                                  "generator_params": json.dumps(params or {}, sort_keys=True)})

    # ---- transactions, queries for the file's other tables (far.py) ----------
    def transaction(self):
        """`with wf.transaction() as db:` one write transaction (BEGIN IMMEDIATE: no
        other process writes until it ends), under the file's lock."""
        return Transaction(self)

    def reading(self):
        """`with wf.reading():` a burst of reads (read_chunk, fetch, ...) as one read
        transaction, at one instant, under the file's lock: SQLite otherwise takes
        and drops its shared lock for every statement, half the SQL time of a chunk
        read. Keep it short (this file's writers wait for the lock; other processes
        write on, unseen until it ends); no writes inside. Nests, also inside a
        transaction (then it adds nothing)."""
        return Reading(self)

    def locked(self):
        """The file's lock (re-entrant): hold it around reads and writes that must
        see no other thread's write in between."""
        return self._lock

    def query(self, sql: str, args=()) -> list:
        """Rows of one read statement, under the file's lock."""
        with self._lock:
            return self.db.execute(sql, tuple(args)).fetchall()

    @property
    def file_ids(self) -> np.ndarray:
        """Lookup table registry id -> the file's block id (read it, never change it)."""
        return self._to_file

    @property
    def registry_ids(self) -> np.ndarray:
        """Lookup table file block id -> registry id (its length bounds file ids)."""
        return self._to_reg

    def _writable(self) -> None:
        if self.readonly:
            raise VoxelError(f"{self.path} is open read-only")

    # ---- chunks -----------------------------------------------------------
    def chunk_keys(self) -> list[tuple[int, int]]:
        """Keys of the stored chunks; rows keyed outside the world or by no whole
        numbers (a hostile file: text, reals) are left out, as they are when read."""
        with self._lock:
            return [tuple(r) for r in self.db.execute(f"SELECT cx, cy FROM chunks WHERE {_KEYED}")]

    def chunk_count(self) -> int:
        with self._lock:
            return self.db.execute(f"SELECT COUNT(*) FROM chunks WHERE {_KEYED}").fetchone()[0]

    def has_chunk(self, key) -> bool:
        with self._lock:
            return self.db.execute("SELECT 1 FROM chunks WHERE cx=? AND cy=?",
                                   tuple(key)).fetchone() is not None

    def read_chunk(self, key, light: bool = False):
        """(blocks, data-or-None) in registry ids, or None when the chunk is absent;
        with light=True (blocks, data, light-or-None)."""
        with self._lock:  # one cursor for these reads (the lock orders them): not one each
            cur = self._cursor
            if cur is None:
                cur = self._cursor = self.db.cursor()
            row = cur.execute("SELECT codec, blocks, data FROM chunks WHERE cx=? AND cy=?",
                              tuple(key)).fetchone()
            lrow = self.db.execute("SELECT codec, light FROM light WHERE cx=? AND cy=?",
                                   tuple(key)).fetchone() if light and self._has_light else None
        if row is None:
            return None
        blocks, data = self._decode(key, *row)
        if not light:
            return blocks, data
        return blocks, data, None if lrow is None else self._decode_light(*lrow)

    def fetch(self, key):
        """(blocks, data, light, version) of chunk `key` read at one instant (one
        statement): blocks None when the file has no such chunk; version: the
        chunk's number in chunk_versions (0: never written since versions exist).
        Light is None when missing or damaged; a damaged chunk raises CorruptChunk."""
        with self._lock:
            row = self.db.execute(_sql(self._fetch_sql, 0), tuple(key)).fetchone()
        return self._fetched(key, row)

    def fetch_many(self, keys, packed: bool = False) -> dict:
        """{key: fetch(key)} of `keys` read at one instant (one read transaction),
        a damaged chunk's CorruptChunk in place of its tuple; decoded outside the
        file's lock, so other threads' reads and writes wait only for the SQL.
        PACKED: blocks that need no mapping come as a core.chunk.Packed frame of
        the stored blob (checked by a decode into this thread's scratch, not kept):
        what a world keeps in memory, with no array made and packed; light as
        (array, its frame) (Chunk.light_read). Keys: (cx, cy) tuples of ints."""
        keys = list(keys)
        rows = self._rows(self._fetch_sql, keys)
        out = {}
        for k in keys:
            try:
                out[k] = self._fetched(k, rows[k], packed)
            except CorruptChunk as e:
                out[k] = e
        return out

    def read_many(self, keys):
        """(key, read_chunk(key)) of each of `keys`, a damaged chunk's CorruptChunk in
        place of its pair: the rows read at one instant (a statement per 64 keys: one
        per chunk cost ~1-2 of a read's ~20 us, issue 29), each decoded only when the
        loop asks for it (32 fresh 128 KB arrays kept cost page faults, ~4x the
        read). A chunk decodes into the array of the one before the last when the
        caller let that go (nothing but this loop holds it: its refcount), else into
        a new one: an array kept is never written again. Keys: (cx, cy) tuples of ints."""
        keys = list(keys)
        rows = self._box_rows(keys)
        if rows is None:
            rows = self._rows(_READ_MANY, keys)
        decode, ring, i, free = self._decode, [None, None], 0, 0
        for k in keys:
            _, _, codec, blob, dblob = rows.get(k, _NONE)
            if codec is None:
                yield k, None
                continue
            buf = ring[i]  # let go: counted as when only ring and buf held it
            if buf is None or _refs(buf) > free:
                buf = ring[i] = np.empty(_ZYX, np.uint16)
                free = _refs(buf)  # measured, not assumed (interpreters count apart)
            i ^= 1
            try:
                got = decode(k, codec, blob, dblob, out=buf)
            except CorruptChunk as e:
                got = e
            yield k, got

    def _box_rows(self, keys: list) -> dict | None:
        """{(cx, cy): row} of read_many's keys when they are each chunk of a box
        once (columns xs, rows y0..y1), read by one statement; None otherwise."""
        xs, ys = {k[0] for k in keys}, {k[1] for k in keys}
        if not 0 < len(xs) <= _MANY or len(xs) * len(ys) != len(keys) \
                or max(ys) - min(ys) + 1 != len(ys) or len(set(keys)) != len(keys):
            return None
        with self._lock:
            return {(r[0], r[1]): r for r in self.db.execute(
                _box_sql(len(xs)), (*xs, min(ys), max(ys)))}

    def _rows(self, template: str, keys: list) -> dict:
        """{(cx, cy): its row (cx, cy first)} of TEMPLATE's statement for every key,
        read at one instant, a statement per _MANY keys."""
        got = {}
        parts = [keys[i:i + _MANY] for i in range(0, len(keys), _MANY)]
        # one statement reads at one instant by itself (BEGIN and END cost more)
        with self.reading() if len(parts) > 1 else self._lock:
            for part in parts:
                for row in self.db.execute(_sql(template, len(part)),
                                           list(chain.from_iterable(part))):
                    got[row[0], row[1]] = row
        return got

    def version(self, key) -> int:
        """The stored version of chunk `key` (0: never written since versions exist)."""
        if not self._has_versions:
            return 0
        with self._lock:
            row = self.db.execute("SELECT v FROM chunk_versions WHERE cx=? AND cy=?",
                                  tuple(key)).fetchone()
        return 0 if row is None else row[0]

    def top_version(self) -> int:
        """The newest chunk version in the file (versions only grow)."""
        if not self._has_versions:
            return 0
        with self._lock:
            return self.db.execute("SELECT COALESCE(MAX(v), 0) FROM chunk_versions"
                                   ).fetchone()[0]

    def versions_since(self, v: int) -> list[tuple[tuple[int, int], int]]:
        """((cx, cy), version) of every chunk written or deleted after version v."""
        if not self._has_versions:
            return []
        with self._lock:
            return [((cx, cy), w) for cx, cy, w in self.db.execute(
                "SELECT cx, cy, v FROM chunk_versions WHERE v > ?", (v,))]

    def data_changed(self) -> bool:
        """Whether another connection (another process) committed a change since the
        last call (SQLite's data_version: cheap, no file read)."""
        with self._lock:
            if self.db is None:
                return False
            v = self.db.execute("PRAGMA data_version").fetchone()[0]
        old, self._data_version = getattr(self, "_data_version", v), v
        return v != old

    def encode_chunk(self, key, blocks, data=None, codec: str | None = None,
                     light=None) -> tuple:
        """A ready-to-write row; thread-safe, so callers can encode outside locks.
        `light` only when it is the chunk's final light (see the schema)."""
        return self.encoder(codec).row(key, blocks, data, light)

    def encoder(self, codec: str | None = None) -> "Encoder":
        """encode_chunk without the file: picklable, so other processes (cluster
        workers) make the very rows this file would."""
        return Encoder(codec or codecs.default(), None if self._identity else self._to_file)

    def save(self, rows=(), edits=(), stale_light=(), resolve=None, also=None) -> dict:
        """Encoded chunk rows (from encode_chunk) and (x, y, z, block, data) edits in
        registry ids, written in one transaction: after it returns they survive a kill.
        A row's light (its 6th value) replaces the stored one, None drops it;
        `stale_light`: keys whose stored light no longer holds (dropped too).

        `resolve(key, version)`, when given, is called inside the transaction (the
        file is locked for writing: nobody writes meanwhile) with the stored version
        of each row's chunk and returns the row to write: the same, another one (a
        merge: read the stored chunk with read_chunk, encode the result; the light of
        its 3x3 is dropped) or None (keep the stored one). Returns {key: version} of
        the rows written. `also(db, keys written)`: more writes of the same
        transaction, after the rows (an import's biome rows and resume note: a kill
        leaves all of them or none)."""
        with self.transaction() as db:
            stale_light = [tuple(k) for k in stale_light]
            if resolve is not None:
                out = []
                for r in rows:
                    key = (r[0], r[1])
                    got = resolve(key, self.version(key))
                    if got is not None and got is not r:  # merged: its 3x3's light is off
                        stale_light += [(key[0] + i, key[1] + j)
                                        for i in (-1, 0, 1) for j in (-1, 0, 1)]
                    if got is not None:
                        out.append(got)
                rows = out
            top = self.top_version()
            staged = dict(self._staged)
            moved = self._moved_meta()
            if moved:
                raise MetaMoved(f"{self.path}: another program changed {', '.join(moved)} "
                                "meanwhile; nothing was written")
            self.db.executemany("INSERT OR REPLACE INTO meta VALUES (?, ?)", staged.items())
            self.db.executemany("INSERT OR REPLACE INTO chunks VALUES (?, ?, ?, ?, ?)",
                                [r[:5] for r in rows])
            self.db.executemany("INSERT OR REPLACE INTO light VALUES (?, ?, ?, ?)",
                                [r[:3] + r[5:] for r in rows if r[5] is not None])
            self.db.executemany("DELETE FROM light WHERE cx=? AND cy=?",
                                [r[:2] for r in rows if r[5] is None] + stale_light)
            written = {(r[0], r[1]) for r in rows}
            now = time.time()
            self.db.executemany("INSERT OR REPLACE INTO edits VALUES (?, ?, ?, ?, ?, ?)",
                                [(x, y, z, int(self._to_file[b]), d, now)
                                 for x, y, z, b, d in edits])
            if also is not None:
                also(db, written)
            new = {k: v for k, v in self.versions_since(top) if k in written}
        with self._lock:
            for k, v in staged.items():  # written: unless staged again meanwhile
                if self._staged.get(k) == v:
                    del self._staged[k]
                    self._bases.pop(k, None)
        return new

    def write_chunks(self, items, codec: str | None = None) -> None:
        """items: (key, blocks, data-or-None) triples."""
        self.save([self.encode_chunk(k, b, d, codec) for k, b, d in items])

    def delete_chunks(self) -> int:
        """Drop every generated chunk (edits stay); used to regenerate a world."""
        self._writable()
        with self.transaction():
            self.db.execute("DELETE FROM light")
            return self.db.execute("DELETE FROM chunks").rowcount

    # ---- edits ------------------------------------------------------------
    def edits_in(self, key, since: float | None = None) -> list[tuple[int, int, int, int, int]]:
        """(x, y, z, block, data) edits inside chunk `key`, in registry ids (those
        saved at or after time `since` only, when given), oldest first."""
        x0, y0 = key[0] * C.SIZE, key[1] * C.SIZE
        with self._lock:  # rows outside the world's ranges (a hostile file) are left out
            rows = self.db.execute(
                "SELECT x, y, z, block, data FROM edits WHERE x>=? AND x<? AND y>=? AND y<? "
                "AND z>=0 AND z<? AND data>=0 AND data<=65535 AND t>=? ORDER BY t",
                (x0, x0 + C.SIZE, y0, y0 + C.SIZE, C.HEIGHT,
                 float("-inf") if since is None else since)).fetchall()
        return [(x, y, z, int(self._to_reg[b]) if 0 <= b < len(self._to_reg) else 0, d)
                for x, y, z, b, d in rows]

    def edits_box(self, x0, y0, x1, y1) -> np.ndarray:
        """(x, y, z, block) of the edits in columns [x0, x1) x [y0, y1) as an (n, 4)
        array in registry ids (rows with block ids outside the file's table left out)."""
        rows = self.query("SELECT x, y, z, block FROM edits WHERE x>=? AND x<? AND y>=? AND y<?",
                          (x0, x1, y0, y1))
        a = np.array(rows, np.int64).reshape(-1, 4)
        a = a[(a[:, 3] >= 0) & (a[:, 3] < len(self._to_reg))]
        a[:, 3] = self._to_reg[a[:, 3]]
        return a

    def chunks_in(self, cx0, cy0, cx1, cy1) -> set:
        """Keys of the stored chunks in [cx0, cx1] x [cy0, cy1]."""
        return {tuple(r) for r in self.query(
            f"SELECT cx, cy FROM chunks WHERE cx BETWEEN ? AND ? AND cy BETWEEN ? AND ? AND {_KEYED}",
            (cx0, cx1, cy0, cy1))}

    def edit_count(self) -> int:
        with self._lock:
            return self.db.execute("SELECT COUNT(*) FROM edits").fetchone()[0]

    def clear_edits(self) -> None:
        self._writable()
        with self.transaction():
            self.db.execute("DELETE FROM edits")

    def close(self) -> None:
        with self._lock:
            if self.db is not None:
                if not self.readonly and self.gone():
                    # SQLite leaves the -wal of a moved file when it closes: the file
                    # put at the path (or a New world there) would read our pages as
                    # its own. Emptied into our own (old) file first, it is harmless.
                    try:
                        self.db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
                    except sqlite3.Error:
                        pass
                self.db.close()
                self.db = self._cursor = None
