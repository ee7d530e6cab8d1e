"""One world = one SQLite file (SPEC §3).

Block ids in the file are the file's own (table `block_types`); they are translated
to and from the running registry's ids here, so nothing above storage ever sees
file ids. Every write is one transaction (WAL journal), so a killed writer leaves
the last committed state: a chunk row is either the old blob or the new one.
"""
from __future__ import annotations

import json
import sqlite3
import threading
import time
from pathlib import Path

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError
from . import codecs

FORMAT_VERSION = 1
APP_ID = 0x564F5857  # "VOXW": marks our files in the SQLite header

LIGHT_TABLE = """CREATE TABLE IF NOT EXISTS light(cx INTEGER, cy INTEGER, codec TEXT NOT NULL,
    light BLOB NOT NULL, PRIMARY KEY (cx, cy))"""
SCHEMA = f"""
CREATE TABLE IF NOT EXISTS meta(key TEXT PRIMARY KEY, value TEXT);
CREATE TABLE IF NOT EXISTS block_types(id INTEGER PRIMARY KEY, name TEXT UNIQUE NOT NULL);
CREATE TABLE IF NOT EXISTS chunks(cx INTEGER, cy INTEGER, codec TEXT NOT NULL,
    blocks BLOB NOT NULL, data BLOB, PRIMARY KEY (cx, cy));
-- A chunk's final light when it was saved, packed as SPEC 3 in linear order. Derived
-- data, kept apart from the chunks table of SPEC 3: a row is dropped whenever its
-- chunk is written without light or a block in its 3x3 changes, and a missing or
-- damaged one is only computed again (saves the light solve when reloading).
{LIGHT_TABLE};
-- The user's own changes, kept apart so a world can be regenerated with them.
CREATE TABLE IF NOT EXISTS edits(x INTEGER, y INTEGER, z INTEGER, block INTEGER NOT NULL,
    data INTEGER NOT NULL DEFAULT 0, t REAL NOT NULL, PRIMARY KEY (x, y, z));
"""


class CorruptChunk(VoxelError):
    """A chunk row that cannot be decoded; it is left as it is in the file."""


class WorldFile:
    """A world file opened for reading (and writing unless `readonly`)."""

    def __init__(self, path, *, readonly: bool = False, _create: dict | None = None):
        self.path = Path(path)
        self.readonly = readonly
        self._lock = threading.RLock()
        if _create is None and not self.path.is_file():
            raise VoxelError(f"no world file at {self.path}")
        if _create is not None and self.path.exists():
            raise VoxelError(f"{self.path} already exists")
        try:
            if readonly:
                # as_uri escapes what a URI would misread (#, ?, %, spaces) and spells
                # Windows paths file:///C:/...
                uri = self.path.resolve().as_uri() + "?mode=ro"
                self.db = sqlite3.connect(uri, uri=True, check_same_thread=False)
            else:
                self.db = sqlite3.connect(self.path, check_same_thread=False, timeout=30)
            self.db.isolation_level = None  # explicit BEGIN/COMMIT below
            if _create is not None:
                self._init(_create)
            # Read before any pragma that writes, so a foreign file is never touched.
            self.meta = dict(self.db.execute("SELECT key, value FROM meta"))
            file_names = dict(self.db.execute("SELECT id, name FROM block_types"))
            self.db.execute("PRAGMA synchronous=NORMAL")
        except sqlite3.DatabaseError as e:
            raise VoxelError(f"{self.path} is not a readable world file ({e})") from None
        self._check_version()
        if not readonly and _create is None:
            self.db.execute("PRAGMA journal_mode=WAL")
        self._map_ids(file_names)
        self._light_table(readonly)

    # ---- creation and checks -------------------------------------------------
    @classmethod
    def create(cls, path, *, seed: int, generator: str, generator_version: int,
               params: dict | None = None) -> "WorldFile":
        return cls(path, _create={"seed": str(int(seed)), "generator": generator,
                                  "generator_version": str(generator_version),
                                  "generator_params": json.dumps(params or {}, sort_keys=True)})

    def _init(self, meta: dict) -> None:
        db = self.db
        db.execute(f"PRAGMA application_id={APP_ID}")
        db.execute("PRAGMA journal_mode=WAL")
        db.execute("BEGIN")
        for statement in SCHEMA.split(";"):
            if statement.strip():
                db.execute(statement)
        rows = {"format_version": str(FORMAT_VERSION), "created": time.strftime("%Y-%m-%dT%H:%M:%S"),
                **meta}
        db.executemany("INSERT INTO meta VALUES (?, ?)", rows.items())
        db.executemany("INSERT INTO block_types VALUES (?, ?)", enumerate(REGISTRY.names()))
        db.execute("COMMIT")

    def _check_version(self) -> None:
        v = self.meta.get("format_version")
        if v is None or not v.isdigit():
            raise VoxelError(f"{self.path} is not a Voxel Worlds file (no format_version)")
        if int(v) > FORMAT_VERSION:
            raise VoxelError(f"{self.path} has format {v}, newer than this version "
                             f"understands ({FORMAT_VERSION}); please update Voxel Worlds")

    def _map_ids(self, file_names: dict[int, str]) -> None:
        """Lookup tables file id <-> registry id; new registry blocks get file ids."""
        names = REGISTRY.names()
        bad = [i for i in file_names if not 0 <= i <= 0xFFFF]
        if bad:  # block ids are uint16: a larger one would size the lookup table
            raise VoxelError(f"{self.path} has block type id {bad[0]} outside 0..65535; "
                             "it is not a readable world file")
        unknown = [n for n in file_names.values() if n not in names]
        if unknown:
            raise VoxelError(f"{self.path} uses block types this version does not know: "
                             f"{', '.join(sorted(unknown))}")
        missing = [n for n in names if n not in file_names.values()]
        if missing and not self.readonly:
            start = max(file_names, default=-1) + 1
            with self.transaction():
                for i, n in enumerate(missing, start):
                    self.db.execute("INSERT INTO block_types VALUES (?, ?)", (i, n))
                    file_names[i] = n
        size = max(file_names, default=0) + 1
        self._to_reg = np.zeros(max(size, 1), np.uint16)
        self._to_file = np.zeros(len(names), np.uint16)
        for fid, n in file_names.items():
            self._to_reg[fid] = REGISTRY.id(n)
            self._to_file[REGISTRY.id(n)] = fid
        for n in missing if self.readonly else ():  # never written back: map to air
            self._to_file[REGISTRY.id(n)] = 0
        self._identity = all(self._to_reg[i] == i for i in file_names) and \
            len(file_names) == len(names)

    def _light_table(self, readonly: bool) -> None:
        """Files written before the light table get it (empty: light is recomputed)."""
        self._has_light = self.db.execute("SELECT 1 FROM sqlite_master WHERE type='table' "
                                          "AND name='light'").fetchone() is not None
        if not self._has_light and not readonly:
            with self.transaction():
                self.db.execute(LIGHT_TABLE)
            self._has_light = True

    # ---- properties -------------------------------------------------------
    @property
    def seed(self) -> int:
        return int(self.meta["seed"])

    @property
    def generator(self) -> str:
        return self.meta["generator"]

    @property
    def generator_params(self) -> dict:
        return json.loads(self.meta.get("generator_params") or "{}")

    def set_meta(self, key: str, value: str) -> None:
        with self.transaction():
            self.db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)", (key, str(value)))
        self.meta[key] = str(value)

    # ---- transactions -----------------------------------------------------
    def transaction(self):
        return _Transaction(self)

    def _writable(self) -> None:
        if self.readonly:
            raise VoxelError(f"{self.path} is open read-only")

    # ---- chunks -----------------------------------------------------------
    def chunk_keys(self) -> list[tuple[int, int]]:
        with self._lock:
            return [tuple(r) for r in self.db.execute("SELECT cx, cy FROM chunks")]

    def chunk_count(self) -> int:
        with self._lock:
            return self.db.execute("SELECT COUNT(*) FROM chunks").fetchone()[0]

    def has_chunk(self, key) -> bool:
        with self._lock:
            return self.db.execute("SELECT 1 FROM chunks WHERE cx=? AND cy=?",
                                   tuple(key)).fetchone() is not None

    def read_chunk(self, key, light: bool = False):
        """(blocks, data-or-None) in registry ids, or None when the chunk is absent;
        with light=True (blocks, data, light-or-None)."""
        with self._lock:
            row = self.db.execute("SELECT codec, blocks, data FROM chunks WHERE cx=? AND cy=?",
                                  tuple(key)).fetchone()
            lrow = self.db.execute("SELECT codec, light FROM light WHERE cx=? AND cy=?",
                                   tuple(key)).fetchone() if light and self._has_light else None
        if row is None:
            return None
        codec, blob, dblob = row
        try:
            blocks = C.from_linear(codecs.decode(codec, blob, C.VOLUME * 2)).copy(order="F")
            data = None if dblob is None else \
                C.from_linear(codecs.decode(codec, dblob, C.VOLUME * 2)).copy(order="F")
        except ValueError as e:
            raise CorruptChunk(f"chunk ({key[0]}, {key[1]}) in {self.path} is damaged ({e}); "
                               "it was left untouched") from None
        if blocks.max() >= len(self._to_reg):  # checked always: tables are indexed by id
            raise CorruptChunk(f"chunk ({key[0]}, {key[1]}) in {self.path} has block ids "
                               "missing from block_types; it was left untouched")
        if not self._identity:
            blocks = self._to_reg[blocks]
        if not light:
            return blocks, data
        lit = None
        if lrow is not None:
            try:
                lit = C.from_linear(codecs.decode(lrow[0], lrow[1], C.VOLUME * 2)).copy(order="F")
            except (ValueError, VoxelError):  # derived data: recomputed, never a failure
                lit = None
        return blocks, data, lit

    def encode_chunk(self, key, blocks, data=None, codec: str | None = None,
                     light=None) -> tuple:
        """A ready-to-write row; thread-safe, so callers can encode outside locks.
        `light` only when it is the chunk's final light (see the schema)."""
        return self.encoder(codec).row(key, blocks, data, light)

    def encoder(self, codec: str | None = None) -> "Encoder":
        """encode_chunk without the file: picklable, so other processes (cluster
        workers) make the very rows this file would."""
        return Encoder(codec or codecs.default(), None if self._identity else self._to_file)

    def save(self, rows=(), edits=(), stale_light=()) -> None:
        """Encoded chunk rows (from encode_chunk) and (x, y, z, block, data) edits in
        registry ids, written in one transaction: after it returns they survive a kill.
        A row's light (its 6th value) replaces the stored one, None drops it;
        `stale_light`: keys whose stored light no longer holds (dropped too)."""
        with self.transaction():
            self.db.executemany("INSERT OR REPLACE INTO chunks VALUES (?, ?, ?, ?, ?)",
                                [r[:5] for r in rows])
            self.db.executemany("INSERT OR REPLACE INTO light VALUES (?, ?, ?, ?)",
                                [r[:3] + r[5:] for r in rows if r[5] is not None])
            self.db.executemany("DELETE FROM light WHERE cx=? AND cy=?",
                                [r[:2] for r in rows if r[5] is None]
                                + [tuple(k) for k in stale_light])
            now = time.time()
            self.db.executemany("INSERT OR REPLACE INTO edits VALUES (?, ?, ?, ?, ?, ?)",
                                [(x, y, z, int(self._to_file[b]), d, now)
                                 for x, y, z, b, d in edits])

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
    def edits_in(self, key) -> list[tuple[int, int, int, int, int]]:
        """(x, y, z, block, data) edits inside chunk `key`, in registry ids."""
        x0, y0 = key[0] * C.SIZE, key[1] * C.SIZE
        with self._lock:  # rows outside the world's ranges (a hostile file) are left out
            rows = self.db.execute(
                "SELECT x, y, z, block, data FROM edits WHERE x>=? AND x<? AND y>=? AND y<? "
                "AND z>=0 AND z<? AND data>=0 AND data<=65535",
                (x0, x0 + C.SIZE, y0, y0 + C.SIZE, C.HEIGHT)).fetchall()
        return [(x, y, z, int(self._to_reg[b]) if 0 <= b < len(self._to_reg) else 0, d)
                for x, y, z, b, d in rows]

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
                self.db.close()
                self.db = None


class Encoder:
    """Chunk rows in one file's block numbering (WorldFile.encoder)."""

    def __init__(self, codec: str, to_file=None):
        self.codec, self.to_file = codec, to_file  # to_file None: ids are the registry's

    def row(self, key, blocks, data=None, light=None) -> tuple:
        codec = self.codec
        ids = blocks if self.to_file is None else self.to_file[blocks]
        lblob = None if light is None else codecs.encode(codec, C.to_linear(light))
        return (int(key[0]), int(key[1]), codec, codecs.encode(codec, C.to_linear(ids)),
                self.data(data), lblob)

    def data(self, data):
        """A row's data blob (None when there are no data values)."""
        return None if data is None or not data.any() else \
            codecs.encode(self.codec, C.to_linear(data))


class _Transaction:
    """BEGIN IMMEDIATE … COMMIT under the file's lock; ROLLBACK on any error."""

    def __init__(self, wf: WorldFile):
        self.wf = wf

    def __enter__(self):
        self.wf._writable()
        self.wf._lock.acquire()
        self.wf.db.execute("BEGIN IMMEDIATE")
        return self.wf.db

    def __exit__(self, exc_type, exc, tb):
        db = self.wf.db
        try:
            if exc_type:
                db.execute("ROLLBACK")
            else:
                try:
                    db.execute("COMMIT")
                except sqlite3.Error:
                    # a COMMIT that failed (disk full, I/O error) can leave the
                    # transaction open: end it, so a later save can try again
                    if db.in_transaction:
                        db.execute("ROLLBACK")
                    raise
        finally:
            self.wf._lock.release()
        return False
