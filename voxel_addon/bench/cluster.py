"""Cluster bench (issue 27): whole commands (`generate --backend numpy`, `import` of a
Minecraft region) against workers (`--workers 1`, `--workers 2`: an embedded local
cluster, its start included), and the one writer's ceiling: its whole loop (checks,
palette, commits) fed with results computed beforehand, i.e. the chunks per second
no number of workers can exceed."""
from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]


def _cli(*args) -> float:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "voxel_addon", *map(str, args)],
                       capture_output=True, text=True, env=env)
    if r.returncode:
        raise RuntimeError(r.stderr.strip().splitlines()[-1])
    return time.perf_counter() - t0


class _Replay:
    """A pool that computes each task once in this process (first pass) and then
    hands the same results back instantly: what is left is the writer's own work."""

    size = 1

    def __init__(self):
        self.got = {}

    def map(self, fn, items, *, shared=None, progress=None, window=None):
        for item in items:
            k = repr(item if fn.__name__ == "make" else [x[0] for x in item[0]])
            if k not in self.got:
                self.got[k] = fn(item, shared)
            yield item, self.got[k]


def run(ctx):
    from ..cluster import generate, imports
    from ..world import World
    from .formats import region
    r = 4 if ctx.quick else 16
    n = (2 * r + 1) ** 2
    rows = {}
    for w in (1, 2):
        t = _cli("generate", "--world", ctx.tmp / f"g{w}.sqlite", "--seed", 5, "--radius", r,
                 "--backend", "numpy", "--workers", w)
        rows[("generate", w)] = n / t
        yield (f"cluster_generate_numpy_w{w}_chunks_per_s", n / t, "chunks/s",
               f"whole command, {n} chunks, --workers {w} (cluster start included)")
    yield ("cluster_generate_numpy_speedup_w2", rows[("generate", 2)] / rows[("generate", 1)],
           "x", "--workers 2 over --workers 1")

    side = 12 if ctx.quick else 32
    save = ctx.tmp / "mcc"
    (save / "region").mkdir(parents=True)
    (save / "region" / "r.0.0.mca").write_bytes(region(np.random.default_rng(2), side))
    for w in (1, 2):
        t = _cli("import", "--world", ctx.tmp / f"i{w}.sqlite", "--from", save, "--workers", w)
        rows[("import", w)] = side * side / t
        yield (f"cluster_import_w{w}_chunks_per_s", side * side / t, "chunks/s",
               f"whole command, {side * side} 1.18+ chunks, --workers {w} (cluster start "
               "included)")
    yield ("cluster_import_speedup_w2", rows[("import", 2)] / rows[("import", 1)], "x",
           "--workers 2 over --workers 1")

    # the writer alone
    keys = [(x, y) for x in range(-r, r + 1) for y in range(-r, r + 1)]
    pool = _Replay()
    for i in range(2):
        with World.create(ctx.tmp / f"wg{i}.sqlite", seed=5, backend="numpy",
                          loader=False) as world:
            t0 = time.perf_counter()
            generate.run(world, pool, keys, "numpy")
            t = time.perf_counter() - t0
    yield ("cluster_writer_generate_chunks_per_s", len(keys) / t, "chunks/s",
           "the writer's loop with results ready: existence and edit checks, "
           "one transaction per 64 rows")
    pool = _Replay()
    for i in range(2):
        with World.create(ctx.tmp / f"wi{i}.sqlite", seed=0, generator="empty",
                          loader=False) as world:
            t0 = time.perf_counter()
            rep, _ = imports.run(world, pool, save)
            t = time.perf_counter() - t0
    yield ("cluster_writer_import_chunks_per_s", rep.chunks / t, "chunks/s",
           "the writer's loop with results ready: plan order, report, palette, light rows "
           "dropped, one transaction per 64 chunks (its reading of the region files included)")
