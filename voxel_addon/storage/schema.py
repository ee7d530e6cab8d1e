"""The world file's tables (SPEC §3 and ours beside them), and how opening it fails."""
from __future__ import annotations

import os
import sqlite3
from pathlib import Path

from ..core.errors import VoxelError, cause, damaged

FORMAT_VERSION = 1
APP_ID = 0x564F5857  # "VOXW": marks our files in the SQLite header

# The user's own changes, kept apart so a world can be regenerated with them.
EDITS_TABLE = """CREATE TABLE IF NOT EXISTS edits(x INTEGER, y INTEGER, z INTEGER,
    block INTEGER NOT NULL, data INTEGER NOT NULL DEFAULT 0, t REAL NOT NULL,
    PRIMARY KEY (x, y, z))"""
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
{EDITS_TABLE};
"""

# Our own table beside SPEC 3's `chunks` (whose columns stay as they are): the
# version of each chunk row, the file-wide sequence number of its last write (or
# delete). Kept by triggers, so every writer of `chunks` keeps it right.
VERSION_TABLE = (
    """CREATE TABLE IF NOT EXISTS chunk_versions(cx INTEGER, cy INTEGER, v INTEGER NOT NULL,
        PRIMARY KEY (cx, cy)) WITHOUT ROWID""",  # the key is the table: no second b-tree
    "CREATE INDEX IF NOT EXISTS chunk_versions_v ON chunk_versions(v)",
) + tuple(
    f"""CREATE TRIGGER IF NOT EXISTS chunk_version_{what} AFTER {what.upper()} ON chunks BEGIN
        INSERT OR REPLACE INTO chunk_versions VALUES ({row}.cx, {row}.cy,
            (SELECT COALESCE(MAX(v), 0) + 1 FROM chunk_versions));
    END""" for what, row in (("insert", "NEW"), ("update", "NEW"), ("delete", "OLD")))


def lock_timeout() -> float:
    """Seconds a write waits for another program's transaction on the same file
    (VOXEL_LOCK_TIMEOUT, default 30) before it fails as locked."""
    try:
        return max(0.0, float(os.environ.get("VOXEL_LOCK_TIMEOUT", "30")))
    except ValueError:
        return 30.0


def open_error(path: Path, e: sqlite3.DatabaseError) -> VoxelError:
    """A full disk, a locked or read-only file is not a damaged one: say which."""
    what = None if damaged(e) else cause(e, path)
    if what is not None:
        return VoxelError(f"{what} while opening {path}: nothing was written")
    return VoxelError(f"{path} is not a readable world file ({e})")
