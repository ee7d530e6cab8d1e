"""A Minecraft 1.21 region that looks like a survival world's, for the import rows
(no real save may ship): bedrock, deepslate with tuff, stone with granite / diorite /
andesite blobs and ores, caves, dirt under grass, sand and water (level=0) below sea
level, oak trees (logs with axis=y, leaves with distance 1..6), grass and flowers, a
few stairs, slabs, wool and terracotta (states that differ from their block's usual
one; the `color` block) and 1.18+
section biome palettes (plains / forest / river by area). Deterministic per chunk
position; `chunk(cx, cz)` also gives the block state of every block (the oracle of
the tests: tests/formats/test_statestore.py)."""
from __future__ import annotations

import struct
import zlib

import numpy as np

Y0, SECTIONS = -64, 24
STATES = [  # (name, properties): index = a voxel's code below
    ("minecraft:air", None), ("minecraft:bedrock", None),
    ("minecraft:deepslate", {"axis": "y"}), ("minecraft:tuff", None),
    ("minecraft:stone", None), ("minecraft:granite", None), ("minecraft:diorite", None),
    ("minecraft:andesite", None), ("minecraft:coal_ore", None), ("minecraft:iron_ore", None),
    ("minecraft:deepslate_iron_ore", None), ("minecraft:cave_air", None),
    ("minecraft:dirt", None), ("minecraft:grass_block", {"snowy": "false"}),
    ("minecraft:sand", None), ("minecraft:water", {"level": "0"}),
    ("minecraft:oak_log", {"axis": "y"}),
    *[("minecraft:oak_leaves", {"distance": str(d), "persistent": "false",
                                "waterlogged": "false"}) for d in range(1, 7)],
    ("minecraft:short_grass", None), ("minecraft:poppy", None),
    *[("minecraft:oak_stairs", {"facing": f, "half": "bottom", "shape": "straight",
                                "waterlogged": "false"}) for f in ("north", "east", "south", "west")],
    ("minecraft:cobblestone_slab", {"type": "bottom", "waterlogged": "false"}),
    ("minecraft:water", {"level": "2"}), ("minecraft:lava", {"level": "0"}),
    ("minecraft:white_wool", None), ("minecraft:red_terracotta", None),
]
CODE = {(n, tuple(sorted((p or {}).items()))): i for i, (n, p) in enumerate(STATES)}
LEAVES = CODE[("minecraft:oak_leaves", (("distance", "1"), ("persistent", "false"),
                                        ("waterlogged", "false")))]
STAIRS = CODE[("minecraft:oak_stairs", (("facing", "north"), ("half", "bottom"),
                                        ("shape", "straight"), ("waterlogged", "false")))]
BIOMES = ["minecraft:plains", "minecraft:forest", "minecraft:river"]


def _c(n, props=None):
    return CODE[(f"minecraft:{n}", tuple(sorted((props or {}).items())))]


def _noise(x, y, z, f, seed):
    """A smooth field in -3..3 (sums of sines: no dependency, deterministic)."""
    return (np.sin(x * f + seed) + np.sin(y * f * 1.3 + 2 * seed) * np.cos(z * f * 0.7 - seed)
            + np.sin((x + z) * f * 0.6 + y * f * 0.4 + 3 * seed))


def chunk(cx: int, cz: int) -> np.ndarray:
    """(384, 16, 16) [y - Y0, z, x] codes into STATES of Minecraft chunk (cx, cz)."""
    x = (cx * 16 + np.arange(16))[None, None, :].astype(np.float64)
    z = (cz * 16 + np.arange(16))[None, :, None].astype(np.float64)
    y = (Y0 + np.arange(SECTIONS * 16))[:, None, None].astype(np.float64)
    h = np.rint(64 + 7 * np.sin(x[0] / 23) + 5 * np.cos(z[0] / 17) + 3 * np.sin((x[0] + z[0]) / 9)
                ).astype(int)                                     # (16, 16) [z, x]
    Y = y.astype(int)
    a = np.where(Y < 0, _c("deepslate", {"axis": "y"}), _c("stone")).astype(np.int16) * np.ones((1, 16, 16), np.int16)
    blob = _noise(x, y, z, 0.21, 1.0)
    a[(Y >= 0) & (blob > 2.1)] = _c("granite")
    a[(Y >= 0) & (blob < -2.2)] = _c("diorite")
    a[(Y >= 0) & (_noise(z, y, x, 0.17, 4.0) > 2.2)] = _c("andesite")
    a[(Y < 0) & (_noise(x, y, z, 0.13, 7.0) > 2.0)] = _c("tuff")
    ore = _noise(x, y, z, 0.9, 2.0)
    a[(Y >= 0) & (ore > 2.55)] = _c("coal_ore")
    a[(Y >= -40) & (Y < 60) & (ore < -2.6)] = _c("iron_ore")
    a[(Y < 0) & (ore < -2.6)] = _c("deepslate_iron_ore")
    cave = (np.abs(_noise(x, y, z, 0.08, 5.0)) < 0.12) & (Y > -58) & (Y < h[None] - 6)
    a[cave] = _c("cave_air")
    a[cave & (Y < -54)] = _c("lava", {"level": "0"})
    a[Y <= -64 + (ore[:1] > 0).astype(int)] = _c("bedrock")
    top = h[None]
    a[(Y >= top - 3) & (Y < top)] = _c("dirt")
    wet = h < 63
    a = np.where(Y == top, np.where(wet, _c("sand"), _c("grass_block", {"snowy": "false"}))[None], a)
    a[Y > top] = _c("air")
    a[(Y > top) & (Y <= 62)] = _c("water", {"level": "0"})
    edge = wet & ~np.roll(wet, 1, 0)
    a[(Y == 63) & edge[None]] = _c("water", {"level": "2"})
    rng = np.random.default_rng((cx * 7919 + cz * 104729) & 0xFFFFFFFF)
    dry = np.argwhere(~wet)
    open_ = (_c("air"), _c("short_grass"), _c("poppy"))
    for zz, xx in dry[rng.random(len(dry)) < 0.08]:           # grass and flowers
        a[h[zz, xx] + 1 - Y0, zz, xx] = _c("poppy") if rng.random() < 0.2 else _c("short_grass")
    for zz, xx in dry[rng.random(len(dry)) < 0.006]:          # trees inside the chunk
        if 2 <= zz <= 13 and 2 <= xx <= 13:
            t = h[zz, xx] + 1 - Y0
            for dz in range(-2, 3):
                for dx in range(-2, 3):
                    for dy in range(3, 7):
                        d = abs(dz) + abs(dx) + max(0, dy - 5)
                        if d and d < 5 and a[t + dy, zz + dz, xx + dx] in open_:
                            a[t + dy, zz + dz, xx + dx] = LEAVES + min(d, 6) - 1
            a[t:t + 5, zz, xx] = _c("oak_log", {"axis": "y"})
    if (cx * 31 + cz * 17) % 11 == 0:                          # a hut: stairs and slabs
        g = int(h[4:12, 4:12].max()) + 1 - Y0
        a[g, 4:12, 4:12] = _c("cobblestone_slab", {"type": "bottom", "waterlogged": "false"})
        a[g, 6:10, 6:10] = _c("white_wool")                    # colour blocks
        a[g, 7, 7] = _c("red_terracotta")
        for i, f in enumerate(range(4)):
            a[g + 1 + i, 4 + i:12 - i, 4 + i] = STAIRS + f
    return a


def _s(v: str) -> bytes:
    b = v.encode()
    return struct.pack(">H", len(b)) + b


def _longs(idx: np.ndarray, bits: int) -> bytes:
    per = 64 // bits
    idx = np.concatenate([idx.astype(np.uint64), np.zeros(-len(idx) % per, np.uint64)]).reshape(-1, per)
    words = (idx << (np.arange(per, dtype=np.uint64) * np.uint64(bits))).sum(1, dtype=np.uint64)
    return struct.pack(">i", len(words)) + words.astype(">u8").tobytes()


def _entry(code: int) -> bytes:
    name, props = STATES[code]
    out = b"\x08" + _s("Name") + _s(name)
    if props:
        out += b"\x0a" + _s("Properties") + b"".join(
            b"\x08" + _s(k) + _s(v) for k, v in sorted(props.items())) + b"\x00"
    return out + b"\x00"


def _section(sy: int, codes: np.ndarray, biome: int) -> bytes:
    pal, idx = np.unique(codes.reshape(-1), return_inverse=True)
    out = b"\x01" + _s("Y") + struct.pack(">b", sy) + b"\x0a" + _s("block_states")
    out += b"\x09" + _s("palette") + b"\x0a" + struct.pack(">i", len(pal))
    out += b"".join(_entry(int(c)) for c in pal)
    if len(pal) > 1:
        out += b"\x0c" + _s("data") + _longs(idx, max(4, (len(pal) - 1).bit_length()))
    out += b"\x00" + b"\x0a" + _s("biomes") + b"\x09" + _s("palette") + b"\x08"
    names = [BIOMES[biome], BIOMES[(biome + 1) % 3]]
    out += struct.pack(">i", 2) + b"".join(_s(n) for n in names)
    cells = (np.arange(64) // 16 + sy) % 3 == 0               # a second biome in some cells
    out += b"\x0c" + _s("data") + _longs(cells.astype(np.uint64), 1)
    out += b"\x00"
    if sy >= 3:   # sky light, as a lit chunk keeps it (read past by the import)
        out += b"\x07" + _s("SkyLight") + struct.pack(">i", 2048) + bytes([0xFF if sy > 4 else 0x0F]) * 2048
    return out + b"\x00"


def chunk_nbt(cx: int, cz: int, codes: np.ndarray | None = None) -> bytes:
    codes = chunk(cx, cz) if codes is None else codes
    biome = (cx // 3 + cz // 5) % 3
    body = b"\x03" + _s("DataVersion") + struct.pack(">i", 3953)
    body += b"\x03" + _s("xPos") + struct.pack(">i", cx) + b"\x03" + _s("zPos") + struct.pack(">i", cz)
    body += b"\x08" + _s("Status") + _s("minecraft:full")
    body += b"\x0a" + _s("Heightmaps") + b"".join(   # what a saved chunk also holds
        b"\x0c" + _s(k) + _longs(np.full(256, 140, np.uint64), 9) for k in
        ("MOTION_BLOCKING", "MOTION_BLOCKING_NO_LEAVES", "OCEAN_FLOOR", "WORLD_SURFACE")) + b"\x00"
    body += b"\x09" + _s("block_entities") + b"\x0a" + struct.pack(">i", 0)
    body += b"\x09" + _s("sections") + b"\x0a" + struct.pack(">i", SECTIONS)
    body += b"".join(_section(Y0 // 16 + i, codes[16 * i:16 * i + 16], biome)
                     for i in range(SECTIONS))
    return b"\x0a" + _s("") + body + b"\x00"


def region(n: int = 32, rx: int = 0, rz: int = 0) -> bytes:
    """Region file (rx, rz) with its first n x n chunks (zlib, as Minecraft writes)."""
    head, body, sector = bytearray(8192), bytearray(), 2
    for lz in range(n):
        for lx in range(n):
            p = zlib.compress(chunk_nbt(rx * 32 + lx, rz * 32 + lz), 6)
            blob = struct.pack(">iB", len(p) + 1, 2) + p
            blob += bytes(-len(blob) % 4096)
            head[4 * (lx + 32 * lz):4 * (lx + 32 * lz) + 4] = \
                (sector << 8 | len(blob) // 4096).to_bytes(4, "big")
            body += blob
            sector += len(blob) // 4096
    return bytes(head + body)


def save(folder, n: int = 32):
    """A save folder (region/r.0.0.mca, n x n chunks); its path."""
    from pathlib import Path
    folder = Path(folder)
    (folder / "region").mkdir(parents=True, exist_ok=True)
    (folder / "region" / "r.0.0.mca").write_bytes(region(n))
    return folder
