"""A Minecraft Java chunk's NBT -> its block sections (palette + 4096 indices).

1.18+ (DataVersion >= 2844): root `sections[]` with `Y` and `block_states {palette,
data}`, root `Status`. 1.13-1.17 (1451..2843): `Level.Sections[]` with `Palette` and
`BlockStates`, `Level.Status`; before 1.16 (DataVersion 2529) indices run on across
longs, since then a long holds 64 // bits whole indices. Older worlds (numeric ids)
are refused. Index order in a section's data: y * 256 + z * 16 + x; Section.indices
holds them z-flipped (y * 256 + (15 - z) * 16 + x, a world chunk's layer order).

A chunk's NBT may hold at most CHUNK_TAGS tags (arrays count as one): a full 1.21
chunk has a few thousand, one with a thousand filled chests some hundred thousand;
more is a hostile file (budget.Exceeded), refused with the whole import.
"""
from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import chunkscan, nbt

V_FLATTENING = 1451  # 17w47a: block names and palettes (1.13)
V_PACKED = 2529      # 20w17a: indices never span two longs
V_NO_LEVEL = 2844    # 21w43a: no Level wrapper, y from -64 (1.18)
CHUNK_TAGS = 1 << 19
DONE = {"full", "minecraft:full", "postprocessed", "fullchunk"}
_ENTRY = {"Name": None, "Properties": None}
_SECTION = {"Y": None, "block_states": {"palette": _ENTRY, "data": None},
            "Palette": _ENTRY, "BlockStates": None, "biomes": {"palette": None, "data": None}}
KEEP = {"DataVersion": None, "Status": None, "sections": _SECTION,
        "Level": {"Status": None, "Sections": _SECTION, "Biomes": None}}


class ChunkError(ValueError):
    pass


class Section(NamedTuple):
    y: int                  # section index: blocks 16*y .. 16*y + 15
    palette: list           # block names
    indices: np.ndarray | None  # (4096,) intp into palette, y*256 + (15-z)*16 + x; None: all palette[0]
    props: list | None = None   # each palette entry's properties ({str: str}), or None
    biomes: tuple | None = None  # 1.18+: (names, packed longs or None): cells() unpacks them
    key: bytes | None = None     # the palette's bytes (chunkscan): equal keys, equal palettes
    # read(packed=True), a 4-bit section (most): its 2048 bytes (little-endian longs, two
    # indices a byte) as (16, 16, 8) intp, z-flipped as indices, plus 256 * its place
    # among the chunk's 4-bit sections (Chunk.nibs holds them all); each palette
    # entry's voxels; indices None
    nib: np.ndarray | None = None
    counts: np.ndarray | None = None


class Chunk(NamedTuple):
    version: int
    status: str
    sections: list
    biomes: np.ndarray | None = None  # 1.13–1.17: Level.Biomes (256 per column or 1024 cells)
    nibs: np.ndarray | None = None    # read(packed=True): every Section.nib, (n, 16, 16, 8)


def read(payload: bytes, budget=None, fast: bool = True, packed: bool = False) -> Chunk:
    """The sections of a chunk's NBT; `budget` (a budget.Budget) is charged its tags.
    `fast`: try chunkscan first (False: the general reader only, the tests' oracle).
    `packed`: the fast path leaves 4-bit sections packed (Section.nib and counts:
    formats/minecraft.convert looks their bytes up, no 4096 indices made)."""
    limit = limit_of(budget)
    payload = payload if isinstance(payload, bytes) else bytes(payload)
    got = scanned(payload, limit, packed) if fast else None
    if got is not None:
        if budget is not None:
            budget.spend_tags(got[1])
        return got[0]
    try:
        root, tags = nbt.read(payload, KEEP, limit)
    except nbt.TooMany:
        if limit < CHUNK_TAGS:
            raise nbt.TooMany(budget.tags_message()) from None
        raise nbt.TooMany(f"more than {CHUNK_TAGS:,} NBT tags in one chunk (real ones "
                          "have thousands)") from None
    if budget is not None:
        budget.spend_tags(tags)
    version = root.get("DataVersion")
    if not isinstance(version, int):
        raise ChunkError("no DataVersion (a world from before 1.13 is not supported; "
                         "open and save it in Minecraft 1.13 or newer first)")
    if version < V_FLATTENING:
        raise ChunkError(f"DataVersion {version} is before 1.13 (numeric block ids); "
                         "open and save the world in Minecraft 1.13 or newer first")
    level = root if version >= V_NO_LEVEL else root.get("Level")
    if not isinstance(level, dict):
        raise ChunkError("no Level compound")
    status = level.get("Status", "full" if version >= V_NO_LEVEL else "")
    if not isinstance(status, str):
        raise ChunkError("Status is not a string")
    raw = level.get("sections" if version >= V_NO_LEVEL else "Sections", [])
    if not isinstance(raw, list):
        raise ChunkError("sections is not a list")
    # checked in order; the packed indices of 1.16+ sections are unpacked together
    # afterwards (one NumPy pass per bit width), so the first fault stays the one reported
    found, fault = [], None
    try:
        for s in raw:
            got = _section(s, version)
            if got is not None:
                found.append(got)
    except ChunkError as e:
        fault = e
    _unpack_all(found)
    sections = []
    for y, names, idx, props, bio in found:
        if idx is not None and int(idx.max()) >= len(names):
            raise ChunkError(f"section {y}: index {int(idx.max())} outside its "
                             f"palette of {len(names)}")
        sections.append(Section(y, names, idx, props, bio))
    if fault is not None:
        raise fault
    old = level.get("Biomes") if version < V_NO_LEVEL else None
    if old is not None and not (isinstance(old, np.ndarray) and old.size in (256, 1024)):
        old = None        # damaged biomes only lose their tints
    return Chunk(version, status, sections, None if old is None else old.astype(np.int32))


def limit_of(budget) -> int:
    """The NBT tags one chunk may hold under `budget` (None: CHUNK_TAGS)."""
    return CHUNK_TAGS if budget is None else min(CHUNK_TAGS, max(budget.tags, 0))


def scanned(payload: bytes, limit: int = CHUNK_TAGS, packed: bool = False):
    """read's fast path alone: (Chunk, tags) of a well-formed 1.18+ chunk of at most
    `limit` tags, None when the general reader must decide. Nothing is charged: the
    import's helper thread reads ahead with this (CHUNK_TAGS), and its own thread
    charges the tags, or reads the chunk again (read(fast=False)) where they pass
    what is left of the budget: the same chunk, or the same error, as read gives."""
    try:   # one pass, nothing else built
        version, status, found, tags = chunkscan.scan(payload, limit)
        sections, nibs = _fast(found, packed)
    except chunkscan.Bail:
        return None
    if sections is None:
        return None
    return Chunk(version, status, sections, None, nibs), tags


def _fast(found, packed=False):
    """(chunkscan's sections unpacked (4-bit ones left packed with `packed`), Chunk.nibs),
    or (None, None) when an index lies outside its palette (the general path then
    reports it)."""
    out, rows = [], []
    for f in found:
        if f[2] is None:   # no longs: its Section once, kept with chunkscan's (memo) row
            if len(f) == 4:
                y, p, _, bio = f
                f.append(Section(y, p.names, None, p.props, bio, p.key))
            out.append(f[4])
        else:
            y, p, data, bio = f
            r = [y, p.names, data, p, bio, None, None]
            rows.append(r)
            out.append(r)
    nibs = None
    if packed:
        four = [r for r in rows if bits_for(len(r[1])) == 4]
        if four:
            nibs = _count(four)
            if nibs is None:
                return None, None
    if not _unpack_all(rows):
        return None, None
    return [r if type(r) is Section else Section(r[0], r[1], r[2], r[3].props, r[4], r[3].key,
                                                 r[5], r[6]) for r in out], nibs


_OFF = np.arange(64, dtype=np.intp)[:, None, None, None] * 256
_NIB = np.arange(16)
_B = np.arange(256)[:, None]
_BYTE_NIBS = ((_B & 15) == _NIB).astype(np.float64) + ((_B >> 4) == _NIB)  # a byte's two nibbles
_OUTSIDE = _NIB[None, :] >= np.arange(17)[:, None]   # [palette size]: nibbles outside it


def _count(rows):
    """4-bit sections' bytes, z-flipped and offset by 256 * their place (rows' nib; all
    of them returned), and voxels per palette entry (counts), their longs dropped: one
    histogram of those values for all; None when an index lies outside its palette."""
    n = len(rows)
    off = _OFF[:n] if n <= len(_OFF) else np.arange(n, dtype=np.intp)[:, None, None, None] * 256
    # z flipped and each long's bytes low first (one byte-swapping copy of the longs),
    # then widened and offset in place: contiguous passes, no 8-byte inner strides
    w = np.concatenate([r[2] for r in rows], dtype=_PACKED).reshape(n, 16, 16)[:, :, ::-1]
    at = w.astype("<u8").view(np.uint8).reshape(n, 16, 16, 8).astype(np.intp)
    at += off
    h = np.bincount(at.reshape(-1), minlength=n * 256).reshape(n, 256)
    # [section, nibble]: low ones + high ones, one small product (exact: counts < 2**53)
    per = (h.astype(np.float64) @ _BYTE_NIBS).astype(np.int64)
    ks = [len(r[1]) for r in rows]
    if min(ks) < 16 and (per * _OUTSIDE[ks]).any():
        return None
    for r, a, c, k in zip(rows, at, per, ks):
        r[2], r[5], r[6] = None, a, c[:k]
    return at


def _section(s, version):
    """[y, names, indices (or the packed longs, for _unpack_all), props, biomes] of one
    raw section, None when it holds no blocks; ChunkError when damaged."""
    if not isinstance(s, dict) or not isinstance(s.get("Y"), int):
        raise ChunkError("a section without Y")
    if version >= V_NO_LEVEL:
        states = s.get("block_states")
        if states is None:
            return None
        if not isinstance(states, dict):
            raise ChunkError("block_states is not a compound")
        palette, data = states.get("palette"), states.get("data")
    else:
        palette, data = s.get("Palette"), s.get("BlockStates")
        if palette is None:
            return None
    if not isinstance(palette, list) or not palette:
        raise ChunkError(f"section {s['Y']}: empty or damaged palette")
    names, props = [], []
    for p in palette:
        name = p.get("Name") if isinstance(p, dict) else None
        if not isinstance(name, str):
            raise ChunkError(f"section {s['Y']}: a palette entry without Name")
        names.append(name)
        pr = p.get("Properties")
        props.append({k: v for k, v in pr.items() if isinstance(v, str)}
                     if isinstance(pr, dict) else None)
    idx = None
    if data is not None:
        if not isinstance(data, np.ndarray) or data.dtype != np.dtype(">i8"):
            raise ChunkError(f"section {s['Y']}: block data is not a long array")
        if version < V_PACKED:
            idx = _flip(unpack(data, len(names), spanning=True))
        else:
            bits = bits_for(len(names))
            _need(len(data), bits)
            idx = data            # unpacked by _unpack_all
    elif len(names) > 1:
        raise ChunkError(f"section {s['Y']}: {len(names)} palette entries and no data")
    return [int(s["Y"]), names, idx, props if any(props) else None, _biomes(s.get("biomes"))]


def _need(n: int, bits: int) -> None:
    per = 64 // bits
    need = -(-4096 // per)
    if n != need:
        raise ChunkError(f"{n} longs of block data, expected {need} "
                         f"({bits} bits per block)")


def _unpack_all(found) -> bool:
    """Replace the packed longs of `found` sections by their 4096 indices (Section's
    order and type: _flip), the sections of one bit width in one pass; whether all
    of those indices lie inside their palettes."""
    groups: dict = {}
    for f in found:
        if f[2] is not None and f[2].dtype == _PACKED:
            groups.setdefault(bits_for(len(f[1])), []).append(f)
    fits = True
    for bits, fs in groups.items():
        n = len(fs)
        if bits == 4:   # two indices a byte, looked up (most sections): no shifts
            u8 = np.concatenate([f[2] for f in fs], dtype="<i8").view(np.uint8)
            out = _NIBBLES.take(u8.reshape(n, 16, 16, 8)[:, :, ::-1], axis=0)  # z flipped
        else:
            per = 64 // bits
            words = np.concatenate([f[2] for f in fs], dtype=np.int64).view(np.uint64)
            shifts = np.arange(per, dtype=np.uint64) * np.uint64(bits)
            out = (words[:, None] >> shifts[None, :]) & np.uint64((1 << bits) - 1)
            out = out.reshape(n, -1)[:, :4096].reshape(n, 16, 16, 16)[:, :, ::-1].astype(np.intp)
        out = out.reshape(n, 4096)
        if (out.max(axis=1) >= [len(f[1]) for f in fs]).any():
            fits = False
        for f, row in zip(fs, out):
            f[2] = row
    return fits


_PACKED = np.dtype(">i8")
_NIBBLES = np.array([[b & 15, b >> 4] for b in range(256)], np.intp)   # a byte's two indices


def nibbles(nib: np.ndarray) -> np.ndarray:
    """A packed 4-bit section's (Section.nib) 4096 indices in Section's order."""
    return _NIBBLES.take(nib & 255, axis=0).reshape(4096)


def _flip(idx: np.ndarray) -> np.ndarray:
    """File order (y*256 + z*16 + x) -> Section's: y*256 + (15 - z)*16 + x as intp,
    the order of a world chunk's layer (x fastest, north up): convert takes from it
    without a copy and NumPy without a cast."""
    return idx.reshape(16, 16, 16)[:, ::-1].astype(np.intp).reshape(4096)


def _biomes(b):
    """A 1.18+ section's biomes: (names, packed longs or None), None when damaged
    (biomes only tint: a bad one is not worth refusing the chunk). Unpacked only for
    the sections a column's top reaches (cells)."""
    if not isinstance(b, dict):
        return None
    names, data = b.get("palette"), b.get("data")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) for n in names):
        return None
    if data is not None and not (isinstance(data, np.ndarray) and data.dtype == np.dtype(">i8")):
        return None
    return (names, data)


def cells(biomes) -> np.ndarray | None:
    """A section's 64 biome cells (indices into its names, cell y*16 + z*4 + x), all
    0 when it has one biome; None when the longs do not fit the palette."""
    names, data = biomes
    if data is None:
        return np.zeros(64, np.int32)
    bits = max(1, (len(names) - 1).bit_length())
    per = 64 // bits
    if len(data) != -(-64 // per):
        return None
    w = data.astype(">u8").astype(np.uint64)
    shifts = np.arange(per, dtype=np.uint64) * np.uint64(bits)
    idx = ((w[:, None] >> shifts[None, :]) & np.uint64((1 << bits) - 1)).reshape(-1)[:64]
    return np.minimum(idx.astype(np.int32), len(names) - 1)


def bits_for(n: int) -> int:
    return max(4, (n - 1).bit_length())


def unpack(longs: np.ndarray, palette_size: int, spanning: bool = False) -> np.ndarray:
    """4096 indices of `bits_for(palette_size)` bits from big-endian longs."""
    bits = bits_for(palette_size)
    words = longs.astype(">u8").astype(np.uint64)
    if spanning:  # one little-endian bit stream over all longs
        need = -(-4096 * bits // 64)
        if len(words) != need:
            raise ChunkError(f"{len(words)} longs of block data, expected {need}")
        b = np.unpackbits(words.view(np.uint8), bitorder="little")  # native little-endian
        w = b[:4096 * bits].reshape(4096, bits).astype(np.uint16)
        return (w << np.arange(bits, dtype=np.uint16)).sum(1, dtype=np.uint16)
    _need(len(words), bits)
    per = 64 // bits
    shifts = (np.arange(per, dtype=np.uint64) * np.uint64(bits))
    out = (words[:, None] >> shifts[None, :]) & np.uint64((1 << bits) - 1)
    return out.reshape(-1)[:4096].astype(np.uint16)
