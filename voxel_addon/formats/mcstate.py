"""What the Minecraft import keeps beyond block types (issue 30): each block's state
and each column's biome, so a resource stack can draw the world as the game does.

States: meta `mc_states` is the world's state palette, a JSON list of
`minecraft:name[k=v,…]` (properties sorted), entry 0 the empty string. Meta
`mc_state_defaults` ({block name: state index}) gives each block type of the world
its default state: the state most of its voxels have in the first chunk where an
import meets at least SETTLE of them (stone → minecraft:stone, water →
water[level=0]), fixed from then on.
An imported voxel's small data is 0 when its state is its block's default, else its
state's index: most voxels store 0, and a chunk's data blob is NULL or mostly zeros
(storage/minecraft.py `states` reads them back). The `color` block's data stays its
colour (core.colors): meta `mc_color_states` ({colour index: state index}) names the
state of each colour an import made (every Minecraft dye state gets a colour entry of
its own, so white wool and a white carpet stay apart). Air keeps 0. Voxels written by
other means (generation, edits, .vox) store 0: their block's default state where the
world has one, else none (today's look). A world imported before defaults existed
(states, no `mc_state_defaults`) keeps data = state index, also for later imports.

Biomes: one per voxel column, the biome at the column's highest block (1.18+ section
palettes of 4×4×4 cells; 1.15–1.17 1024 cells; older 256 per column), written to
storage/minecraft.py beside the chunks.
"""
from __future__ import annotations

import json

import numpy as np

from ..core.blocks import REGISTRY
from ..core.errors import VoxelError
from ..mcres.states import parse_key, state_key  # noqa: F401  (the one spelling)
from ..storage import minecraft as mcfile

KEY, COLOR_KEY, RESOURCES, Y_MIN = mcfile.STATES, mcfile.COLOR_STATES, mcfile.RESOURCES, mcfile.Y_MIN
DEFAULTS = mcfile.DEFAULTS
LIMIT = 1 << 16
SETTLE = 256
MEMO = 4096    # section biome layouts remembered (columns)   # voxels of a block in one chunk that decide its default state
DEFAULT_BIOME = "minecraft:plains"

# 1.13–1.17 numeric biome ids (the common ones; others read as plains)
LEGACY = dict(enumerate(
    "ocean plains desert mountains forest taiga swamp river nether_wastes the_end "
    "frozen_ocean frozen_river snowy_plains snowy_mountains mushroom_fields "
    "mushroom_field_shore beach desert_hills wooded_hills taiga_hills mountain_edge jungle "
    "jungle_hills sparse_jungle deep_ocean stony_shore snowy_beach birch_forest "
    "birch_forest_hills dark_forest snowy_taiga snowy_taiga_hills old_growth_pine_taiga "
    "giant_tree_taiga_hills windswept_forest savanna savanna_plateau badlands "
    "wooded_badlands badlands_plateau small_end_islands end_midlands end_highlands "
    "end_barrens warm_ocean lukewarm_ocean cold_ocean deep_warm_ocean deep_lukewarm_ocean "
    "deep_cold_ocean deep_frozen_ocean".split()))
LEGACY.update({127: "the_void", 129: "sunflower_plains", 130: "desert", 131: "windswept_gravelly_hills",
               132: "flower_forest", 133: "taiga", 134: "swamp", 140: "ice_spikes",
               149: "jungle", 151: "sparse_jungle", 155: "old_growth_birch_forest",
               156: "old_growth_birch_forest", 157: "dark_forest", 158: "snowy_taiga",
               160: "old_growth_spruce_taiga", 161: "old_growth_spruce_taiga",
               162: "windswept_gravelly_hills", 163: "windswept_savanna",
               164: "windswept_savanna", 165: "eroded_badlands", 166: "wooded_badlands",
               167: "badlands", 168: "bamboo_jungle", 169: "bamboo_jungle",
               170: "soul_sand_valley", 171: "crimson_forest", 172: "warped_forest",
               173: "basalt_deltas", 174: "dripstone_caves", 175: "lush_caves"})
# 1.18 renamed some: the tint table (mcres.tints) knows the new names
RENAMED = {"mountains": "windswept_hills", "snowy_mountains": "snowy_slopes",
           "snowy_tundra": "snowy_plains", "giant_tree_taiga": "old_growth_pine_taiga",
           "giant_spruce_taiga": "old_growth_spruce_taiga", "wooded_mountains": "windswept_forest",
           "jungle_edge": "sparse_jungle", "stone_shore": "stony_shore",
           "shattered_savanna": "windswept_savanna", "gravelly_mountains": "windswept_gravelly_hills",
           "tall_birch_forest": "old_growth_birch_forest", "wooded_badlands_plateau": "wooded_badlands",
           "nether": "nether_wastes"}


def load(meta: dict, key: str, empty):
    raw = meta.get(key)
    if not raw:
        return empty
    try:
        got = json.loads(raw)
    except ValueError:
        raise VoxelError(f"the world's meta {key!r} is damaged") from None
    if type(got) is not type(empty):
        raise VoxelError(f"the world's meta {key!r} is damaged")
    return got


class States:
    """The world's state palette, grown by an import and staged with its batches."""

    def __init__(self, file):
        self.file = file
        old = load(file.meta, KEY, [])
        self.list = old or [""]
        self.index = {s: i for i, s in enumerate(self.list)}
        # states imported before defaults existed: data stays the state index
        self.legacy = bool(old) and DEFAULTS not in file.meta
        self.defaults = {} if self.legacy else load(file.meta, DEFAULTS, {})
        self.dflt = np.zeros(len(REGISTRY), np.uint16)   # per block id, 0: none yet
        names = REGISTRY.names()
        for n, st in self.defaults.items():
            if n in names and isinstance(st, int) and 0 < st < len(self.list):
                self.dflt[names.index(n)] = st
        self.colors = {int(k): v for k, v in load(file.meta, COLOR_KEY, {}).items()}
        self.color_of = {v: k for k, v in self.colors.items()}
        self.biomes = mcfile.names(file.meta) or [DEFAULT_BIOME]
        self.biome_index = {b: i for i, b in enumerate(self.biomes)}
        self.changed = set()
        self._memo: dict = {}       # section biome palettes → their world indices

    def of(self, name: str, props: dict | None) -> int:
        return self.of_key(state_key(name, props))

    def of_key(self, key: str) -> int:
        i = self.index.get(key)
        if i is None:
            if len(self.list) >= LIMIT:
                raise VoxelError(f"a world keeps at most {LIMIT} Minecraft block states")
            i = self.index[key] = len(self.list)
            self.list.append(key)
            self.changed.add(KEY)
        return i

    def settle(self, ids: np.ndarray, vals: np.ndarray, counts: np.ndarray) -> np.ndarray:
        """The default state per block id (0: none yet) for a chunk whose palette
        entries are block IDS with states VALS covering COUNTS voxels: a block id
        without one gets the state most of its voxels have here (ties: the lower
        index) once it covers SETTLE voxels in one chunk, so that a few flowing water
        blocks do not decide water. Values equal to their block's default are stored
        as 0; the others (an undecided block's too) as their index."""
        if self.legacy:
            return self.dflt
        new = (self.dflt[ids] == 0) & (ids != 0) & (ids != _COLOR)
        # (most chunks: only blocks too rare here to decide, such as ores, are new)
        if new.any() and np.bincount(ids[new], counts[new]).max() >= SETTLE:
            tally: dict = {}
            total: dict = {}
            for b, v, n in zip(ids[new].tolist(), vals[new].tolist(), counts[new].tolist()):
                tally[b, v] = tally.get((b, v), 0) + n
                total[b] = total.get(b, 0) + n
            best: dict = {}
            for (b, v), n in tally.items():
                if total[b] >= SETTLE and (b not in best or (n, -v) > (best[b][0], -best[b][1])):
                    best[b] = (n, v)
            for b, (_, v) in best.items():
                self.dflt[b] = v
                self.defaults[REGISTRY[b].name] = v
                self.changed.add(DEFAULTS)
        return self.dflt

    def color(self, state: int, palette: np.ndarray, rgb) -> tuple[np.ndarray, int]:
        """The colour index of a dye STATE (a palette entry of its own) and the palette."""
        c = self.color_of.get(state)
        if c is None:
            if len(palette) >= LIMIT:
                raise VoxelError(f"a world holds at most {LIMIT} colours")
            c = len(palette)
            palette = np.vstack([palette, np.asarray(rgb, np.uint8).reshape(1, 3)])
            self.colors[c] = state
            self.color_of[state] = c
            self.changed.add(COLOR_KEY)
        return palette, c

    def biome(self, name) -> int:
        if isinstance(name, (int, np.integer)):
            name = LEGACY.get(int(name), "plains")
        name = name if ":" in name else f"minecraft:{name}"
        ns, _, short = name.partition(":")
        name = f"{ns}:{RENAMED.get(short, short)}"
        i = self.biome_index.get(name)
        if i is None:
            if len(self.biomes) >= 255:
                return 0
            i = self.biome_index[name] = len(self.biomes)
            self.biomes.append(name)
            self.changed.add(mcfile.NAMES)
        return i

    def stage(self, put=None) -> None:
        """Stage what changed into the world file's meta (written with the next batch);
        `put(key, value)`: the staging (ToFile's: with the value it was built on)."""
        put = put or self.file.stage_meta
        if KEY in self.changed:
            put(KEY, json.dumps(self.list))
            if not self.legacy:   # the mark of this encoding, with the first states
                self.changed.add(DEFAULTS)
        if DEFAULTS in self.changed:
            put(DEFAULTS, json.dumps(self.defaults, sort_keys=True))
        if COLOR_KEY in self.changed:
            put(COLOR_KEY, json.dumps({str(k): v for k, v in self.colors.items()}))
        if mcfile.NAMES in self.changed:
            put(mcfile.NAMES, json.dumps(self.biomes))
        self.changed.clear()

    def columns(self, ch, blocks: np.ndarray, y_min: int) -> np.ndarray | None:
        return columns(ch, blocks, y_min, self.biome, self._memo)


_COLOR = REGISTRY.id("color")
_LAYERS: dict = {}   # (y_min, lowest and highest section with biomes, height) -> columns' lookups
_LX = np.arange(16)[:, None].repeat(16, 1)             # voxel lx = Minecraft x
_MZ = 15 - np.arange(16)[None, :].repeat(16, 0)        # voxel ly → Minecraft z
_CELL_XZ = (_MZ >> 2) * 4 + (_LX >> 2)                 # a column's 4×4 biome cell


_SPAN = 32
_DOWN = np.arange(_SPAN, 0, -1, dtype=np.uint8)[:, None]   # span row r (from the top) -> SPAN - r


def tops(blocks: np.ndarray) -> np.ndarray:
    """(16, 16) [lx, ly]: each column's highest non-air z, 0 when it has none. Found in
    the _SPAN layers below the highest non-empty one when every column has a block
    there (most chunks: the ground is not that far below the tree tops), else over
    all layers (one pass, not three over the chunk)."""
    h = blocks.shape[2]
    lay = np.ascontiguousarray(blocks.T).reshape(h, -1)   # [z][ly * 16 + lx]: a view (x fastest)
    solid = lay[::-1] != 0                                # [h - 1 - z]: from the top down
    first = int(solid.reshape(-1).argmax()) // lay.shape[1]   # first row with a block
    if not solid[first].any():
        return np.zeros(blocks.shape[:2], np.intp)
    span = solid[first:first + _SPAN]
    k = len(span)
    got = (span.view(np.uint8) * _DOWN[_SPAN - k:]).max(axis=0)   # k - (first hit's row), 0: none
    if got.all():
        top = got.astype(np.intp)
        top += h - 1 - first - k                           # z = h - 1 - (first + k - got)
    else:   # a column without a block in the span: each column's last solid layer
        top = h - 1 - solid.argmax(axis=0)
        top[~solid.any(axis=0)] = 0
    return top.reshape(blocks.shape[1], blocks.shape[0]).T


def columns(ch, blocks: np.ndarray, y_min: int, biome, memo: dict | None = None) -> np.ndarray | None:
    """(16, 16) biome indices [lx, ly] of a chunk: the biome at each column's highest
    block (the lowest cell where a column is empty); `biome` (a name or a legacy id →
    an index) numbers them, `memo` keeps a section palette's numbers between calls."""
    from .anvil import cells
    memo = {} if memo is None else memo
    lx, mz, cell_xz = _LX, _MZ, _CELL_XZ
    if ch.biomes is not None:                   # 1.13–1.17
        y = tops(blocks) + y_min                # Minecraft y of each column's top
        b = ch.biomes
        ids = b[mz * 16 + lx] if b.size == 256 else b[np.clip(y >> 2, 0, 63) * 16 + cell_xz]
        uniq, inv = np.unique(ids, return_inverse=True)
        return np.array([biome(int(u)) for u in uniq], np.uint8)[inv].reshape(16, 16)
    secs = {s.y: s.biomes for s in ch.sections if s.biomes is not None}
    if not secs:
        return None
    ys = sorted(secs)
    # per top layer: its section (clipped to those with biomes) - ys[0], and the row of
    # its cells (((y & 15) >> 2) * 16): two lookups instead of a dozen array passes
    got = _LAYERS.get((y_min, ys[0], ys[-1], blocks.shape[2]))
    if got is None:
        if len(_LAYERS) >= MEMO:
            _LAYERS.clear()
        y = np.arange(blocks.shape[2]) + y_min
        got = _LAYERS[y_min, ys[0], ys[-1], blocks.shape[2]] = (
            np.clip(y >> 4, ys[0], ys[-1]) - ys[0], ((y & 15) >> 2) * 16)
    top = tops(blocks)
    sy = got[0][top]
    ds = np.flatnonzero(np.bincount(sy.ravel())).tolist()   # sections met, sorted
    # each section met: its 64 cells' world biomes (kept by the section's biome bytes,
    # which repeat across chunks); then one lookup for all columns
    rows = []
    for s in ds:
        s += ys[0]
        near = s if s in secs else min(ys, key=lambda v: abs(v - s))
        names, data = secs[near]
        key = (tuple(names), None if data is None else data.tobytes())
        row = memo.get(key)
        if row is None:
            if len(memo) >= MEMO:   # a save of endless distinct biome layouts
                memo.clear()
            glob = np.array([biome(n) for n in names], np.uint8)
            idx = cells(secs[near])
            row = memo[key] = np.full(64, glob[0], np.uint8) if idx is None else glob[idx]
        rows.append(row)
    at = got[1][top]
    at += cell_xz
    if len(rows) == 1:
        return rows[0][at]
    rank = np.zeros(ys[-1] - ys[0] + 1, np.intp)
    rank[ds] = np.arange(0, 64 * len(ds), 64)
    at += rank[sy]
    return np.concatenate(rows)[at]


PALETTES = (KEY, DEFAULTS, COLOR_KEY, mcfile.NAMES)


class ToFile:
    """An import's numbers (its States and colour palette, begun from the file's meta)
    as the world file holds them. While no other writer adds to the file's palettes
    they are the same: the import's values are staged as they are, each with the value
    it was built on (a save finding another one raises storage.MetaMoved and writes
    nothing). After that, `moved` reads the file's palettes again and adds the
    import's entries to them (a state, colour or biome another writer added too is
    shared); from then on the batches' data and biome columns are mapped onto the
    file's numbers (`rows`, `columns`) and the file's palettes, grown as the import
    goes, are staged. The import itself keeps its own numbers throughout (its caches,
    a cluster's `known`, workers' blobs stay valid)."""

    def __init__(self, states: States):
        self.st, self.file = states, states.file
        self.fs = None          # the file's States, once it moved; None: the same numbers
        self.fpal = None        # and its colour palette
        self.ts = self.tb = self.tc = None
        self.same = True        # the maps are the identity

    def _stage(self, key, value) -> None:
        self.file.stage_meta(key, value, base=self.file.meta.get(key))

    def stage(self, palette, grown: bool) -> None:
        """Stage what changed (the palettes) for the next save."""
        from ..core import colors
        st = self.st
        if self.fs is None:
            if grown:
                self._stage(colors.KEY, colors.dump(palette))
            st.stage(self._stage)
            return
        n = len(self.fpal)
        self._sync(palette)
        if len(self.fpal) != n:
            self._stage(colors.KEY, colors.dump(self.fpal))
        st.changed.clear()
        self.fs.stage(self._stage)

    def moved(self, palette) -> None:
        """After MetaMoved: the file's palettes as they are now, the import's entries
        added (staged: written with the batch saved next)."""
        from ..core import colors
        self.file.reload_meta(PALETTES + (colors.KEY,))
        self.fs = States(self.file)
        self.fpal = colors.parse(self.file.meta)
        self.ts, self.tb, self.tc = [], [], {}
        self.stage(palette, False)

    def _sync(self, palette) -> None:
        st, fs = self.st, self.fs
        ts, tb, tc = self.ts, self.tb, self.tc
        for key in st.list[len(ts):]:
            ts.append(fs.of_key(key))
        for name in st.biomes[len(tb):]:
            tb.append(fs.biome(name))
        for c, s in st.colors.items():
            if c not in tc:
                self.fpal, tc[c] = fs.color(ts[s], self.fpal, palette[c])
        if not fs.legacy:
            names = REGISTRY.names()
            for name, s in st.defaults.items():
                if name not in fs.defaults and name in names:
                    fs.defaults[name] = ts[s]
                    fs.dflt[names.index(name)] = ts[s]
                    fs.changed.add(DEFAULTS)
        self.tsa = np.array(ts, np.uint16)
        self.tba = np.array(tb, np.uint8)
        self.tca = np.arange(max(len(palette), 1), dtype=np.uint16)
        for c, v in tc.items():
            self.tca[c] = v
        ldf = self.tsa[st.dflt]
        self.same = bool((self.tsa == np.arange(len(ts))).all()
                         and (self.tba == np.arange(len(tb))).all()
                         and (self.tca == np.arange(len(self.tca))).all()
                         and (ldf == fs.dflt).all())

    def data(self, blocks: np.ndarray, data: np.ndarray) -> np.ndarray:
        """A chunk's data (the import's numbers; BLOCKS registry ids) in the file's."""
        col = blocks == _COLOR
        s = np.where(data != 0, data, self.st.dflt[blocks])   # each voxel's state, 0 none
        s[col] = 0
        v = self.tsa[s]
        v[v == self.fs.dflt[blocks]] = 0                       # the file's default: 0
        v[col] = self.tca[data[col]]
        return v

    def rows(self, rows, file, enc) -> list:
        """Encoded rows (the import's numbers) in the file's: their data blobs made again."""
        if self.same:
            return rows
        out = []
        for r in rows:
            if r[4] is None:
                out.append(r)
                continue
            b, d = file.decode_row(r)
            out.append(r[:4] + (enc.data(self.data(b, d)),) + r[5:])
        return out

    def columns(self, bio) -> list:
        """(key, biome columns) pairs in the file's biome numbers."""
        return bio if self.same else [(k, self.tba[c]) for k, c in bio]

    def save(self, palette, write):
        """write() (a batch's save: its rows through `rows`, made in it) and its
        answer; tried again, on the file's palettes, while other writers move them."""
        from ..storage.meta import while_moved
        return while_moved(write, "palettes", lambda: self.moved(palette))
