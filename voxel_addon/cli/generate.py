"""generate: create a world or extend it around a point (SPEC §5)."""
from __future__ import annotations

import time

from .. import cluster
from ..core.errors import VoxelError
from .common import Progress, Writing, add_world, coord, note


def add_parser(sub):
    from ..opencl import BACKENDS
    p = sub.add_parser("generate", help="create or extend a world")
    add_world(p)
    p.add_argument("--seed", type=int, help="world seed (required for a new world)")
    p.add_argument("--center", type=coord, nargs=2, metavar=("X", "Y"), default=(0, 0),
                   help="block column at the centre (default 0 0)")
    p.add_argument("--radius", type=int, default=4,
                   help="chunks around the centre chunk: (2R+1)^2 chunks (default 4)")
    p.add_argument("--generator", help="overworld (default) or flat; new worlds only")
    p.add_argument("--backend", choices=BACKENDS,
                   help="generation backend (default: OpenCL when a device is present)")
    cluster.add_arguments(p)
    return p


def run(args):
    if not 0 <= args.radius <= 256:
        raise VoxelError(f"--radius must be between 0 and 256 (got {args.radius})")
    if not args.world.exists():
        if args.seed is None:
            raise VoxelError("--seed is needed to create a new world")
        if not args.world.parent.is_dir():
            raise VoxelError(f"folder {args.world.parent} does not exist")
    cluster.check_writable(args)
    cluster.warm(args)   # before the imports below (~0.2 s)
    from ..world import World
    from ..generation import DEFAULT
    from ..storage import Exists
    # the cluster first: an unreachable one leaves no file created or changed
    with cluster.session(args) as pool, \
            Writing(args.world, "generation", "generating into") as w:
        world = None
        if not args.world.exists():
            try:
                world = w.own(World.create(args.world, seed=args.seed,
                                           generator=args.generator or DEFAULT,
                                           backend=args.backend, loader=False))
            except Exists:  # another process made it just now: extend theirs
                pass
        if world is None:
            world = w.own(World.open(args.world, backend=args.backend, loader=False))
            if args.seed is not None and args.seed != world.seed:
                raise VoxelError(f"{args.world} has seed {world.seed}; a world keeps its seed "
                                 "(use another file for another seed)")
            if args.generator and args.generator != world.file.generator:
                raise VoxelError(f"{args.world} uses generator {world.file.generator!r}, "
                                 f"not {args.generator!r}")
        gen = world.generator
        note(f"generator {gen.name}, backend {getattr(gen, 'backend_used', gen.backend)}")
        cx, cy = args.center[0] >> 4, args.center[1] >> 4
        r = args.radius
        # Nearest first, so an interrupted run leaves a usable area around the centre.
        keys = sorted(((x, y) for x in range(cx - r, cx + r + 1) for y in range(cy - r, cy + r + 1)),
                      key=lambda k: (max(abs(k[0] - cx), abs(k[1] - cy)), k))
        t0 = time.perf_counter()
        show, done = Progress("generating"), [0, 0]

        def progress(n, total):  # what is in the file, should the next batch fail
            done[:] = n, total
            show(n, total)
        w.kept = lambda: f"{done[0]} of {done[1]} new chunks were written and kept" \
            if done[0] else None
        try:
            if pool is None:
                made = world.generate_area(keys, progress)
            else:
                from ..cluster import generate
                made, computed = generate.run(world, pool, keys, args.backend, progress)
                note(f"workers computed {computed} chunks")
        except KeyboardInterrupt:  # the batches written stay (Writing): say so
            note(f"{w.kept() or 'no new chunks were written'}; the same command again "
                 "generates the rest")
            raise
        dt = time.perf_counter() - t0
        note(f"{made} new chunks in {dt:.2f} s, {len(keys) - made} already present; "
             f"{world.file.chunk_count()} chunks in {args.world}")

