"""dump: one chunk's blocks, light and 3x3 neighbourhood as .npz (SPEC §5). Never writes the world."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from .common import add_world, chunk_coord, out_file, write_out


def add_parser(sub):
    p = sub.add_parser("dump", help="write a chunk's arrays to an .npz file")
    add_world(p)
    p.add_argument("--chunk", nargs=2, type=chunk_coord, required=True, metavar=("CX", "CY"))
    p.add_argument("--out", required=True, type=Path, metavar="F.npz")
    return p


def chunk_light(blocks3x3: np.ndarray) -> np.ndarray:
    from ..light import chunk_light as solve
    return solve(blocks3x3)


def run(args):
    from ..world import World
    cx, cy = args.chunk
    out_file(args.out, world=args.world)
    with World.open(args.world, readonly=True, loader=False) as world:
        world.chunk_at(cx, cy)  # a damaged chunk is an error here, not air (neighbours: air)
        b3 = world.region_blocks(cx - 1, cy - 1, cx + 2, cy + 2)
    blocks = np.asfortranarray(b3[16:32, 16:32])
    light = chunk_light(b3)
    f = io.BytesIO()  # np.savez would append .npz to other names
    np.savez_compressed(f, blocks=blocks, light=light, blocks3x3=b3)
    write_out(args.out, f.getvalue())
    print(args.out)
