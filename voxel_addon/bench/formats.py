"""Import bench (issue 21): a synthetic Minecraft region of 32 x 32 full 1.18+ chunks
(24 sections, palettes of 2-9 entries, surface with plants and air above; zlib, as
Minecraft writes it) imported into a new world (chunks/s, the whole import path:
read, inflate, NBT, unpack, map, encode, one transaction per batch of 32), and a
.vox round trip (import a 64^3 model half full, export it again).

`import_mc_states_*` (issue 30): a survival-like 1.21 region (bench/mcsave.py: layered
terrain, ore and stone blobs, caves, sea, trees, huts, block states and section
biomes, 16 x 16 chunks, 8 x 8 with --quick) imported with its states and biomes kept:
chunks/s (wall and CPU), the world file's bytes per chunk (and its small-data blobs
alone), the import's peak traced memory (NumPy and Python, tracemalloc) and the
resident arrays of a loaded imported chunk."""
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
    yield from states(ctx)
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


def states(ctx):
    """The import_mc_states_* rows (module docstring)."""
    import sqlite3
    import tracemalloc
    from . import mcsave
    from ..formats import minecraft
    from ..world import World
    n = 8 if ctx.quick else 16
    save = mcsave.save(ctx.tmp / "mcstates", n)
    wall, cpu = [], []
    for i in range(1 if ctx.quick else 3):
        path = ctx.tmp / f"mcs{i}.sqlite"
        t0, c0 = time.perf_counter(), time.process_time()
        with World.create(path, seed=0, generator="empty", loader=False) as w:
            rep = minecraft.import_world(w, save)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    note = f"{n}x{n} survival-like 1.21 chunks (bench/mcsave.py), states and biomes kept"
    yield ("import_mc_states_chunks_per_s", rep.chunks / float(np.median(wall)), "chunks/s",
           f"median of {len(wall)}: {note}; issue 30 goal >= 300")
    yield ("import_mc_states_cpu_chunks_per_s", rep.chunks / float(np.median(cpu)), "chunks/s",
           "the same, per second of this process's CPU time (less sensitive to load)")
    with sqlite3.connect(path) as db:
        blocks, data, nd = db.execute("SELECT SUM(LENGTH(blocks)), SUM(COALESCE(LENGTH(data), 0)),"
                                      " SUM(data IS NOT NULL) FROM chunks").fetchone()
    yield ("import_mc_states_file_bytes_per_chunk", path.stat().st_size / rep.chunks, "B",
           f"world file size / chunks ({note})")
    yield ("import_mc_states_data_bytes_per_chunk", data / rep.chunks, "B",
           f"small-data blobs alone (states other than their block's default), {nd} of "
           f"{rep.chunks} chunks have one; blocks blobs {blocks / rep.chunks:.0f} B")
    tracemalloc.start()
    with World.create(ctx.tmp / "mcs_mem.sqlite", seed=0, generator="empty", loader=False) as w:
        minecraft.import_world(w, save)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    yield ("import_mc_states_peak_mb", peak / 2 ** 20, "MB",
           f"traced peak of the import ({rep.chunks} chunks, batches of {minecraft.BATCH})")
    with World.open(path, loader=False, readonly=True) as w:
        keys = list(w.file.chunk_keys())
        tracemalloc.start()
        got = [w.file.read_chunk(k) for k in keys]
        held = tracemalloc.get_traced_memory()[0]
        tracemalloc.stop()
    yield ("import_mc_states_loaded_kb_per_chunk", held / len(got) / 1024, "KiB",
           "blocks + small data of an imported chunk read back (data None when all default)")
