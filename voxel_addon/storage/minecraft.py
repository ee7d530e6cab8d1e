"""What a Minecraft import keeps in the world file for a resource stack (issue 30;
formats/mcstate.py fills it, the bake and the drawing read it).

Meta (JSON): `mc_states` the state palette (`minecraft:name[k=v,…]`, entry 0 empty;
a voxel's small data indexes it, except the `color` block's), `mc_color_states`
({colour index: state index}), `mc_resources` (the stack's paths, bottom first),
`mc_y_min` (the Minecraft y of z 0), `mc_biome_names`.
Biomes, one per voxel column, for grass, foliage and water tints: a table of our own
beside SPEC 3's, created on first write: `mc_biomes(cx, cy, data)`, `data` the zlib
of 256 uint8 `[lx + 16*ly]` indexing `mc_biome_names`. Deleting a chunk leaves its
row: a later import writes it again, and a row without a chunk tints nothing."""
from __future__ import annotations

import json
import sqlite3
import zlib

import numpy as np

STATES = "mc_states"
COLOR_STATES = "mc_color_states"
RESOURCES = "mc_resources"
Y_MIN = "mc_y_min"
NAMES = "mc_biome_names"
SCHEMA = """CREATE TABLE IF NOT EXISTS mc_biomes(cx INTEGER, cy INTEGER, data BLOB NOT NULL,
    PRIMARY KEY (cx, cy))"""


def names(meta: dict) -> list[str]:
    try:
        got = json.loads(meta.get(NAMES) or "[]")
    except ValueError:
        return []
    return [n for n in got if isinstance(n, str)] if isinstance(got, list) else []


def write(wf, rows) -> None:
    """ROWS: (key, (16, 16) uint8 [lx, ly]) pairs, in one transaction."""
    rows = [(int(k[0]), int(k[1]), zlib.compress(np.asarray(a, np.uint8).tobytes(order="F")))
            for k, a in rows]
    if not rows:
        return
    with wf.transaction() as db:
        db.execute(SCHEMA)
        db.executemany("INSERT OR REPLACE INTO mc_biomes VALUES (?, ?, ?)", rows)


def read(wf, key) -> np.ndarray | None:
    """A chunk's (16, 16) biome indices [lx, ly], None when it has none (or a damaged row)."""
    try:
        got = wf.query("SELECT data FROM mc_biomes WHERE cx = ? AND cy = ?", key)
    except sqlite3.OperationalError:      # no table: nothing was imported with biomes
        return None
    if not got:
        return None
    try:
        raw = zlib.decompressobj().decompress(got[0][0], 257)
    except (zlib.error, TypeError):
        return None
    if len(raw) != 256:
        return None
    return np.frombuffer(raw, np.uint8).reshape(16, 16, order="F")
