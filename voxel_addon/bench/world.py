"""Bench area `world` (issue 11): streaming a view from an empty and from a generated
file, the consumer's drain times, resident memory, and edit -> payload latency."""
from __future__ import annotations

import gc
import os
import time

import numpy as np

from ..core import chunk as C
from ..core.blocks import REGISTRY
from ..world import Stream, World
from ..world.edit import edit

SEED = 7
BUDGET = 0.004  # the consumer's drain budget per call (4 ms)
EDITS_ONLY = "VOXEL_BENCH_EDITS_ONLY"  # set: only the edit rows, on a view-8 world


def _load() -> str:
    return "load average %.1f" % os.getloadavg()[0]


def _cpu() -> float:
    t = os.times()
    return t.user + t.system


def _stream(world, distance, drains=None, workers=2, backends=None):
    """Time from set_view to every wanted payload drained; the consumer drains with a
    4 ms budget every 2 ms and drops the payloads (as an upload would). Returns
    (stream, wall seconds, process CPU seconds: all threads, pocl's included)."""
    c0 = _cpu()
    t0 = time.perf_counter()
    s = Stream(world, distance, workers=workers, backends=backends)
    s.set_view(8.0, 8.0, direction=(1.0, 0.3, 0.0))
    while True:
        c = time.thread_time()
        t = time.perf_counter()
        ready, _ = s.drain(BUDGET)
        if drains is not None:
            # wall and the consumer thread's CPU: on a loaded machine the longest
            # wall call is the one the OS preempted (issue 29: ms of wall, 0.03 ms CPU)
            drains.append((time.perf_counter() - t, time.thread_time() - c))
        del ready
        if s.error is not None:
            raise s.error
        w, r, d = s.counts
        if d >= w:
            break
        time.sleep(0.002)
    dt = time.perf_counter() - t0
    return s, dt, _cpu() - c0


def _warm(path):
    """Kernel builds and first launches outside the timings."""
    with World.create(path, seed=SEED) as w:
        s, _, _ = _stream(w, 1)
        s.close()


def _without_opencl(ctx):
    """The live view's first fill at its default distance (8 chunks) from an empty
    file, with OpenCL and without it (as on a Mac or a Windows machine without an
    OpenCL driver: NumPy generates and meshes; light is NumPy either way)."""
    from .. import opencl
    dist = 4 if ctx.quick else 8
    n = (2 * dist + 1) ** 2
    for backend in opencl.usable():
        with World.create(ctx.tmp / f"first_{backend}.sqlite", seed=SEED, backend=backend) as w:
            s, dt, cpu = _stream(w, dist, backends=("numpy", backend))
            s.close()
        yield (f"stream_view{dist}_{backend}_s", dt, "s",
               f"{n} chunks generated ({backend}), lit (numpy), meshed ({backend}) from an "
               f"empty file: the first fill of a new world's view, {_load()}")


def run(ctx):
    if os.environ.get(EDITS_ONLY):
        yield from _edits_only(ctx)
        return
    import psutil
    far = 12 if ctx.quick else 32
    near = 8 if ctx.quick else 16
    _warm(ctx.tmp / "warm.sqlite")
    note_q = " (quick: smaller distance)" if ctx.quick else ""

    path = ctx.tmp / "world16.sqlite"
    with World.create(path, seed=SEED) as w:
        s, dt, cpu = _stream(w, near)
        s.close()
    n = (2 * near + 1) ** 2
    yield ("stream_view16_s", dt, "s", f"{n} chunks generated, lit, meshed from an empty file, "
           f"{_load()}{note_q}")
    yield ("stream_view16_cpu_s", cpu, "s", "process CPU time of the same (all threads): the "
           "work, whatever else runs on the machine")

    yield from _without_opencl(ctx)

    path = ctx.tmp / "world32.sqlite"
    proc = psutil.Process()
    gc.collect()
    rss0 = proc.memory_info().rss
    drains: list = []
    w = World.create(path, seed=SEED)
    s, dt, cpu = _stream(w, far, drains)
    gc.collect()
    grown = proc.memory_info().rss - rss0
    voxels = len(w.chunks) * C.VOLUME
    n = (2 * far + 1) ** 2
    yield ("stream_view32_s", dt, "s", f"{n} chunks from an empty file, 2 workers, "
           f"{_load()} (target 10 s){note_q}")
    yield ("stream_view32_cpu_s", cpu, "s", "process CPU time of the same (all threads)")
    d, dc = (np.array(drains) * 1e3).T
    yield ("stream_consumer_max_ms", float(d.max()), "ms",
           f"longest drain call, 4 ms budget, {len(d)} calls, p99 {np.percentile(d, 99):.2f} ms "
           f"(target 8 ms), {_load()}")
    yield ("stream_consumer_max_cpu_ms", float(dc.max()), "ms",
           "the consumer thread's CPU time in its longest drain (by CPU) of the same: the "
           "drain's own work (a batch's 64 payloads), without the OS's preemptions")
    yield ("resident_bytes_per_voxel", grown / voxels, "B/voxel",
           f"RSS growth / active voxels ({len(w.chunks)} chunks: blocks + final light "
           f"(compact: its non-uniform layers) + meshes kept for edits)")

    yield from _edits(ctx, w)
    s.close()
    t0 = time.perf_counter()
    w.close()
    yield ("world_close_save_s", time.perf_counter() - t0, "s",
           f"saving the {n}+ generated chunks at close")

    with World.open(path) as w:
        s, dt, cpu = _stream(w, far)
        s.close()
    yield ("stream_reload_view32_s", dt, "s", f"{n} chunks loaded from the file (blocks + stored "
           f"light), meshed, {_load()} (target 8 s){note_q}")
    yield ("stream_reload_view32_cpu_s", cpu, "s", "process CPU time of the same (all threads)")


def clicks(w, n: int):
    """The bench's n single-block edits near the surface of world w, in turn: clear,
    lamp, solid (also tools/edit_profile.py's)."""
    rng = np.random.default_rng(3)
    lamps = [REGISTRY.id(n) for n in ("lamp_red", "lamp_green", "lamp_blue", "glowstone")
             if n in REGISTRY.names()] or [REGISTRY.id("lamp_red")]
    solid = [REGISTRY.id(n) for n in ("stone", "glass", "planks", "dirt") if n in REGISTRY.names()]
    for i in range(n):
        x, y = int(rng.integers(-120, 120)), int(rng.integers(-120, 120))
        c = w.chunk_at(x >> 4, y >> 4)
        z = int(np.flatnonzero(c.blocks[x & 15, y & 15])[-1])
        kind = i % 3
        yield ((x, y, z, 0) if kind == 0 else
               (x, y, z + 1, int(rng.choice(lamps))) if kind == 1 else
               (x, y, z + 1, int(rng.choice(solid))))


def _edits(ctx, w):
    """Single-block edits near the surface (clear, lamp, solid), the stream idle."""
    times, cpus = [], []
    for change in clicks(w, 40 if ctx.quick else 120):
        c, t = time.thread_time(), time.perf_counter()
        payloads, _ = edit(w, change)
        times.append(time.perf_counter() - t)
        cpus.append(time.thread_time() - c)
        settle = getattr(w, "settle", None)  # the write goes on after the payloads (issue 29):
        if settle:                           # let it end before the next click, as a user's
            settle()                         # clicks are far apart
    t = np.array(times) * 1e3
    note = f"{len(t)} single-block edits at the surface (clear, lamp, solid), {_load()}"
    yield ("edit_to_payload_median_ms", float(np.median(t)), "ms", note + " (target 5 ms)")
    yield ("edit_to_payload_p90_ms", float(np.percentile(t, 90)), "ms", note + " (target 20 ms)")
    yield ("edit_to_payload_median_cpu_ms", float(np.median(cpus) * 1e3), "ms",
           "CPU time of the editing thread (OpenCL meshing's pocl threads and the world's "
           "writer thread, which saves the edit after its payloads, not included)")
    lamp = np.arange(len(cpus)) % 3 == 1  # every third edit sets a lamp
    for name, m in (("lamp", lamp), ("other", ~lamp)):
        yield (f"edit_to_payload_{name}_median_cpu_ms", float(np.median(np.array(cpus)[m]) * 1e3),
               "ms", f"the same, the {int(m.sum())} edits that set a lamp" if name == "lamp"
               else f"the same, the {int(m.sum())} others (clear, solid)")


def _edits_only(ctx):
    """The edit rows alone (env VOXEL_BENCH_EDITS_ONLY): the same edits on a world
    streamed to distance 8 (it covers the edited square), the stream kept open idle."""
    _warm(ctx.tmp / "warm.sqlite")
    with World.create(ctx.tmp / "edits.sqlite", seed=SEED) as w:
        s, _, _ = _stream(w, 8)
        yield from _edits(ctx, w)
        s.close()
