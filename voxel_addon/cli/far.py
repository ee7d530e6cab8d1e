"""far: build the far-terrain tiles of a ring and keep them in the world file, so a
vista opens at once in Blender (far/README.md; issue 27)."""
from __future__ import annotations

import time

from .. import cluster
from ..core.errors import VoxelError
from .common import Progress, Writing, add_world, coord, note


def add_parser(sub):
    from ..opencl import BACKENDS
    p = sub.add_parser("far", help="build and keep the far terrain around a point")
    add_world(p)
    p.add_argument("--center", type=coord, nargs=2, metavar=("X", "Y"), required=True,
                   help="block column at the centre of the view")
    p.add_argument("--far", type=int, required=True, metavar="N",
                   help="chunks beyond the view chunk, like render --far (1..256)")
    p.add_argument("--near", type=int, default=0, metavar="N",
                   help="leave out tiles inside the N chunks a view draws as chunks "
                        "(default 0: every tile, good for any view distance)")
    p.add_argument("--backend", choices=BACKENDS,
                   help="generation backend (default: OpenCL when a device is present)")
    cluster.add_arguments(p)
    return p


def run(args):
    from ..far import grid
    from ..world import World
    if not 1 <= args.far <= grid.FAR_MAX:
        raise VoxelError(f"--far must be between 1 and {grid.FAR_MAX} chunks (got {args.far})")
    if not 0 <= args.near < args.far:
        raise VoxelError(f"--near must be between 0 and --far - 1 (got {args.near})")
    from ..storage import check_path
    check_path(args.world)
    cluster.check_writable(args)
    from ..cluster import far
    with cluster.session(args) as pool, \
            Writing(args.world, "far build", "building far tiles into") as w:
        world = w.own(World.open(args.world, backend=args.backend, loader=False))
        t0 = time.perf_counter()
        wanted, kept, built = far.run(world, pool or cluster.Serial(), *args.center, args.far,
                                      args.near, args.backend, Progress("far tiles", "tiles"))
        note(f"{built} tiles built in {time.perf_counter() - t0:.2f} s, {kept} already "
             f"in the file; {wanted} tiles to far {args.far} around "
             f"{args.center[0]} {args.center[1]}")
    return 0
