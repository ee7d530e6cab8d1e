"""Bench area `generation`: Overworld chunks/s per backend and per biome, where the
time goes (per pass kernel), and raw noise throughput. Writes generation_map.png."""
from __future__ import annotations

import time

import numpy as np

from .. import opencl
from ..generation import make_generator, topview
from ..generation import noise as N

SEED = 7
# chunk windows of seed 7 (as in tests/generation): biome -> (cx0, cy0, cx1, cy1)
BIOMES = {"coast+forest": (-8, -20, 8, -4), "desert": (250, -156, 262, -144),
          "mountains": (292, -214, 304, -202), "ocean": (-40, -40, -30, -30)}


def _keys(w, limit):
    cx0, cy0, cx1, cy1 = w
    keys = [(x, y) for y in range(cy0, cy1) for x in range(cx0, cx1)]
    return keys[:limit]


_CPU: dict = {}  # row name -> process CPU ms per chunk of its last _rate


def _rate(gen, keys, reps=2, row=None):
    """Best of reps runs: the machine is shared, the best run is the least disturbed.
    The best run's process CPU (all threads, pocl's too) per chunk goes to _CPU[row]."""
    gen.generate(keys[:4])  # warm-up: kernel compilation, first-launch costs
    best, cpu = 0.0, 1e9
    for _ in range(reps):
        t, c = time.perf_counter(), time.process_time()
        gen.generate(keys)
        best = max(best, len(keys) / (time.perf_counter() - t))
        cpu = min(cpu, 1000 * (time.process_time() - c) / len(keys))
    if row:
        _CPU[row] = cpu
    return best


def _cpu_row(row):
    """The CPU twin of a chunks/s row: less moved by the shared machine's load."""
    return (row.replace("_chunks_per_s", "_cpu_ms_per_chunk"), _CPU[row], "ms",
            "process CPU per chunk (all threads), best run; lower is better")


def run(ctx):
    have_cl = opencl.available()
    n_cl = 64 if ctx.quick else 256
    n_np = 8 if ctx.quick else 24
    if have_cl:
        g = make_generator("overworld", SEED, None, "opencl")
        keys = [(x, y) for y in range(-8, 8) for x in range(-8, 8)][:n_cl]
        yield ("gen_opencl_chunks_per_s", _rate(g, keys, row="gen_opencl_chunks_per_s"),
               "chunks/s", f"Overworld version {g.version}, caves+trees, {len(keys)} chunks, "
               f"batches of {g.batch_cl}, {opencl.describe()}")
        yield _cpu_row("gen_opencl_chunks_per_s")
        for name, w in BIOMES.items():
            ks = _keys(w, n_cl // 2)
            row = f"gen_opencl_{name}_chunks_per_s"
            yield (row, _rate(g, ks, row=row), "chunks/s", f"{len(ks)} chunks of seed {SEED}")
            yield _cpu_row(row)
        # where the time goes: each pass kernel timed alone (queue serialised)
        r = g._runner
        r.timings = {}
        t = time.perf_counter()
        g.generate(keys)
        total = time.perf_counter() - t
        spent = sum(r.timings.values())
        for k, v in r.timings.items():
            yield (f"gen_opencl_ms_per_chunk {k[:60]}", 1000 * v / len(keys), "ms",
                   "kernel (3d: rock+caves, then plants+trees+water; 2d: columns)")
        yield ("gen_opencl_ms_per_chunk host+copy", 1000 * (total - spent) / len(keys), "ms",
               "buffer fills, top/field readbacks for the layer lists, block readback")
        r.timings = None
        yield from _noise(ctx)
    gn = make_generator("overworld", SEED, None, "numpy")
    keys = [(x, y) for y in range(0, 4) for x in range(0, 8)][:n_np]
    yield ("gen_numpy_chunks_per_s", _rate(gn, keys, row="gen_numpy_chunks_per_s"), "chunks/s",
           f"{len(keys)} chunks")
    yield _cpu_row("gen_numpy_chunks_per_s")
    for name, w in BIOMES.items():
        ks = _keys(w, max(4, n_np // 3))
        row = f"gen_numpy_{name}_chunks_per_s"
        yield (row, _rate(gn, ks, row=row), "chunks/s", f"{len(ks)} chunks")
        yield _cpu_row(row)
    _map(ctx, g if have_cl else gn, 8 if ctx.quick else 24)


def _noise(ctx):
    import pyopencl as cl
    from ..generation.clscalar import OPTIONS
    c, q, _ = opencl.context()
    prg = opencl.program("noise.cl", OPTIONS)
    s32 = N.seed32(SEED)
    perm = cl.Buffer(c, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                     hostbuf=N.perm_table(s32))
    shape = (64, 64, 256)
    out = cl.Buffer(c, cl.mem_flags.WRITE_ONLY, 4 * int(np.prod(shape)))
    k = cl.Kernel(prg, "fbm3_grid")
    k(q, shape, None, out, perm, np.uint32(s32), np.float32(1 / 32)).wait()
    best = 1e9
    for _ in range(4):
        t = time.perf_counter()
        k(q, shape, None, out, perm, np.uint32(s32), np.float32(1 / 32)).wait()
        best = min(best, time.perf_counter() - t)
    yield ("noise_opencl_perlin3_4oct_Mvoxels_per_s", np.prod(shape) / best / 1e6, "M/s",
           "4-octave 3D Perlin, gpu/noise.cl fbm3_grid (vectorized by pocl), best of 4")
    x = np.random.default_rng(0).uniform(-100, 100, (3, 1 << 18)).astype(np.float32)
    t = time.perf_counter()
    N.perlin3(x[0], x[1], x[2], N.perm_table(s32), 1)
    yield ("noise_numpy_perlin3_Msamples_per_s", x.shape[1] / (time.perf_counter() - t) / 1e6,
           "M/s", "one octave")


def _map(ctx, g, r):
    keys = [(x, y) for y in range(-r, r) for x in range(-r, r)]
    chunks = g.generate(keys)
    w = 32 * r
    reg = np.zeros((w, w, 256), np.uint16)
    for (x, y), a in zip(keys, chunks):
        reg[16 * (x + r):16 * (x + r) + 16, 16 * (y + r):16 * (y + r) + 16] = a
    img = topview.terrain_rgb(reg)

    def draw(ax):
        ax.imshow(img, extent=(-16 * r, 16 * r, -16 * r, 16 * r))
        ax.set_title(f"Overworld seed {SEED}, {len(keys)} chunks (top view)")
    ctx.plot("generation_map", draw)
