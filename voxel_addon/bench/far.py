"""Bench area `far` (issue 22): the far ring's data side: time from an empty file to
a horizon at far 128 and 256 (alone and beside the near stream), a second view,
the generator's surface rate, triangles per level, memory and file growth."""
from __future__ import annotations

import gc
import os
import time

import numpy as np

from ..far import Builder, grid
from ..generation import make_generator
from ..world import Stream, World

SEED = 7
NEAR = 16
VIEW = (8.0, 8.0)


def _load() -> str:
    return "load average %.1f" % os.getloadavg()[0]


def _horizon(world, far, near=NEAR, drains=None):
    """Seconds from set_view to every wanted tile drained (4 ms drains every 2 ms,
    meshes kept as a consumer keeps them), and the builder and meshes."""
    t0 = time.perf_counter()
    b = Builder(world.file, world.generator)
    b.set_view(*VIEW, far=far, near=near)
    meshes = {}
    while True:
        t = time.perf_counter()
        ready, gone = b.drain(0.004)
        if drains is not None:
            drains.append(time.perf_counter() - t)
        meshes.update((m.key, m) for m in ready)
        for k in gone:
            meshes.pop(k, None)
        if b.error is not None:
            raise b.error
        if b.counts[0] == len(meshes) and b.counts[1] == b.counts[0]:
            break
        time.sleep(0.002)
    return time.perf_counter() - t0, b, meshes


def run(ctx):
    import psutil
    proc = psutil.Process()
    fars = (64, 128) if ctx.quick else (128, 256)
    note_q = " (quick: smaller far)" if ctx.quick else ""
    with World.create(ctx.tmp / "farwarm.sqlite", seed=SEED) as w:  # kernel builds
        _, b, _ = _horizon(w, 8, 0)
        b.close()

    gen = make_generator("overworld", SEED, None, None)
    rng = np.random.default_rng(1)
    for backend in ("opencl", "numpy"):
        g = make_generator("overworld", SEED, None, backend) if backend != gen.backend_used \
            else gen
        xy = rng.integers(-4096, 4096, (65536 if backend == "opencl" else 8192, 2))
        g.surface(xy[:64])
        t = time.perf_counter()
        g.surface(xy)
        dt = time.perf_counter() - t
        yield (f"far_surface_{backend}_columns_per_s", len(xy) / dt, "1/s",
               f"Generator.surface (2D passes pruned to height, block, trees; 1-column "
               f"domains), overworld, {_load()}")

    for far in fars:
        path = ctx.tmp / f"far{far}.sqlite"
        gc.collect()
        rss0 = proc.memory_info().rss
        drains = []
        with World.create(path, seed=SEED) as w:
            dt, b, meshes = _horizon(w, far, drains=drains)
            gc.collect()
            grown = proc.memory_info().rss - rss0
            tris = sum(m.triangles for m in meshes.values())
            mb = sum(m.nbytes for m in meshes.values()) / 2 ** 20
            b.close()
        yield (f"far_horizon{far}_s", dt, "s",
               f"empty file to every far tile drained, far {far} beyond near {NEAR}, "
               f"{len(meshes)} tiles ({b.stats['built']} built), {_load()}{note_q}")
        d = np.array(drains) * 1e3
        yield (f"far_consumer_max_ms{far}", float(d.max()), "ms",
               f"longest drain call (4 ms budget) of {len(d)} while building, p99 "
               f"{np.percentile(d, 99):.2f} ms, {_load()}")
        yield (f"far_triangles{far}", tris, "", "the far ring's triangles (every tile, before "
               "culling), " + ", ".join(
                   f"level {lv} (s={grid.spacing(lv)}): "
                   f"{sum(m.triangles for k, m in meshes.items() if k[0] == lv)}"
                   for lv in grid.LEVELS))
        yield (f"far_mesh_mb{far}", mb, "MiB", f"far meshes' vertex + index bytes "
               f"({mesh_bytes_note()}): the GPU copy is the same size")
        yield (f"far_rss_mb{far}", grown / 2 ** 20, "MiB", "process RSS growth while building "
               "(meshes, builder, generator runner, SQLite cache)")
        yield (f"far_file_mb{far}", os.path.getsize(path) / 2 ** 20, "MiB",
               "world file with only far tables (samples of every tile)")
        with World.open(path) as w:
            dt, b, meshes = _horizon(w, far)
            b.close()
        yield (f"far_second_view{far}_s", dt, "s", f"the same view again: tiles loaded from the "
               f"file ({b.stats['loaded']} loaded, {b.stats['built']} built), {_load()}")

    far = fars[-1]
    with World.create(ctx.tmp / "farstream.sqlite", seed=SEED) as w:
        s = Stream(w, NEAR)
        s.set_view(*VIEW)
        dt, b, meshes = _horizon(w, far)
        b.close()
        s.close()
    yield (f"far_horizon{far}_with_stream_s", dt, "s", f"as far_horizon{far}_s with the near "
           f"stream (distance {NEAR}) working from the same empty file, {_load()}{note_q}")


def mesh_bytes_note() -> str:
    from ..far import mesh
    return f"{mesh.BYTES_PER_VERTEX} B per vertex, 4 B per index"
