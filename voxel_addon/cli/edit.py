"""edit: set or clear one block and save it (SPEC §5), relit and remeshed through
world.edit like any other edit (one transaction)."""
from __future__ import annotations

import os

from .common import Writing, add_world, coord


def add_parser(sub):
    p = sub.add_parser("edit", help="set or clear one block")
    add_world(p)
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--set", nargs=4, metavar=("X", "Y", "Z", "NAME"), help="place block NAME")
    g.add_argument("--clear", nargs=3, type=coord, metavar=("X", "Y", "Z"), help="make it air")
    return p


def run(args):
    from ..core import chunk
    from ..core.blocks import REGISTRY
    from ..core.errors import VoxelError
    from ..world import World
    from ..opencl import SWITCH
    from ..world.edit import edit
    if args.set:
        try:
            x, y, z = (int(v) for v in args.set[:3])
        except ValueError:
            raise VoxelError(f"--set X Y Z NAME: X Y Z must be whole numbers (got {' '.join(args.set[:3])})") from None
        name = args.set[3]
    else:
        (x, y, z), name = args.clear, "air"
    bid = REGISTRY.id(name)        # check everything before the file is opened for writing
    chunk.check_z(z)
    # One voxel on NumPy (generation, light and meshing agree with OpenCL exactly):
    # as fast as OpenCL with its kernels cached, and no kernel build, which would
    # write a cache and abort inside the compiler on a full disk or a size limit.
    was = os.environ.get(SWITCH)
    os.environ[SWITCH] = "0"
    try:
        with Writing(args.world, "edit") as w:
            world = w.own(World.open(args.world, loader=False))
            payloads, rec = edit(world, (x, y, z, bid))
    finally:  # (main() may run in a longer process: tests)
        if was is None:
            del os.environ[SWITCH]
        else:
            os.environ[SWITCH] = was
    old = rec.before[0][0] if rec.voxels else bid
    note = f"{len(payloads)} chunks relit/remeshed" if rec.voxels else "unchanged"
    print(f"({x}, {y}, {z}): {REGISTRY[old].name} -> {name} (saved; {note})")
