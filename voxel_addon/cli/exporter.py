"""export: a box of a world as a MagicaVoxel .vox (SPEC §5, issue 21)."""
from __future__ import annotations

from pathlib import Path

from .common import add_world, coord, note, out_file


def add_parser(sub):
    p = sub.add_parser("export", help="write a box of a world as a MagicaVoxel .vox")
    add_world(p)
    p.add_argument("--box", type=coord, nargs=6, required=True,
                   metavar=("X0", "Y0", "Z0", "X1", "Y1", "Z1"),
                   help="half-open block box; its (X0, Y0, Z0) is the model's origin")
    p.add_argument("--out", type=Path, required=True, metavar="F.vox")
    return p


def run(args):
    from ..core.errors import VoxelError
    from ..formats import magica
    from ..world import World
    if args.out.suffix.lower() != ".vox":
        raise VoxelError(f"--out {args.out}: the file name must end in .vox")
    out_file(args.out, world=args.world)
    with World.open(args.world, readonly=True, loader=False) as world:
        r = magica.export_vox(world, args.box, args.out)
    note(f"{r['voxels']} voxels, {r['colors']} colours"
         f"{'' if r['exact'] else ' (quantised)'}, {r['models']} models -> {args.out}")
    return 0
