"""Bench area `bake`: a 48×48 region of a generated world -> arrays -> .glb (target < 5 s),
and a 256×256 region through the import job (issue 14).

Stages are timed separately (world read/generate, light + meshing, Blender objects,
glTF export) and the whole bake including export is the headline figure. bpy runs
in-process, as in `python -m voxel_addon bake`; without bpy only the array part runs.
The 48×48 rows compare the light atlas (default) with per-vertex light and naive
unit faces. The 256×256 region runs in a child process (its peak RSS is its own)
through blender/job.py's steps, as the modal import runs them, per 64×64 tile.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path



def run(ctx):
    from .. import bake
    from ..world import World
    size = 32 if ctx.quick else 48
    x0, y0 = -size // 2, -size // 2
    x1, y1 = x0 + size, y0 + size
    path = ctx.tmp / "bake.sqlite"
    gen = "overworld"
    try:
        world = World.create(path, seed=2019, generator=gen, loader=False)
    except Exception as e:  # the overworld generator may be missing: flat still measures bake
        ctx.say(f"overworld unavailable ({e}); using flat")
        gen = "flat"
        world = World.create(ctx.tmp / "bake_flat.sqlite", seed=2019, generator=gen, loader=False)
    with world:
        t0 = time.perf_counter()
        blocks = bake.region_of(world, x0, y0, x1, y1)
        t_read = time.perf_counter() - t0
    note = f"{size}x{size} region, {gen} seed 2019"
    t0 = time.perf_counter()
    bk = bake.bake_blocks(blocks, origin=(x0, y0, 0))
    t_arrays = time.perf_counter() - t0
    naive = bake.bake_blocks(blocks, origin=(x0, y0, 0), method="none", light="vertex").triangles
    vert = bake.bake_blocks(blocks, origin=(x0, y0, 0), light="vertex")
    yield ("bake_generate_s", t_read, "s", f"world chunks for {note} (not part of bake)")
    yield ("bake_arrays_s", t_arrays, "s", "light solve + greedy meshing + light atlas")
    yield ("bake_triangles", bk.triangles, "", f"{note}, light atlas (merged quads)")
    yield ("bake_triangles_vertex", vert.triangles, "", f"{note}, per-vertex light (split quads)")
    yield ("bake_triangles_naive", naive, "", f"{note}, unit faces")
    yield ("bake_triangles_pct_naive", 100.0 * bk.triangles / naive, "%",
           "light atlas vs naive; issue 14 target <= 40, goal <= 30")
    yield ("bake_atlas_texels", bk.atlas.shape[0] * bk.atlas.shape[1], "",
           f"{bk.atlas.shape[1]}x{bk.atlas.shape[0]} light atlas")
    yield from lod(ctx)
    try:
        import bpy
    except ImportError:
        ctx.say("no bpy: Blender objects and glTF export not measured")
        return
    from ..blender import bake as BB
    bpy.ops.wm.read_factory_settings(use_empty=True)
    t0 = time.perf_counter()
    objs = BB.build(bk, style="gltf")
    t_objs = time.perf_counter() - t0
    out = ctx.tmp / "bake.glb"
    t0 = time.perf_counter()
    BB.export_glb(out, objs)
    t_exp = time.perf_counter() - t0
    total = t_arrays + t_objs + t_exp
    yield ("bake_objects_s", t_objs, "s", "bpy meshes, attributes, materials")
    yield ("bake_export_s", t_exp, "s", "Blender glTF exporter")
    yield ("bake_48x48_total_s", total, "s", f"{note}; target < 5 s, excl. world generation")
    yield ("bake_glb_bytes", out.stat().st_size, "B", f"{note}, light atlas")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    out_v = ctx.tmp / "bake_vertex.glb"
    BB.export_glb(out_v, BB.build(vert, style="gltf"))
    yield ("bake_glb_bytes_vertex", out_v.stat().st_size, "B", f"{note}, per-vertex light")
    yield from big(ctx)

    def draw(ax):
        parts = [("arrays", t_arrays), ("objects", t_objs), ("export", t_exp)]
        left = 0.0
        for name, t in parts:
            ax.barh(["bake"], [t], left=left, label=f"{name} {t:.2f} s")
            left += t
        ax.axvline(5.0, color="k", ls="--", label="target 5 s")
        ax.set_xlabel("seconds")
        ax.set_title(f"Bake {note}: {bk.triangles} triangles")
        ax.legend()
    ctx.plot("bake_stages", draw)


def lod(ctx):
    """`bake --lod X Y NEAR FAR` without Blender (bake.lod.bake_lod): the near square
    in full, one far object per level; triangles per level and the time."""
    from ..bake import lod as L
    from ..world import World
    near, far = (1, 8) if ctx.quick else (2, 16)
    with World.create(ctx.tmp / "lod.sqlite", seed=2019, generator="overworld",
                      loader=False) as w:
        t0 = time.perf_counter()
        bk, parts = L.bake_lod(w, 8.0, 8.0, near, far, light="vertex")
        t = time.perf_counter() - t0
    note = f"--lod 8 8 {near} {far}, overworld seed 2019 from an empty file"
    yield ("bake_lod_s", t, "s", f"{note}: generate, near bake, far tiles (no Blender)")
    yield ("bake_lod_near_triangles", bk.triangles, "", f"{note}: the near {2 * near + 1}^2 chunks")
    for p in parts:
        yield (f"bake_lod_far{p.level}_triangles", p.triangles, "",
               f"{note}: far level {p.level} ({len(p.water)} of them water)")
    yield ("bake_lod_objects", 1 + len(parts), "", f"{note}: near + one per far level")


BIG = 256


def big(ctx):
    """256×256 (128×128 with --quick) through the import job in a child process."""
    size = BIG // 2 if ctx.quick else BIG
    path = ctx.tmp / f"bake{size}.sqlite"
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[2]))
    r = subprocess.run([sys.executable, "-c",
                        "import sys; from voxel_addon.bench.bake import child; "
                        "child(sys.argv[1], int(sys.argv[2]), sys.argv[3])",
                        str(path), str(size), str(ctx.tmp / f"bake{size}.glb")],
                       capture_output=True, text=True, env=env, timeout=3600)
    if r.returncode != 0:
        ctx.say(f"bake {size}x{size} failed: {r.stderr[-500:]}")
        return
    m = json.loads(r.stdout.strip().splitlines()[-1])
    note = f"{size}x{size} Overworld seed 2019, 64x64 tiles, light atlas"
    yield (f"bake{size}_generate_s", m["generate_s"], "s", f"{note}: generating {m['chunks']} chunks")
    yield (f"bake{size}_bake_s", m["bake_s"], "s", f"{note}: read, light, mesh, atlas, objects")
    yield (f"bake{size}_max_step_s", m["max_step_s"], "s",
           f"{note}: longest single modal step (UI pause)")
    yield (f"bake{size}_export_s", m["export_s"], "s", f"{note}: glTF export")
    yield (f"bake{size}_triangles", m["triangles"], "", f"{note}, {m['objects']} objects")
    yield (f"bake{size}_glb_bytes", m["glb_bytes"], "B", note)
    yield (f"bake{size}_peak_rss_mb", m["peak_mb"], "MB", f"{note}: child process peak RSS")
    yield (f"bake{size}_base_rss_mb", m["base_mb"], "MB", "the same process before the work "
           "(Python, NumPy, bpy loaded)")


def child(path, size, glb):
    """The 256×256 measurement (run in a fresh process): prints one JSON line."""
    import resource

    import bpy

    from ..blender import bake as BB
    from ..blender import job as J
    from ..world import World

    def rss_mb():
        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    bpy.ops.wm.read_factory_settings(use_empty=True)
    base = rss_mb()
    h = size // 2
    region = (-h, -h, size - h, size - h)
    with World.create(path, seed=2019, generator="overworld", loader=False) as w:
        keys = [(cx, cy) for cy in range(region[1] >> 4, ((region[3] - 1) >> 4) + 1)
                for cx in range(region[0] >> 4, ((region[2] - 1) >> 4) + 1)]
        t0 = time.perf_counter()
        w.generate_area(keys)
        t_gen = time.perf_counter() - t0
        job = J.Job(w, region, per="tile", tile=64, style="gltf", generate=False)
        run = J.Runner(job, budget=0.0)  # one step per tick: the longest is a UI pause
        t0 = time.perf_counter()
        longest = 0.0
        while True:
            s0 = time.perf_counter()
            done = run.step()
            longest = max(longest, time.perf_counter() - s0)
            if done:
                break
        t_bake = time.perf_counter() - t0
    import contextlib
    import io
    t0 = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        BB.export_glb(glb, job.objects)
    t_exp = time.perf_counter() - t0
    print(json.dumps({"generate_s": t_gen, "bake_s": t_bake, "max_step_s": longest,
                      "export_s": t_exp, "triangles": job.bake.triangles,
                      "objects": len(job.objects), "chunks": len(keys),
                      "glb_bytes": os.path.getsize(glb), "peak_mb": rss_mb(), "base_mb": base}))
