"""Minecraft files written by the tests themselves, independently of the reader:
an NBT encoder, the long-array packing of block states (both the 1.16+ layout and
the older one that runs across longs), region files with every compression type,
and an LZ4 block compressor in lz4-java's framing."""
from __future__ import annotations

import gzip
import struct
import zlib
from pathlib import Path

import numpy as np


# ---- NBT ----------------------------------------------------------------------
class T:
    """A typed NBT value: T(kind, value[, item]); kinds by name."""
    IDS = {"end": 0, "byte": 1, "short": 2, "int": 3, "long": 4, "float": 5, "double": 6,
           "bytes": 7, "string": 8, "list": 9, "compound": 10, "ints": 11, "longs": 12}

    def __init__(self, kind, value, item=None):
        self.kind, self.value, self.item = kind, value, item


def _kind(v):
    if isinstance(v, T):
        return v.kind
    if isinstance(v, str):
        return "string"
    if isinstance(v, dict):
        return "compound"
    if isinstance(v, int):
        return "int"
    raise TypeError(v)


def _payload(kind, v) -> bytes:
    if isinstance(v, T):
        item, v = v.item, v.value
    else:
        item = None
    fmt = {"byte": ">b", "short": ">h", "int": ">i", "long": ">q", "float": ">f", "double": ">d"}
    if kind in fmt:
        return struct.pack(fmt[kind], v)
    if kind == "string":
        b = v.encode()
        return struct.pack(">H", len(b)) + b
    if kind in ("bytes", "ints", "longs"):
        code = {"bytes": "b", "ints": "i", "longs": "q"}[kind]
        return struct.pack(f">i{len(v)}{code}", len(v), *[int(x) for x in v])
    if kind == "list":
        item = item or (_kind(v[0]) if v else "end")
        return bytes([T.IDS[item]]) + struct.pack(">i", len(v)) + b"".join(
            _payload(item, x) for x in v)
    if kind == "compound":
        out = b""
        for k, x in v.items():
            kk = _kind(x)
            out += bytes([T.IDS[kk]]) + _payload("string", k) + _payload(kk, x)
        return out + b"\0"
    raise TypeError(kind)


def nbt(root: dict) -> bytes:
    return b"\x0a" + _payload("string", "") + _payload("compound", root)


# ---- block states -------------------------------------------------------------
def pack(indices, bits, spanning=False) -> list[int]:
    """4096 indices (or 64 biome cells) -> signed 64-bit longs, the way Minecraft stores them."""
    longs = []
    if spanning:
        acc, n = 0, 0
        total = 0
        for v in indices:
            total |= int(v) << n
            n += bits
        count = -(-4096 * bits // 64)
        longs = [(total >> (64 * i)) & (2**64 - 1) for i in range(count)]
    else:
        per = 64 // bits
        for i in range(0, len(indices), per):
            w = 0
            for k, v in enumerate(indices[i:i + per]):
                w |= int(v) << (k * bits)
            longs.append(w)
    return [w - 2**64 if w >= 2**63 else w for w in longs]


def _entry(n: str) -> dict:
    """A palette entry; `name[k=v,…]` gives it Properties (a stair without any faces north)."""
    if "[" in n:
        name, _, rest = n.partition("[")
        return {"Name": name, "Properties": dict(p.split("=") for p in rest.rstrip("]").split(","))}
    return {"Name": n, "Properties": {"facing": "north"}} if "stairs" in n else {"Name": n}


def section_nbt(y, names, version, biomes=None):
    """names: (16, 16, 16) array [y][z][x] of block names, `name[k=v,…]` with
    properties; biomes (1.18+): (names, (64,) cell indices [y][z][x] or None)."""
    flat = names.reshape(-1)
    palette = list(dict.fromkeys(flat.tolist()))
    pal = [_entry(n) for n in palette]
    idx = np.array([palette.index(n) for n in flat])
    bits = max(4, (len(palette) - 1).bit_length())
    states = {"palette": T("list", pal, "compound")}
    if len(palette) > 1 or version < 2844:
        states["data"] = T("longs", pack(idx, bits, spanning=version < 2529))
    if version >= 2844:
        bnames, bidx = biomes or (["minecraft:plains"], None)
        b = {"palette": T("list", bnames)}
        if bidx is not None:
            b["data"] = T("longs", pack(np.asarray(bidx), max(1, (len(bnames) - 1).bit_length())))
        return {"Y": T("byte", y), "block_states": states, "biomes": b}
    return {"Y": T("byte", y), "Palette": states["palette"], "BlockStates": states["data"],
            "BlockLight": T("bytes", [0] * 2048)}


def chunk_nbt(cx, cz, sections: dict, version=3953, status="minecraft:full", biomes=None,
              old_biomes=None) -> bytes:
    """biomes: {section y: (names, cells)} (1.18+); old_biomes: Level.Biomes ints."""
    secs = T("list", [section_nbt(y, a, version, (biomes or {}).get(y))
                      for y, a in sorted(sections.items())], "compound")
    noise = {"Heightmaps": {"WORLD_SURFACE": T("longs", [7] * 37)},
             "block_entities": T("list", [{"id": "minecraft:chest", "x": 1, "y": 2, "z": 3,
                                           "Items": T("list", [], "compound")}], "compound"),
             "structures": {"References": {}, "starts": {}}}
    if version >= 2844:
        root = {"DataVersion": version, "xPos": cx, "zPos": cz, "yPos": -4, "Status": status,
                "sections": secs, **noise}
    else:
        root = {"DataVersion": version,
                "Level": {"xPos": cx, "zPos": cz, "Status": status, "Sections": secs, **noise}}
        if old_biomes is not None:
            root["Level"]["Biomes"] = T("ints", list(old_biomes))
    return nbt(root)


# ---- LZ4 (lz4-java framing) -----------------------------------------------------
def lz4_block(src: bytes) -> bytes:
    """A greedy LZ4 block compressor (matches of 4+ bytes, overlapping ones too)."""
    out = bytearray()
    n, i, anchor = len(src), 0, 0
    table = {}

    def length(v):
        b = bytearray()
        while v >= 255:
            b.append(255)
            v -= 255
        b.append(v)
        return b
    while i + 12 <= n:
        key = src[i:i + 4]
        j = table.get(key)
        table[key] = i
        if j is None or i - j > 65535:
            i += 1
            continue
        m = 4
        while i + m < n - 5 and src[j + m] == src[i + m]:
            m += 1
        lit = src[anchor:i]
        tok = (min(len(lit), 15) << 4) | min(m - 4, 15)
        out.append(tok)
        if len(lit) >= 15:
            out += length(len(lit) - 15)
        out += lit
        out += struct.pack("<H", i - j)
        if m - 4 >= 15:
            out += length(m - 4 - 15)
        i += m
        anchor = i
    lit = src[anchor:]
    out.append(min(len(lit), 15) << 4)
    if len(lit) >= 15:
        out += length(len(lit) - 15)
    out += lit
    return bytes(out)


def lz4_java(data: bytes, block=1 << 16) -> bytes:
    out = b""
    for i in range(0, len(data), block):
        part = data[i:i + block]
        comp = lz4_block(part)
        if len(comp) >= len(part):
            out += b"LZ4Block" + struct.pack("<BiiI", 0x10, len(part), len(part), 0) + part
        else:
            out += b"LZ4Block" + struct.pack("<BiiI", 0x20, len(comp), len(part), 0) + comp
    return out + b"LZ4Block" + struct.pack("<BiiI", 0x10, 0, 0, 0)


# ---- region files ---------------------------------------------------------------
def compress(kind: int, data: bytes) -> bytes:
    return {1: lambda d: gzip.compress(d), 2: zlib.compress, 3: lambda d: d,
            4: lz4_java}[kind](data)


def region(chunks: dict, kind: int = 2, external=()) -> bytes:
    """chunks: {(cx, cz) Minecraft chunk: NBT bytes} of one region; `external`: keys
    marked as stored in .mcc files."""
    head = bytearray(8192)
    body = bytearray()
    sector = 2
    for (cx, cz), data in chunks.items():
        i = (cx & 31) + 32 * (cz & 31)
        if (cx, cz) in external:
            blob = struct.pack(">iB", 1, 0x80 | kind)
        else:
            payload = compress(kind, data)
            blob = struct.pack(">iB", len(payload) + 1, kind) + payload
        blob += bytes(-len(blob) % 4096)
        count = len(blob) // 4096
        head[4 * i:4 * i + 4] = (sector << 8 | count).to_bytes(4, "big")
        body += blob
        sector += count
    return bytes(head) + bytes(body)


def write_region(folder: Path, chunks: dict, kind: int = 2, external=()) -> Path:
    """Region files for chunks of any regions under folder (r.X.Z.mca)."""
    folder.mkdir(parents=True, exist_ok=True)
    by = {}
    for (cx, cz), d in chunks.items():
        by.setdefault((cx >> 5, cz >> 5), {})[(cx, cz)] = d
    for (rx, rz), part in by.items():
        (folder / f"r.{rx}.{rz}.mca").write_bytes(region(part, kind, external))
    return folder


def level_dat(folder: Path, version: int) -> None:
    (folder / "level.dat").write_bytes(gzip.compress(nbt({"Data": {"DataVersion": version}})))


# ---- a small build (the GUI test's and the README picture's scene) ---------------
def demo_build(save: Path) -> Path:
    """A 1.18+ save of 3 x 3 chunks: meadow, a cobblestone-and-planks house with glass
    panes, a brick chimney, torches, a lava pit, a pond, a gravel path, an oak tree."""
    W = 48
    world = {}

    def put(x, y, z, name):
        world[(x, y, z)] = "minecraft:" + name

    for x in range(W):
        for z in range(W):
            for y in range(56, 64):
                put(x, y, z, "stone" if y < 61 else "dirt")
            put(x, 64, z, "grass_block")
    # house: x 14..24, z 14..22, floor 65
    for x in range(14, 25):
        for z in range(14, 23):
            put(x, 65, z, "cobblestone")
            edge = x in (14, 24) or z in (14, 22)
            for y in range(66, 70):
                if edge:
                    corner = x in (14, 24) and z in (14, 22)
                    window = y in (67, 68) and (x in (17, 21) or z in (17, 19)) and not corner
                    put(x, y, z, "oak_log" if corner else "glass_pane" if window else "oak_planks")
    for x in range(18, 21):   # door gap facing south (+z)
        for y in (66, 67):
            world.pop((x, y, 22), None)
            world.pop((x - 1, y, 22), None) if x == 18 else None
    # roof: stepped spruce planks and a stone-brick ridge
    for k in range(5):
        for x in range(13 + k, 26 - k):
            for z in range(13, 24):
                put(x, 70 + k, z, "stone_bricks" if k == 4 else "spruce_planks")
    for y in range(66, 78):
        put(22, y, 20, "bricks")
    for x, z in ((13, 18), (25, 18), (19, 23)):
        put(x, 67, z, "torch")
    # lava pit with a cobblestone rim, a pond
    for x in range(30, 35):
        for z in range(28, 33):
            put(x, 64, z, "cobblestone" if x in (30, 34) or z in (28, 32) else "lava")
    for x in range(6, 12):
        for z in range(28, 36):
            if (x - 8.5) ** 2 / 9 + (z - 31.5) ** 2 / 16 < 1:
                put(x, 64, z, "water")
                put(x, 63, z, "clay")
    for z in range(23, 40):   # gravel path south of the door
        for x in (18, 19):
            put(x, 64, z, "gravel")
    # an oak tree
    for y in range(65, 71):
        put(36, y, 12, "oak_log")
    for x in range(33, 40):
        for z in range(9, 16):
            for y in range(69, 73):
                if abs(x - 36) + abs(z - 12) + abs(y - 71) < 5 and (x, y, z) not in world:
                    put(x, y, z, "oak_leaves")
    rng = np.random.default_rng(5)
    for _ in range(60):
        x, z = (int(v) for v in rng.integers(0, W, 2))
        if world.get((x, 64, z)) == "minecraft:grass_block" and (x, 65, z) not in world:
            put(x, 65, z, "poppy" if rng.random() < 0.3 else "short_grass")
    chunks = {}
    for cx in range(3):
        for cz in range(3):
            secs = {}
            for sy in (3, 4):
                a = np.full((16, 16, 16), "minecraft:air", object)
                for (x, y, z), n in world.items():
                    if x >> 4 == cx and z >> 4 == cz and y >> 4 == sy:
                        a[y & 15, z & 15, x & 15] = n
                secs[sy] = a
            chunks[(cx, cz)] = chunk_nbt(cx, cz, secs)
    write_region(save / "region", chunks, 2)
    level_dat(save, 3953)
    return save


# ---- two imports into one world: saves of their own, what a world shows ----------
def dyed_save(save: Path, dye: str, axis: str, biome: str, xs=(0,)) -> Path:
    """A save whose chunks (x, 0) for x in XS hold a layer of `dye` wool over oak logs,
    most along AXIS (their block's default state), a few along the other, in BIOME;
    when XS are several, a chunk of stone in plains first, so that a cluster writer
    commits one batch before the others meet the rest."""
    other = {"x": "z", "z": "x", "y": "x"}[axis]
    logs = np.full((16, 16, 16), f"minecraft:oak_log[axis={axis}]", object)
    logs[0] = f"minecraft:oak_log[axis={other}]"
    wool = np.full((16, 16, 16), f"minecraft:{dye}_wool", object)
    stone = np.full((16, 16, 16), "minecraft:stone", object)
    bio = {y: ([biome], None) for y in (4, 5)}
    chunks = {}
    for i, x in enumerate(xs):
        first = i == 0 and len(xs) > 1
        chunks[(x, 0)] = chunk_nbt(x, 0, {4: stone} if first else {4: logs, 5: wool},
                                   biomes={4: (["minecraft:plains"], None)} if first else bio)
    write_region(save / "region", chunks)
    return save


def shown(path, keys) -> dict:
    """{key: (state of each voxel, rgb of each voxel, biome name of each column)} of
    chunks KEYS of a world, read as the bake and the live view read them."""
    import json
    from voxel_addon.core import colors
    from voxel_addon.core.blocks import REGISTRY
    from voxel_addon.storage import minecraft as mcfile
    from voxel_addon.world import World
    out = {}
    with World.open(path, loader=False, readonly=True) as w:
        meta = w.file.meta
        pal = np.array(json.loads(meta[mcfile.STATES]), object)
        cst = {int(k): v for k, v in json.loads(meta.get(mcfile.COLOR_STATES) or "{}").items()}
        dflt = mcfile.defaults(meta)
        rgb = colors.parse(meta)
        names = np.array(mcfile.names(meta) + [""] * 256, object)
        color = REGISTRY.id("color")
        for k in keys:
            b, d = w.file.read_chunk(k)
            d = np.zeros_like(b) if d is None else d
            st = pal[mcfile.states(b, d, pal.tolist(), cst, color, dflt)]
            out[k] = (st, np.where((b == color)[..., None], rgb[np.minimum(d, len(rgb) - 1)], 0),
                      names[mcfile.read(w.file, k)])
    return out
