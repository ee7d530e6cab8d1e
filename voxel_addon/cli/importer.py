"""import: a Minecraft Java world, region files or a MagicaVoxel .vox into a world
(SPEC §5, issue 21). A world it creates uses the empty generator (air) unless
--generator names another, so its file holds exactly what was imported."""
from __future__ import annotations

import time
from pathlib import Path

from .. import cluster
from ..core.errors import VoxelError
from .common import Progress, Writing, add_world, coord, note


def add_parser(sub):
    p = sub.add_parser("import", help="import a Minecraft Java world or a .vox model")
    add_world(p, help="world file (.sqlite), created if missing")
    p.add_argument("--from", dest="source", required=True, type=Path, metavar="PATH",
                   help="Minecraft save folder, folder of .mca files, one .mca, or a .vox")
    p.add_argument("--y-min", type=int, metavar="N",
                   help="Minecraft y that becomes z 0 (default -64 for 1.18+, else 0)")
    p.add_argument("--at", type=coord, nargs=3, metavar=("X", "Y", "Z"), default=(0, 0, 0),
                   help=".vox: where the model's bounding box corner goes (default 0 0 0)")
    p.add_argument("--area", type=coord, nargs=4, metavar=("X0", "Z0", "X1", "Z1"),
                   help="Minecraft: only chunks touching blocks [X0, X1) x [Z0, Z1)")
    p.add_argument("--replace", action="store_true",
                   help="Minecraft: overwrite chunks the world already has (an interrupted "
                        "import needs none: the same command again resumes it)")
    p.add_argument("--resources", action="append", metavar="JAR_OR_PACK",
                   help="Minecraft: the game's client .jar (or 'minecraft': the newest in "
                        "the launcher folders) and resource packs (.zip or folders) laid "
                        "over it in the order given; kept in the world for renders, bakes "
                        "and the live view (repeatable)")
    p.add_argument("--generator", help="generator of a new world (default: empty)")
    p.add_argument("--seed", type=int, default=0, help="seed of a new world (default 0)")
    cluster.add_arguments(p)
    return p


def _open(args):
    from ..storage import Exists
    from ..world import World
    if not args.world.exists():
        if not args.world.parent.is_dir():
            raise VoxelError(f"folder {args.world.parent} does not exist")
        try:
            return World.create(args.world, seed=args.seed,
                                generator=args.generator or "empty", loader=False)
        except Exists:  # another process made it just now: import into theirs
            pass
    if args.generator:
        raise VoxelError("--generator is for a new world; this one exists")
    return World.open(args.world, loader=False)


def run(args):
    src = args.source
    if not src.exists():
        raise VoxelError(f"{src} does not exist")
    is_vox = src.is_file() and src.suffix.lower() == ".vox"
    resources = None
    if is_vox and (args.area or args.replace or args.y_min is not None or args.resources):
        raise VoxelError("--area, --replace, --y-min and --resources are for Minecraft worlds")
    if not is_vox and tuple(args.at) != (0, 0, 0):
        raise VoxelError("--at is for .vox files (Minecraft chunks keep their place)")
    if args.area and not (args.area[0] < args.area[2] and args.area[1] < args.area[3]):
        raise VoxelError("--area X0 Z0 X1 Z1 needs X0 < X1 and Z0 < Z1")
    if is_vox:
        from ..formats import magica
        scene = magica.read_file(src)  # a bad file is refused before the world opens
        del scene
    else:
        cluster.warm(args)   # before the imports below
        from ..formats import minecraft
        minecraft.regions_of(src)
        if args.resources:
            from ..mcres.stack import resolve
            resources = resolve(args.resources)
    if is_vox and (args.workers is not None or args.scheduler):
        raise VoxelError("--workers and --scheduler are for Minecraft worlds")
    cluster.check_writable(args)
    t0 = time.perf_counter()
    computed = None
    # the cluster first: an unreachable one leaves no file created or changed
    with cluster.session(args) as pool, Writing(args.world, "import", "importing into") as w:
        world = w.own(_open(args))
        if is_vox:
            r = magica.import_vox(world, src, args.at)
        else:
            rep = minecraft.Report()
            w.kept = lambda: f"{rep.chunks} chunks were written and kept" if rep.chunks else None
            w.rest = "; the same command again imports it"   # resumes (formats/job.py)
            kw = dict(y_min=args.y_min, area=args.area, replace=args.replace,
                      progress=Progress("importing"), report=rep, resources=resources, say=note)
            try:
                if pool is None:
                    minecraft.import_world(world, src, **kw)
                else:
                    from ..cluster import imports
                    computed = imports.run(world, pool, src, **kw)
            except KeyboardInterrupt:   # the batches written stay (Writing), and a note
                note(f"{rep.chunks} chunks were written and kept; the same command again "
                     "imports the rest")
                raise
    if is_vox:
        note(f"{r['voxels']} voxels from {r['models']} models ({r['instances']} placed) "
             f"into box {' '.join(map(str, r['box']))} in {time.perf_counter() - t0:.2f} s")
        return 0
    if computed is not None:
        note(f"workers read {computed} chunks")
    dt = time.perf_counter() - t0
    lines = rep.lines()
    lines[0] += f" in {dt:.2f} s ({rep.chunks / max(dt, 1e-9):.0f} chunks/s)"
    print("\n".join(lines))
    return 0
