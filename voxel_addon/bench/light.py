"""Light bench: full relight (chunks/s per backend), edit relight (ms), stored vs
recomputed light per chunk (decompress a zstd light column vs relight)."""
from __future__ import annotations

import time

import numpy as np

from ..core import chunk


def _terrain(n, ctx):
    """(16n, 16n, 256) freshly generated terrain: the Overworld if present, else the
    light package's synthetic terrain."""
    try:
        from ..generation import make_generator
        gen = make_generator("overworld", 1, backend=None)
        keys = [(cx, cy) for cy in range(n) for cx in range(n)]
        b = chunk.paste(zip(keys, gen.generate(keys)), 0, 0, n, n)
        return b, "overworld"
    except Exception as e:  # generator not there yet
        ctx.say(f"overworld unavailable ({e}); synthetic terrain")
        from ..light import scenes
        return scenes.terrain(16 * n, 16 * n, 1), "synthetic"


def run(ctx):
    from .. import opencl
    from ..core.blocks import REGISTRY as R
    from ..light import full, incremental
    n = 6 if ctx.quick else 10
    b, kind = _terrain(n, ctx)
    inner = (n - 2) ** 2
    backends = opencl.usable()
    rates = {}
    for be in backends:
        full.region_light(b, be)  # warm-up (kernel build)
        ts, cpu = [], []
        for _ in range(3 if ctx.quick else 5):
            t, c = time.perf_counter(), time.process_time()
            full.region_light(b, be)
            ts.append(time.perf_counter() - t)
            cpu.append(time.process_time() - c)
        rates[be] = inner / min(ts)
        note = f"{kind} {n}x{n} chunks, {inner} interior, tiles of 8x8 (+1 ring)"
        if be == "opencl":
            from ..light import cl
            note += f", {cl.STATS['sweeps']} line sweeps"
        yield (f"light_full_{be}", rates[be], "chunks/s", note)
        # CPU time moves far less with the machine's load than the wall time above
        yield (f"light_full_{be}_cpu_ms", min(cpu) * 1e3 / inner, "ms",
               "process CPU (all threads, pocl's included) per interior chunk, best run")
    # Edit relight: random places/removals near the surface, lamps included.
    L = full.solve(b)
    rng = np.random.default_rng(0)
    ids = [0, 0, R.id("stone"), R.id("lamp_red"), R.id("lamp_white"), R.id("glass"), R.id("water")]
    ts, cpu = [], []
    while len(ts) < (40 if ctx.quick else 150):
        x, y = (int(v) for v in rng.integers(16, b.shape[0] - 16, 2))
        top = int(np.flatnonzero(b[x, y])[-1])
        z = int(rng.integers(max(top - 12, 0), min(top + 3, 255)))
        new = int(rng.choice(ids))
        if b[x, y, z] == new:  # a no-op edit would flatter the figures
            continue
        t, c = time.perf_counter(), time.process_time()
        incremental.edit(b, L, x, y, z, new)
        ts.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    ts, cpu = np.array(ts) * 1e3, np.array(cpu) * 1e3
    yield ("light_edit_median", float(np.median(ts)), "ms",
           "numpy incremental, near surface, block-changing edits only")
    yield ("light_edit_p90", float(np.percentile(ts, 90)), "ms", "")
    # CPU time of the same edits: wall time on a shared machine includes preemption.
    yield ("light_edit_cpu_median", float(np.median(cpu)), "ms", "process CPU time")
    yield ("light_edit_cpu_p90", float(np.percentile(cpu, 90)), "ms", "")
    # Stored vs recomputed: per chunk cost of reading a stored zstd light column.
    import zstandard
    chunks = [np.asfortranarray(L[i * 16:(i + 1) * 16, j * 16:(j + 1) * 16])
              for i in range(1, n - 1) for j in range(1, n - 1)]
    blobs = [zstandard.ZstdCompressor(level=3).compress(chunk.to_linear(c)) for c in chunks]
    d = zstandard.ZstdDecompressor()
    t = time.perf_counter()
    for blob in blobs:
        chunk.from_linear(d.decompress(blob))
    load = (time.perf_counter() - t) / len(blobs)
    yield ("light_stored_load", load * 1e3, "ms/chunk", "zstd-3 decompress of a light column")
    yield ("light_stored_size", float(np.mean([len(x) for x in blobs])), "B/chunk", "zstd-3")
    best = max(rates.values())
    yield ("light_recompute", 1e3 / best, "ms/chunk", "region relight, best backend")

    def draw(ax):
        ax.bar(list(rates), list(rates.values()))
        ax.axhline(200, color="r", ls="--", label="goal 200 chunks/s")
        ax.set_ylabel("chunks/s")
        ax.set_title("full relight")
        ax.legend()
    ctx.plot("light_full", draw)
