"""bake: a block region -> .glb through Blender's own glTF exporter (bpy in-process);
--per tile --out DIR: one .glb per 64×64 tile, in this process or on a Dask cluster."""
from __future__ import annotations

import contextlib
import io
import tempfile
import threading
import time
from pathlib import Path

from ..core.errors import VoxelError
from .common import Progress, add_world, coord, note, out_file, write_out


def add_parser(sub):
    from ..meshing import METHODS
    p = sub.add_parser("bake", help="bake a block region into a glTF binary (.glb) with bpy")
    add_world(p)
    p.add_argument("--region", type=coord, nargs=4, metavar=("X0", "Y0", "X1", "Y1"),
                   help="half-open block columns [X0,X1) x [Y0,Y1), full height")
    p.add_argument("--lod", type=coord, nargs=4, metavar=("X", "Y", "NEAR", "FAR"),
                   help="instead of --region: the chunks within NEAR of block (X, Y) in full, "
                        "far terrain beyond out to FAR chunks, one object per level")
    p.add_argument("--out", type=Path, required=True, metavar="F.glb|DIR",
                   help="output .glb; with --per tile a folder takes one tile_X_Y.glb per "
                        "tile (X Y: its first block column; tiles already there are kept)")
    p.add_argument("--per", choices=("region", "chunk", "tile"), default="region",
                   help="one object for the region (default), one per chunk, or one per "
                        "64×64 tile (big regions)")
    p.add_argument("--method", default="greedy", choices=METHODS,
                   help="face aggregation (default greedy)")
    p.add_argument("--instances", action="store_true", help="plants as GPU instances")
    p.add_argument("--light", choices=("atlas", "vertex"), default="atlas",
                   help="light in a texture on a second UV set, quads stay merged (default), "
                        "or per vertex (quads split where light varies; for tools that "
                        "ignore a second UV set)")
    p.add_argument("--time", default="12:00", help="time of day of the exported light (HH:MM)")
    p.add_argument("--blend", type=Path, help="also save the baked scene as this .blend")
    from .. import cluster
    cluster.add_arguments(p)
    return p


def run(args):
    from .. import bake
    from ..world import World
    from ..light import daytime
    from ..storage import check_path
    check_path(args.world)
    hours = daytime.parse_time(args.time)
    if (args.region is None) == (args.lod is None):
        raise VoxelError("give --region X0 Y0 X1 Y1 or --lod X Y NEAR FAR (one of them)")
    if args.out.suffix.lower() != ".glb":
        if args.lod:
            raise VoxelError("--lod writes one .glb: --out must end in .glb")
        if args.per != "tile":
            raise VoxelError(f"--out must end in .glb (got {args.out.name}); a folder "
                             "takes --per tile")
        return _tiles(args, hours)
    if getattr(args, "workers", None) is not None or getattr(args, "scheduler", None):
        raise VoxelError("--workers/--scheduler bake tiles: use --per tile --out DIR")
    out_file(args.out, make_folder=True, world=args.world)  # fail before the long work, not after it
    if args.lod:
        from ..bake import lod
        lx, ly, near, far = args.lod
        if not 0 <= near < far:
            raise VoxelError(f"--lod needs 0 <= NEAR < FAR, got {near} and {far}")
        x0, y0, x1, y1 = lod.near_box(lx, ly, near)
    else:
        x0, y0, x1, y1 = bake.check_region(*args.region)
    big = (x1 - x0) * (y1 - y0) >= 64 * 64
    t0 = time.perf_counter()

    def progress(stage, frac):
        if big:
            note(f"bake: {stage} {100 * frac:3.0f}%  ({time.perf_counter() - t0:.1f} s)")

    far_parts = []
    with World.open(args.world, readonly=True, loader=False) as world:
        kw = dict(per=args.per, method=args.method, instances=args.instances, light=args.light,
                  progress=progress)
        if args.lod:
            bk, far_parts = lod.bake_lod(world, lx, ly, near, far, **kw)
        else:
            bk = bake.bake_world(world, x0, y0, x1, y1, **kw)
    if bk.note:
        note(f"bake: {bk.note}")
    try:
        import bpy
    except ImportError as e:
        raise VoxelError(f"bake needs the bpy module (pip install bpy): {e}") from None
    from ..blender import bake as BB
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="gltf", hours=hours, progress=progress)
    objs += BB.far_objects(far_parts, style="gltf", hours=hours)
    progress("export", 0.0)
    # The exporter logs INFO lines to stdout; keep stdout for our own result. It
    # writes a scratch file, copied whole to --out: a full disk there is one line and
    # leaves no half .glb (the exporter's own failure is a traceback inside Blender).
    with tempfile.TemporaryDirectory(prefix="voxel_glb_") as d:
        tmp = Path(d) / "bake.glb"
        with contextlib.redirect_stdout(io.StringIO()):
            BB.export_glb(tmp, objs, instances=args.instances)
        if not tmp.is_file():
            raise VoxelError(f"Blender's glTF exporter did not write {args.out}")
        write_out(args.out, tmp)
    if args.blend:
        bpy.ops.wm.save_as_mainfile(filepath=str(args.blend.resolve()))
    note(f"bake: {len(objs)} objects, {bk.triangles + sum(p.triangles for p in far_parts)} triangles, "
         f"{len(bk.materials)} materials in {time.perf_counter() - t0:.1f} s")
    print(args.out)


def _tiles(args, hours):
    """--per tile --out DIR: every tile on its own (bake.tiles), one .glb each. This
    process reads the tiles' blocks and writes the files (temp name, then rename, so
    a file there is complete and a re-run skips it); the tiles are baked here or on
    the cluster by the same function, so the files are the same."""
    from .. import cluster
    from ..bake import check_region, tiles
    from ..world import World
    if args.blend:
        raise VoxelError("--blend needs --out F.glb (a folder gets one .glb per tile)")
    out = args.out
    region = check_region(*args.region)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VoxelError(f"cannot create folder {out}: {e.strerror}") from None
    plan = tiles.plan(*region)
    todo = [t for t in plan if not (out / f"{t[0]}.glb").is_file()]
    shared = {"method": args.method, "instances": args.instances, "light": args.light,
              "hours": hours}
    t0 = time.perf_counter()
    written = empty = 0
    with cluster.session(args) as pool:  # the cluster is checked before the slow reads
        pool = pool or cluster.Serial()
        with World.open(args.world, readonly=True, loader=False) as world:
            # read as the tasks go out: the client never holds every tile's blocks
            cuts = _Sized((tiles.cut(world, region, t) for t in todo), len(todo))
            for c, glb in pool.map(tile_glb, cuts, shared=shared,
                                   progress=Progress("bake", "tiles")):
                if glb is None:
                    empty += 1
                else:
                    write_out(out / f"{c['name']}.glb", glb)
                    written += 1
    note(f"bake: {written} tiles written, {len(plan) - len(todo)} already there, {empty} empty "
         f"in {time.perf_counter() - t0:.1f} s")
    print(out)


class _Sized:
    """A lazy iterable that knows its length (Pool.map's progress)."""

    def __init__(self, it, n):
        self.it, self.n = it, n

    def __iter__(self):
        return iter(self.it)

    def __len__(self):
        return self.n


def tile_glb(cut, shared):
    """One tile (bake.tiles.cut) -> its .glb bytes, or None when it has no faces. The
    task of --per tile --out DIR, here and on cluster workers. bpy works only on a
    process's main thread (elsewhere it crashes), and a Dask worker runs tasks on other
    threads: there the tile goes to a helper process (cli.helper)."""
    if cut["empty"]:  # air only: nothing to bake, no bpy needed
        return None
    if threading.current_thread() is threading.main_thread():
        return _tile_glb(cut, shared)
    from . import helper
    return helper.call(_tile_glb, cut, shared)


def _tile_glb(cut, shared):
    import socket
    from ..bake import tiles
    try:
        from ..blender import bake as BB
    except ImportError as e:
        raise VoxelError(f"bake needs the bpy module (pip install bpy) on {socket.gethostname()}: "
                         f"{e}") from None
    bk = tiles.bake(cut, method=shared["method"], instances=shared["instances"],
                    light=shared["light"])
    return BB.glb_bytes(bk, hours=shared["hours"], instances=shared["instances"])
