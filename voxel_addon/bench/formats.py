"""Import bench (issue 21): a synthetic Minecraft region of 32 x 32 full 1.18+ chunks
(24 sections, palettes of 2-9 entries, surface with plants and air above; zlib, as
Minecraft writes it) imported into a new world (chunks/s, the whole import path:
read, inflate, NBT, unpack, map, encode, one transaction per batch of 32), and a
.vox round trip (import a 64^3 model half full, export it again)."""
from __future__ import annotations

import struct
import time
import zlib

import numpy as np

_NAMES = ["minecraft:stone", "minecraft:deepslate", "minecraft:dirt", "minecraft:granite",
          "minecraft:andesite", "minecraft:coal_ore", "minecraft:iron_ore", "minecraft:gravel",
          "minecraft:grass_block", "minecraft:short_grass", "minecraft:oak_log",
          "minecraft:oak_leaves", "minecraft:water", "minecraft:air"]


def _s(v: str) -> bytes:
    b = v.encode()
    return struct.pack(">H", len(b)) + b


def _section(rng, y) -> bytes:
    if y < 4:
        pal = _NAMES[:8] if y >= 0 else _NAMES[:2]
        idx = rng.integers(0, len(pal), 4096)
    elif y < 6:
        pal = _NAMES[8:]
        idx = np.where(rng.random(4096) < 0.7, len(pal) - 1, rng.integers(0, len(pal), 4096))
    else:
        pal, idx = ["minecraft:air"], None
    out = b"\x01" + _s("Y") + struct.pack(">b", y) + b"\x0a" + _s("block_states")
    out += b"\x09" + _s("palette") + b"\x0a" + struct.pack(">i", len(pal))
    out += b"".join(b"\x08" + _s("Name") + _s(n) + b"\x00" for n in pal)
    if idx is not None:
        bits = max(4, (len(pal) - 1).bit_length())
        per = 64 // bits
        idx = np.concatenate([idx, np.zeros(-len(idx) % per, np.int64)]).reshape(-1, per)
        words = (idx.astype(np.uint64) << (np.arange(per, dtype=np.uint64) * np.uint64(bits))
                 ).sum(1, dtype=np.uint64)
        out += b"\x0c" + _s("data") + struct.pack(">i", len(words)) + words.astype(">u8").tobytes()
    return out + b"\x00" + b"\x0a" + _s("biomes") + b"\x00" + b"\x00"


def chunk_nbt(rng, cx, cz) -> bytes:
    body = b"\x03" + _s("DataVersion") + struct.pack(">i", 3953)
    body += b"\x03" + _s("xPos") + struct.pack(">i", cx) + b"\x03" + _s("zPos") + struct.pack(">i", cz)
    body += b"\x08" + _s("Status") + _s("minecraft:full")
    body += b"\x09" + _s("sections") + b"\x0a" + struct.pack(">i", 24)
    body += b"".join(_section(rng, y) for y in range(-4, 20))
    return b"\x0a" + _s("") + body + b"\x00"


def region(rng, n=32) -> bytes:
    head = bytearray(8192)
    body = bytearray()
    sector = 2
    for cz in range(n):
        for cx in range(n):
            p = zlib.compress(chunk_nbt(rng, cx, cz), 6)
            blob = struct.pack(">iB", len(p) + 1, 2) + p
            blob += bytes(-len(blob) % 4096)
            head[4 * (cx + 32 * cz):4 * (cx + 32 * cz) + 4] = (sector << 8 | len(blob) // 4096
                                                                ).to_bytes(4, "big")
            body += blob
            sector += len(blob) // 4096
    return bytes(head + body)


def run(ctx):
    from ..formats import magica, minecraft, vox
    from ..world import World
    rng = np.random.default_rng(1)
    n = 16 if ctx.quick else 32
    folder = ctx.tmp / "mc" / "region"
    folder.mkdir(parents=True)
    (folder / "r.0.0.mca").write_bytes(region(rng, n))
    times = []
    for i in range(1 if ctx.quick else 3):
        path = ctx.tmp / f"mc{i}.sqlite"
        t0 = time.perf_counter()
        with World.create(path, seed=0, generator="empty", loader=False) as w:
            rep = minecraft.import_world(w, folder.parent)
        times.append(time.perf_counter() - t0)
    t = float(np.median(times))
    yield ("import_minecraft_chunks_per_s", rep.chunks / t, "chunks/s",
           f"median of {len(times)}: a {n}x{n} region of 1.18+ chunks ({rep.chunks}), "
           f"{(folder / 'r.0.0.mca').stat().st_size >> 20} MB, into a new world")
    yield ("import_minecraft_region_s", t, "s", f"the same {n}x{n} region")
    grid = np.where(rng.random((64, 64, 64)) < 0.5, rng.integers(1, 256, (64, 64, 64)), 0)
    src = ctx.tmp / "m.vox"
    src.write_bytes(vox.write(grid.astype(np.uint8), rng.integers(0, 256, (256, 3))))
    with World.create(ctx.tmp / "vox.sqlite", seed=0, generator="empty", loader=False) as w:
        t0 = time.perf_counter()
        r = magica.import_vox(w, src, (0, 0, 10))
        ti = time.perf_counter() - t0
        t0 = time.perf_counter()
        magica.export_vox(w, (0, 0, 10, 64, 64, 74), ctx.tmp / "out.vox")
        te = time.perf_counter() - t0
    yield ("import_vox_voxels_per_s", r["voxels"] / ti, "voxels/s",
           f"a 64^3 model, {r['voxels']} voxels, kept as edits, one transaction")
    yield ("export_vox_voxels_per_s", r["voxels"] / te, "voxels/s", "the same box out again")
