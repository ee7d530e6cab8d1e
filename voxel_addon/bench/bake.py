"""Bench area `bake`: a 48×48 region of a generated world -> arrays -> .glb (target < 5 s).

Stages are timed separately (world read/generate, light + meshing, Blender objects,
glTF export) and the whole bake including export is the headline figure. bpy runs
in-process, as in `python -m voxel_addon bake`; without bpy only the array part runs.
"""
from __future__ import annotations

import time



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
    yield ("bake_generate_s", t_read, "s", f"world chunks for {note} (not part of bake)")
    yield ("bake_arrays_s", t_arrays, "s", "light solve + greedy meshing + vertex light")
    yield ("bake_triangles", bk.triangles, "", note)
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
    yield ("bake_glb_bytes", out.stat().st_size, "B", note)

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
