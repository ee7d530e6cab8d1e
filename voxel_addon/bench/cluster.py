"""Cluster bench (issue 27): whole commands against workers: `generate --backend numpy`,
`import` of a Minecraft save, `far`, `bake --per tile --out DIR` and `animate`, each
in one process (no flag: the reference), on `--workers 1` and on `--workers 2` (an
embedded local cluster, its start included); and the one writer's ceiling: its whole
loop (checks, palette, commits) fed with results computed beforehand, i.e. the chunks
per second no number of workers can exceed. Each command's three runs follow each
other, so their ratios are the figures to compare (the machine is shared: absolute
times move with its load, noted in each row)."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
FLAGS = {"one": (), "w1": ("--workers", 1), "w2": ("--workers", 2)}


def _env():
    return dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))


def _cli(*args) -> tuple[float, float, float]:
    """Runs the command; (wall seconds, CPU seconds of its own process: the writer, its
    client and, for --workers, the scheduler; CPU seconds of every process, workers and
    helpers included). CPU is read from the processes every 50 ms (the last 50 ms of a
    process may be missed): unlike wall time it hardly moves with the machine's load."""
    import tempfile
    import psutil
    log = tempfile.TemporaryFile("w+")  # not a pipe: nothing blocks while we poll
    t0 = time.perf_counter()
    p = subprocess.Popen([sys.executable, "-m", "voxel_addon", *map(str, args)],
                         stdout=subprocess.DEVNULL, stderr=log, text=True, env=_env())
    cpu: dict = {}
    me = psutil.Process(p.pid)

    def seen(q):
        try:
            t = q.cpu_times()
            cpu[q.pid] = t.user + t.system
        except psutil.Error:
            pass
    while p.poll() is None:
        try:
            kids = me.children(recursive=True)
        except psutil.Error:
            kids = []
        for q in [me, *kids]:
            seen(q)
        time.sleep(0.05)
    t = time.perf_counter() - t0
    log.seek(0)
    err = log.read()
    log.close()
    if p.returncode:
        raise RuntimeError((err.strip().splitlines() or ["failed"])[-1])
    return t, cpu.get(p.pid, 0.0), sum(cpu.values())


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def _scaling(name, n, unit, what, command):
    """Rows of one command run in one process, on 1 and on 2 workers: `command(tag,
    flags)` runs it once (a fresh output each) and returns _cli's figures."""
    per = {}
    for tag, flags in FLAGS.items():
        t, own, cpu = command(tag, flags)
        per[tag] = n / t
        how = "one process (no flag)" if tag == "one" else f"--workers {flags[1]}"
        yield (f"cluster_{name}_{tag}_{unit}_per_s", n / t, f"{unit}/s",
               f"whole command, {what}, {how} ({_load()} after)")
        yield (f"cluster_{name}_{tag}_cpu_s", cpu, "s",
               f"CPU of all its processes, {how}")
        if tag != "one":
            yield (f"cluster_{name}_{tag}_writer_cpu_s", own, "s",
                   f"CPU of the command's own process (writer, client, scheduler, process "
                   f"start), {how}")
            # per item, start included (the README subtracts a tiny run's to leave it out)
            yield (f"cluster_{name}_{tag}_writer_cpu_ms_per_{unit[:-1]}", 1e3 * own / n, "ms",
                   f"the command's own process per {unit[:-1]}, {how}")
            yield (f"cluster_{name}_{tag}_workers_cpu_ms_per_{unit[:-1]}", 1e3 * (cpu - own) / n,
                   "ms", f"every other process (workers, forkserver) per {unit[:-1]}, {how}")
    yield (f"cluster_{name}_speedup_w2", per["w2"] / per["w1"], "x",
           "--workers 2 over --workers 1, same run (cluster start included in both)")
    yield (f"cluster_{name}_w2_over_one", per["w2"] / per["one"], "x",
           "--workers 2 over one process, same run")


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


def save(folder: Path, side: int, regions: int) -> int:
    """A 1.18+ save of REGIONS region files, each SIDE x SIDE synthetic chunks (one
    region's bytes copied to other region coordinates: the importer places a chunk
    by its file's name). Returns the number of chunks."""
    from .formats import region
    data = region(np.random.default_rng(2), side)
    (folder / "region").mkdir(parents=True)
    for i in range(regions):
        (folder / "region" / f"r.{i % 2}.{i // 2}.mca").write_bytes(data)
    return side * side * regions


BLEND = '''
import math, sys
import bpy
import voxel_addon
out, n = sys.argv[1], int(sys.argv[2])
bpy.ops.wm.read_factory_settings(use_empty=True)
voxel_addon.register()
sc = bpy.context.scene
vv = sc.voxel_view
vv.follow_timeline, vv.frames_per_day, vv.hours, vv.distance = True, 4 * n, 9.0, 4
cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
sc.collection.objects.link(cam)
sc.camera = cam
cam.rotation_euler = (math.radians(60.0), 0.0, math.radians(-30.0))
for f, x in ((1, -40.0), (n, 40.0)):
    cam.location = (x, -60.0, 110.0)
    cam.keyframe_insert("location", frame=f)
sc.frame_start, sc.frame_end = 1, n
sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 320, 180, 100
bpy.ops.wm.save_as_mainfile(filepath=out)
'''


def _blend(ctx, n):
    """A .blend whose camera flies 80 blocks over N frames (the day cycle moving), or
    None without bpy."""
    out = ctx.tmp / "fly.blend"
    r = subprocess.run([sys.executable, "-c", BLEND, str(out), str(n)], capture_output=True,
                       text=True, env=_env(), timeout=300)
    if r.returncode or not out.is_file():
        ctx.say(f"no .blend for animate (bpy?): {r.stderr.strip()[-300:]}")
        return None
    return out


def run(ctx):
    yield from commands(ctx)
    yield from writer(ctx)


def commands(ctx):
    q = ctx.quick
    r = 4 if q else 16
    n = (2 * r + 1) ** 2
    yield from _scaling("generate_numpy", n, "chunks", f"{n} chunks, NumPy",
                        lambda tag, fl: _cli("generate", "--world", ctx.tmp / f"g{tag}.sqlite",
                                             "--seed", 5, "--radius", r, "--backend", "numpy",
                                             *fl))

    side, regions = (12, 1) if q else (32, 4)
    n = save(ctx.tmp / "mcc", side, regions)
    yield from _scaling("import", n, "chunks", f"{n} synthetic 1.18+ chunks in {regions} "
                        f"region files of {side}x{side}",
                        lambda tag, fl: _cli("import", "--world", ctx.tmp / f"i{tag}.sqlite",
                                             "--from", ctx.tmp / "mcc", *fl))

    # a world whose chunks the far tiles, the bake and the frames read
    world = ctx.tmp / "w.sqlite"
    _cli("generate", "--world", world, "--seed", 5, "--radius", 4 if q else 8,
         "--backend", "numpy")
    far = 16 if q else 64

    def far_cmd(tag, fl):
        w = ctx.tmp / f"far{tag}.sqlite"
        shutil.copy(world, w)
        return _cli("far", "--world", w, "--center", 0, 0, "--far", far, "--backend", "numpy",
                    *fl)
    tiles = _far_tiles(far)
    yield from _scaling("far", tiles, "tiles", f"{tiles} far tiles (far {far}, NumPy)", far_cmd)

    try:
        import bpy  # noqa: F401 - bake and animate need it (workers too)
    except ImportError:
        ctx.say("no bpy: cluster bake and animate rows not measured")
        return
    # big enough that each worker's own start (bpy in its helper process, a GL context
    # and the world's copy) is not the whole story
    h = 32 if q else 128
    region = (-64, -h, 64, h) if q else (-h, -h, h, h)
    tiles = len(range(region[0], region[2], 64)) * len(range(region[1], region[3], 64))
    yield from _scaling("bake_tiles", tiles, "tiles", f"{tiles} tiles of 64x64 columns",
                        lambda tag, fl: _cli("bake", "--world", world, "--region", *region,
                                             "--per", "tile", "--out", ctx.tmp / f"t{tag}",
                                             *fl))
    frames = 4 if q else 48
    blend = _blend(ctx, frames)
    if blend is None:
        return
    yield from _scaling("animate", frames, "frames", f"{frames} frames of 320x180, distance 4",
                        lambda tag, fl: _cli("animate", "--world", world, "--blend", blend,
                                             "--out", ctx.tmp / f"f{tag}", *fl))


def _far_tiles(far) -> int:
    """How many tiles `far --far FAR` builds around 0 0 (as cluster.far.run selects)."""
    from ..far import grid
    return len(grid.select(0, 0, far, 0))


def writer(ctx):
    """The writer alone: its loop fed with ready results."""
    from ..cluster import generate, imports
    from ..world import World
    r = 4 if ctx.quick else 16
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
    src = ctx.tmp / "mcw"
    save(src, 12 if ctx.quick else 32, 1)
    for i in range(2):
        with World.create(ctx.tmp / f"wi{i}.sqlite", seed=0, generator="empty",
                          loader=False) as world:
            from ..formats.minecraft import Report
            rep = Report()
            t0 = time.perf_counter()
            imports.run(world, pool, src, report=rep)
            t = time.perf_counter() - t0
    yield ("cluster_writer_import_chunks_per_s", rep.chunks / t, "chunks/s",
           "the writer's loop with results ready: plan order, report, palette, states, "
           "one transaction per 64 chunks (its reading of the region files included; data "
           "blobs encoded by the workers, as once the first tasks are back)")
