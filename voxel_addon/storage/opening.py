"""Opening a world file (storage/worldfile.py's mixin): a new file made whole under a
name of its own and linked into place, the format and block-type checks, the tables
older files lack added, and the file's identity (device, inode) that tells a file
deleted, moved or replaced while open."""
from __future__ import annotations

import glob
import os
import sqlite3
import threading
import time

import numpy as np

from ..core.blocks import REGISTRY
from ..core.errors import VoxelError, cause
from .schema import (APP_ID, EDITS_TABLE, FORMAT_VERSION, LIGHT_TABLE, SCHEMA,
                     VERSION_TABLE)


class Exists(VoxelError):
    """A new world's path is taken (by a file another process may have just made)."""


STALE_S = 600  # a new file is made in well under a second: older ones were left by a kill


def _sweep(path) -> None:
    """Remove what a creating process killed mid-way left beside `path` (its own-named
    new file, with -wal, -shm, -journal), once surely abandoned (by age: a process id
    cannot be checked safely on every platform)."""
    now = time.time()
    for p in path.parent.glob(f".{glob.escape(path.name)}.*.new*"):
        try:
            if now - p.stat().st_mtime > STALE_S:
                p.unlink()
        except OSError:  # gone meanwhile, or not ours to remove
            pass


def wal(db, timeout: float) -> None:
    """PRAGMA journal_mode=WAL, waiting out another opener's switch of the same file
    (an older file in rollback mode opened by two at once: one of them is refused at
    once, SQLite's busy handler does not wait on that lock)."""
    end = time.monotonic() + timeout
    while True:
        try:
            db.execute("PRAGMA journal_mode=WAL")
            return
        except sqlite3.OperationalError as e:
            if "locked" not in str(e) or time.monotonic() > end:
                raise
            time.sleep(0.02)


class Opening:
    """WorldFile's creation and checks; it needs `path`, `db`, `meta`, `readonly`,
    `transaction()` and `_identity_at_open` of WorldFile."""

    def _make(self, meta: dict) -> None:
        """Make the new file whole under a name of its own, then link it to `path`,
        which fails when a file is there: two processes creating one world at once
        (two generates, Blender and an import) never write into one half-made file,
        and the one that comes second finds a whole world (Exists)."""
        if self.path.exists():
            raise Exists(f"{self.path} already exists")
        _sweep(self.path)
        tmp = self.path.with_name(f".{self.path.name}.{os.getpid()}-{threading.get_ident()}.new")
        try:
            self.db = sqlite3.connect(tmp)
            self.db.isolation_level = None
            # in WAL mode before anyone sees it: switching a linked file's journal
            # takes an exclusive lock that a second opener of a new world met as
            # 'database is locked' (two creates at once, 1 round in ~25)
            self.db.execute("PRAGMA journal_mode=WAL")
            self._init(meta)
            self.db.close()  # the last connection: the WAL goes into the file
            self.db = None
            try:
                os.link(tmp, self.path)
            except FileExistsError:
                raise Exists(f"{self.path} already exists") from None
            except OSError:  # no hard links on this file system: a rename, checked first
                if self.path.exists():
                    raise Exists(f"{self.path} already exists") from None
                os.replace(tmp, self.path)
        except sqlite3.DatabaseError as e:
            what = cause(e, self.path)
            if what is None:
                raise
            raise VoxelError(f"{what} while creating {self.path}: nothing was made") from None
        finally:
            if self.db is not None:
                self.db.close()
                self.db = None
            for p in (tmp, *(tmp.with_name(tmp.name + s) for s in ("-wal", "-shm", "-journal"))):
                try:
                    p.unlink()
                except OSError:  # never made, or renamed into place
                    pass

    def _unmake(self) -> None:
        """Remove the file this object made (with its -wal and -shm), unless another
        file has taken its name since."""
        if self.db is not None:
            self.db.close()
            self.db = None
        if self._identity_at_open is not None and self._stat() != self._identity_at_open:
            return
        for p in (self.path, *(self.path.with_name(self.path.name + s)
                               for s in ("-wal", "-shm", "-journal"))):
            try:
                p.unlink()
            except OSError:
                pass

    def _init(self, meta: dict) -> None:
        db = self.db
        db.execute(f"PRAGMA application_id={APP_ID}")
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
        # ids below the largest with no name (a row deleted by another program): a
        # chunk using one is damaged, as one past the table (read as air, an edit
        # wrote the chunk back without them)
        named = np.zeros(len(self._to_reg), bool)
        named[list(file_names)] = True
        self._unnamed = None if named.all() else ~named
        self._identity = all(self._to_reg[i] == i for i in file_names) and \
            len(file_names) == len(names)

    def _edits_table(self, readonly: bool, tables: set) -> None:
        """A file another program wrote to SPEC 3 alone (meta, block_types, chunks)
        gets our edits table; read-only, an empty one of the session's own (TEMP:
        the file is not touched) stands in for it."""
        if "edits" in tables:
            return
        if readonly:
            self.db.execute(EDITS_TABLE.replace("CREATE TABLE", "CREATE TEMP TABLE"))
        else:
            with self.transaction():
                self.db.execute(EDITS_TABLE)

    def _light_table(self, readonly: bool) -> None:
        """Files written before the light table get it (empty: light is recomputed)."""
        self._has_light = self.db.execute("SELECT 1 FROM sqlite_master WHERE type='table' "
                                          "AND name='light'").fetchone() is not None
        if not self._has_light and not readonly:
            with self.transaction():
                self.db.execute(LIGHT_TABLE)
            self._has_light = True

    def _version_table(self, readonly: bool) -> None:
        """Files written before chunk_versions get it (every chunk at version 0)."""
        have = {r[0] for r in self.db.execute(
            "SELECT name FROM sqlite_master WHERE name LIKE 'chunk_version%'")}
        if len(have) < len(VERSION_TABLE) and not readonly:
            with self.transaction() as db:
                for statement in VERSION_TABLE:
                    db.execute(statement)
            have = {"chunk_versions"}
        self._has_versions = "chunk_versions" in have

    def _stat(self):
        try:
            st = os.stat(self.path)
        except OSError:
            return None
        return (st.st_dev, st.st_ino)

    @property
    def identity(self):
        """(device, inode) of the file when opened: the same file reopened has it,
        another file moved to the path has not."""
        return self._identity_at_open

    def gone(self) -> bool:
        """Whether the file at `path` is no longer the one opened (deleted, moved
        away, replaced by another file)."""
        now = self._stat()
        return now is None or (self._identity_at_open is not None
                               and now != self._identity_at_open)

    def damage_seen(self) -> str | None:
        """How the file at `path` is no longer a whole SQLite file, from its 100-byte
        header: "overwritten" (not SQLite's) or "cut short" (shorter than the pages
        its header counts); None when it looks whole or cannot be read. Reading
        through our connection may not notice (the pages it wants may be in the
        -wal). Another process's checkpoint may be caught between the header and
        the file's growth: ask again before believing a "cut short"."""
        try:
            with open(self.path, "rb") as f:
                head = f.read(100)
                size = os.fstat(f.fileno()).st_size
        except OSError:
            return None
        if len(head) < 100:
            return "cut short"
        if head[:16] != b"SQLite format 3\x00":
            return "overwritten"
        page = int.from_bytes(head[16:18], "big")
        pages = int.from_bytes(head[28:32], "big")
        # (the page count is valid while the change counter matches version-valid-for)
        if pages and head[24:28] == head[92:96] and size < pages * (65536 if page == 1 else page):
            return "cut short"
        return None

    def check_path(self) -> None:
        """A VoxelError when the file at `path` is no longer the one opened (deleted,
        moved away, replaced): writing on would put the edits where nobody sees them.
        Every write transaction checks it (a stat: microseconds)."""
        now = self._stat()
        if now is None:
            raise VoxelError(f"the world file {self.path} was deleted or moved while it was "
                             "open; nothing more is written to it")
        if self._identity_at_open is not None and now != self._identity_at_open:
            raise VoxelError(f"the world file {self.path} was replaced by another file while "
                             "it was open; nothing more is written to it")
