"""What a Minecraft import keeps in the world file for a resource stack (issue 30;
formats/mcstate.py fills it, the bake and the drawing read it).

Meta (JSON): `mc_states` the state palette (`minecraft:name[k=v,…]`, entry 0 empty),
`mc_state_defaults` ({block name: state index}: each block type's usual state in
this world), `mc_color_states` ({colour index: state index}), `mc_resources` (the
stack's paths, bottom first), `mc_y_min` (the Minecraft y of z 0), `mc_biome_names`.
A voxel's state (`states`): its small data when not 0, else its block's default, so
the stone, dirt and water of a world store data 0 (a NULL or near-empty blob); the
`color` block's data stays its colour, its state in `mc_color_states`. A world
without `mc_state_defaults` (imported before it existed) has no defaults: its data
is the state index itself, 0 none.
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
DEFAULTS = "mc_state_defaults"
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
    with wf.transaction() as db:
        put(db, rows)


def put(db, rows) -> None:
    """`write` inside the caller's transaction (an import's: with the chunks)."""
    rows = [(int(k[0]), int(k[1]), zlib.compress(np.asarray(a, np.uint8).tobytes(order="F")))
            for k, a in rows]
    if rows:
        db.execute(SCHEMA)
        db.executemany("INSERT OR REPLACE INTO mc_biomes VALUES (?, ?, ?)", rows)


def update(db, key: str, fn) -> None:
    """Meta KEY set to fn(the value stored, or None) inside the caller's transaction
    (an import's note with its batch, on what other imports noted meanwhile)."""
    row = db.execute("SELECT value FROM meta WHERE key=?", (key,)).fetchone()
    db.execute("INSERT OR REPLACE INTO meta VALUES (?, ?)",
               (key, str(fn(None if row is None else row[0]))))


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


def defaults(meta: dict) -> np.ndarray | None:
    """(registry size,) int32 default state per block id, or None for a world whose
    data are state indices (no `mc_state_defaults`); ValueError when damaged."""
    raw = meta.get(DEFAULTS)
    if raw is None:
        return None
    from ..core.blocks import REGISTRY
    got = json.loads(raw or "{}")
    if not isinstance(got, dict):
        raise ValueError(f"{DEFAULTS} is not an object")
    out = np.zeros(len(REGISTRY), np.int32)
    known = set(REGISTRY.names())
    for name, st in got.items():
        if name in known and isinstance(st, int) and st >= 0:
            out[REGISTRY.id(name)] = st
    return out


def kept(meta: dict):
    """(stack paths, state palette, {colour index: state}, y_min, defaults) a
    Minecraft import kept in META, or None where it kept no stack or no states;
    ValueError when damaged."""
    try:
        paths = json.loads(meta.get(RESOURCES) or "null")
        palette = json.loads(meta.get(STATES) or "[]")
        cstates = {int(k): int(v) for k, v in json.loads(meta.get(COLOR_STATES) or "{}").items()}
        y_min = int(meta.get(Y_MIN) or -64)
        dflt = defaults(meta)
    except (ValueError, TypeError, AttributeError) as e:
        raise ValueError(str(e)) from None
    if not paths or not palette:
        return None
    return paths, palette, cstates, y_min, dflt


def states(blocks: np.ndarray, data: np.ndarray | None, palette: list, cstates: dict,
           color: int, defaults: np.ndarray | None = None) -> np.ndarray:
    """Per voxel its state index (0: none) from the blocks' small data (None: all 0)
    and the world's DEFAULTS (see the module docstring): a `color` voxel (block id
    COLOR) keeps its state in CSTATES by its colour index."""
    if data is None:
        data = np.zeros(blocks.shape, np.uint16)
    if defaults is None:
        state = np.where(blocks == 0, 0, data).astype(np.int32)
    else:   # data 0: the block's default (air's is 0)
        state = np.where(data == 0, defaults[np.minimum(blocks, len(defaults) - 1)],
                         data).astype(np.int32)
        state[blocks == 0] = 0
    col = blocks == color
    if cstates:
        cmap = np.zeros(max(cstates) + 1, np.int32)
        cmap[list(cstates)] = list(cstates.values())
        state[col] = np.where(data[col] < len(cmap), cmap[np.minimum(data[col], len(cmap) - 1)], 0)
    else:
        state[col] = 0
    state[state >= len(palette)] = 0
    return state


def region(wf, x0: int, y0: int, x1: int, y1: int, n: int) -> np.ndarray:
    """(x1 - x0, y1 - y0) uint8 biome indices of a box of columns (0 where none
    is kept), below N (the names)."""
    biomes = np.zeros((x1 - x0, y1 - y0), np.uint8)
    for cy in range(y0 >> 4, ((y1 - 1) >> 4) + 1):
        for cx in range(x0 >> 4, ((x1 - 1) >> 4) + 1):
            b = read(wf, (cx, cy))
            if b is None:
                continue
            ax, ay = max(cx * 16, x0), max(cy * 16, y0)
            bx, by = min(cx * 16 + 16, x1), min(cy * 16 + 16, y1)
            biomes[ax - x0:bx - x0, ay - y0:by - y0] = \
                b[ax - cx * 16:bx - cx * 16, ay - cy * 16:by - cy * 16]
    return np.minimum(biomes, max(n - 1, 0))
