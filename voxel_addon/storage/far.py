"""Far terrain in the world file (far/README.md): derived data, like `light`.

Tables of our own beside SPEC 3's, created on first use:
- `far_tiles(level, tx, ty)`: one far tile's samples (arrays of `n` x `n`);
- `far_columns(cx, cy)`: one stored chunk's column summary (16 x 16), so tiles read
  small rows instead of decoding whole chunks;
- `far_dirty(cx, cy)`: chunks written since the far data was made: triggers on
  `chunks` fill it (and drop the chunk's summary) whoever writes, so a tile over a
  changed chunk is rebuilt, and so does dropping edits; the builder empties it.
- `far_info`: the signature of what the data was made from (generator, seed,
  params, layout); another signature clears the tables.
Blobs are the codec's compression of fixed-size little-endian arrays, decoded to
exactly that size (codecs.decode); a damaged or out-of-range row reads as missing.
A read-only file keeps what is built in memory only.
"""
from __future__ import annotations

import sqlite3

import numpy as np

from ..core import chunk as C
from . import codecs

SCHEMA = (
    "CREATE TABLE IF NOT EXISTS far_info(key TEXT PRIMARY KEY, value TEXT)",
    """CREATE TABLE IF NOT EXISTS far_tiles(level INTEGER, tx INTEGER, ty INTEGER,
        codec TEXT NOT NULL, data BLOB NOT NULL, PRIMARY KEY (level, tx, ty))""",
    """CREATE TABLE IF NOT EXISTS far_columns(cx INTEGER, cy INTEGER, codec TEXT NOT NULL,
        data BLOB NOT NULL, PRIMARY KEY (cx, cy))""",
    "CREATE TABLE IF NOT EXISTS far_dirty(cx INTEGER, cy INTEGER, PRIMARY KEY (cx, cy))",
    """CREATE TRIGGER IF NOT EXISTS far_chunk_written AFTER INSERT ON chunks BEGIN
        DELETE FROM far_columns WHERE cx = NEW.cx AND cy = NEW.cy;
        INSERT OR IGNORE INTO far_dirty VALUES (NEW.cx, NEW.cy);
    END""",
    """CREATE TRIGGER IF NOT EXISTS far_chunk_deleted AFTER DELETE ON chunks BEGIN
        DELETE FROM far_columns WHERE cx = OLD.cx AND cy = OLD.cy;
        INSERT OR IGNORE INTO far_dirty VALUES (OLD.cx, OLD.cy);
    END""",
    # edits raise far samples by themselves (tiles.raise_edits): cleared ones too
    """CREATE TRIGGER IF NOT EXISTS far_edit_deleted AFTER DELETE ON edits BEGIN
        INSERT OR IGNORE INTO far_dirty VALUES (OLD.x >> 4, OLD.y >> 4);
    END""",
)
# (name, dtype, lowest, highest) of a sample's values, in blob order; block ids are
# the file's own (translated like chunks)
FIELDS = (("height", "<i2", -1, 255), ("top", "<u2", 0, 65535), ("water", "<i2", -1, 255),
          ("trees", "u1", 0, 255))
SAMPLE_BYTES = sum(np.dtype(t).itemsize for _, t, _, _ in FIELDS)


class FarStore:
    """Far tiles and column summaries of one world file. Arrays come and go as
    {name: (n, n) array} with block ids in the registry's numbering."""

    def __init__(self, wf, signature: str):
        self.wf = wf
        self._mem = {}  # read-only file: what was built, kept here instead
        self.writable = not wf.readonly
        with wf.locked():
            have = {r[0] for r in wf.query(
                "SELECT name FROM sqlite_master WHERE name LIKE 'far_%'")}
            self.tables = "far_tiles" in have and "far_info" in have
            if self.writable:
                with wf.transaction() as db:
                    for statement in SCHEMA:
                        db.execute(statement)
                    self.tables = True
                    old = db.execute("SELECT value FROM far_info WHERE key='signature'"
                                     ).fetchone()
                    if old is None or old[0] != signature:
                        for t in ("far_tiles", "far_columns", "far_dirty"):
                            db.execute(f"DELETE FROM {t}")
                        db.execute("INSERT OR REPLACE INTO far_info VALUES ('signature', ?)",
                                   (signature,))
            elif self.tables:
                old = wf.query("SELECT value FROM far_info WHERE key='signature'")
                self.tables = bool(old) and old[0][0] == signature

    # ---- blobs ------------------------------------------------------------
    def _encode(self, a: dict) -> tuple[str, bytes]:
        parts = []
        for name, t, _, _ in FIELDS:
            v = a[name]
            if name == "top":
                v = self.wf.file_ids[v]
            parts.append(np.ascontiguousarray(v, t).tobytes())
        codec = codecs.default()
        return codec, codecs.encode(codec, b"".join(parts))

    def _decode(self, codec: str, blob: bytes, n: int) -> dict | None:
        try:
            raw = codecs.decode(codec, blob, n * n * SAMPLE_BYTES)
        except Exception:  # derived data: a damaged row is only made again
            return None
        out, at = {}, 0
        for name, t, lo, hi in FIELDS:
            v = np.frombuffer(raw, t, n * n, at).reshape(n, n)
            at += v.nbytes
            if v.size and (v.min() < lo or v.max() > hi):
                return None
            if name == "top":
                if v.max(initial=0) >= len(self.wf.registry_ids):
                    return None
                v = self.wf.registry_ids[v]
            out[name] = v.astype(v.dtype.newbyteorder("="))
        return out

    def _rows(self, sql, args):
        if not self.tables:
            return []
        try:
            return self.wf.query(sql, args)
        except sqlite3.DatabaseError:
            return []

    # ---- tiles ------------------------------------------------------------
    def tile(self, key, n: int) -> dict | None:
        got = self._mem.get(("t",) + tuple(key))
        if got is not None:
            return got
        rows = self._rows("SELECT codec, data FROM far_tiles WHERE level=? AND tx=? AND ty=?",
                          tuple(key))
        return self._decode(*rows[0], n) if rows else None

    def put_tiles(self, items) -> None:
        """items: (key, arrays) pairs, written in one transaction."""
        self._put("INSERT OR REPLACE INTO far_tiles VALUES (?, ?, ?, ?, ?)", "t", items)

    def drop_tiles(self, keys) -> None:
        keys = [tuple(k) for k in keys]
        for k in keys:
            self._mem.pop(("t",) + k, None)
        if self.writable and keys:
            with self.wf.transaction() as db:
                db.executemany("DELETE FROM far_tiles WHERE level=? AND tx=? AND ty=?", keys)

    def tile_keys(self) -> list[tuple[int, int, int]]:
        return [tuple(r) for r in self._rows("SELECT level, tx, ty FROM far_tiles", ())] \
            + [k[1:] for k in self._mem if k[0] == "t"]

    # ---- column summaries of stored chunks ---------------------------------
    def columns(self, key) -> dict | None:
        got = self._mem.get(("c",) + tuple(key))
        if got is not None:
            return got
        rows = self._rows("SELECT codec, data FROM far_columns WHERE cx=? AND cy=?", tuple(key))
        return self._decode(*rows[0], 16) if rows else None

    def put_columns(self, items) -> None:
        self._put("INSERT OR REPLACE INTO far_columns VALUES (?, ?, ?, ?)", "c", items)

    def _put(self, sql, kind, items) -> None:
        items = [(tuple(k), a) for k, a in items]
        if not items:
            return
        if not self.writable:
            self._mem.update((((kind,) + k), a) for k, a in items)
            return
        rows = [k + self._encode(a) for k, a in items]
        with self.wf.transaction() as db:
            db.executemany(sql, rows)

    # ---- what changed -------------------------------------------------------
    def chunks_in(self, cx0, cy0, cx1, cy1) -> set:
        """Keys of the stored chunks in [cx0, cx1] x [cy0, cy1]."""
        return self.wf.chunks_in(cx0, cy0, cx1, cy1)

    def take_dirty(self, tiles_of, limit: int = 4096) -> set:
        """Chunks written since the last call (at most limit): forgotten here, and
        the tiles tiles_of(chunk keys) names dropped in the same transaction (a kill
        in between cannot keep a stale tile). Returns those tile keys."""
        if not self.writable:
            return set()
        with self.wf.locked():
            rows = [tuple(r) for r in self._rows("SELECT cx, cy FROM far_dirty LIMIT ?",
                                                 (limit,))]
            if not rows:
                return set()
            r = C.REACH // C.SIZE  # a row naming no chunk (a hostile file: text, reals,
            good = [k for k in rows  # far away) is dropped with the rest, never used
                    if all(type(v) is int and -r <= v < r for v in k)]
            keys = set(tiles_of(good)) if good else set()
            with self.wf.transaction() as db:
                db.executemany("DELETE FROM far_dirty WHERE cx=? AND cy=?", rows)
                db.executemany("DELETE FROM far_tiles WHERE level=? AND tx=? AND ty=?",
                               list(keys))
        return keys

    def edits(self, x0, y0, x1, y1) -> np.ndarray:
        """(x, y, z, block) of the edits in [x0, x1) x [y0, y1) (registry ids)."""
        return self.wf.edits_box(x0, y0, x1, y1)
