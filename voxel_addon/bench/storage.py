"""Storage: codec size/speed on generated terrain, chunk loads per second, resident memory."""
from __future__ import annotations

import gc
import time

import numpy as np

from ..core import chunk as C
from ..world import World
from ..storage import codecs

SEED = 2019


def _generator_name() -> str:
    try:
        from ..generation import generator_class
        generator_class("overworld")
        return "overworld"
    except Exception:
        return "flat"


def _cpu_best(f, n: int = 5) -> float:
    """Least process CPU of n calls of f: what a loaded machine's wall time hides."""
    best = float("inf")
    for _ in range(n):
        t0 = time.process_time()
        f()
        best = min(best, time.process_time() - t0)
    return best


def run(ctx):
    import psutil
    gen = _generator_name()
    n_side = 8 if ctx.quick else 24
    path = ctx.tmp / "storage.sqlite"
    keys = [(x, y) for x in range(n_side) for y in range(n_side)]
    with World.create(path, seed=SEED, generator=gen, loader=False) as w:
        t0 = time.perf_counter()
        w.generate_area(keys)
        ctx.say(f"generated {len(keys)} {gen} chunks in {time.perf_counter() - t0:.1f} s")
        sample = [w.file.read_chunk(k)[0] for k in keys[:64]]

    # Codecs on the same real chunks.
    sizes = {}
    for codec in codecs.CODECS:
        blobs = [codecs.encode(codec, C.to_linear(b)) for b in sample]
        t0 = time.perf_counter()
        for _ in range(3):
            for blob in blobs:
                codecs.decode(codec, blob, C.VOLUME * 2)
        dec = (time.perf_counter() - t0) / (3 * len(blobs))
        sizes[codec] = float(np.mean([len(b) for b in blobs]))
        yield (f"codec_{codec}_bytes_per_chunk", sizes[codec], "B", gen)
        yield (f"codec_{codec}_decode_us", dec * 1e6, "us", "per chunk")

        def dec():  # each result dropped at once, as above (kept: fresh 128 KB, page faults)
            for blob in blobs:
                codecs.decode(codec, blob, C.VOLUME * 2)
        yield (f"codec_{codec}_decode_cpu_us", _cpu_best(dec) / len(blobs) * 1e6, "us",
               "per chunk, process CPU, best of 5 passes (load-blind)")

    from ..storage import WorldFile
    wf = WorldFile(path, readonly=True)
    yield ("bytes_per_chunk_disk", path.stat().st_size / len(keys), "B",
           f"{gen}, {codecs.default()}, whole file / chunks")
    # as the world's loader reads: batches of 32, each read at one instant, every
    # chunk decoded into its arrays and checked (read_many: a statement per batch),
    # each dropped before the next (one pass, as earlier revisions measured it:
    # --baseline compares like with like)
    def load():
        for i in range(0, len(keys), 32):
            for k, got in wf.read_many(keys[i:i + 32]):
                if type(got) is not tuple:  # damaged (read_chunk raised) or absent
                    raise RuntimeError(f"chunk {k} of {path}: {got}")

    t0 = time.perf_counter()
    load()
    dt = time.perf_counter() - t0
    cpu = _cpu_best(load)
    wf.close()
    yield ("load_chunks_per_s", len(keys) / dt, "chunks/s",
           "SQLite read + decode, one thread, batches of 32 read at one instant each")
    yield ("load_chunks_cpu_per_s", len(keys) / cpu, "chunks/s",
           "the same loop's process CPU, best of 5 passes (load-blind)")

    # Resident bytes per active voxel: load many chunks into a World, watch RSS.
    proc = psutil.Process()
    gc.collect()
    with World.open(path, loader=False, idle_timeout=1e9) as w:
        rss0 = proc.memory_info().rss
        reps = 2 if ctx.quick else 6      # reuse the file's chunks under other keys
        for r in range(reps):
            for (x, y) in keys:
                blocks, data = w.file.read_chunk((x, y))
                w.chunks[(x + 1000 * r, y)] = C.Chunk((x + 1000 * r, y), blocks, data)
        gc.collect()
        grown = proc.memory_info().rss - rss0
        voxels = len(w.chunks) * C.VOLUME
        w.chunks.clear()
    yield ("bytes_per_voxel_resident", grown / voxels, "B/voxel",
           f"{voxels / 1e6:.0f} M active voxels (thesis: 4.8)")

    def draw(ax):
        ax.bar(list(sizes), [sizes[c] / 1024 for c in sizes])
        ax.set_ylabel("KiB per chunk")
        ax.set_title(f"Compressed chunk size ({gen} terrain)")
    ctx.plot("storage_codecs", draw)
