"""map: a top-down picture of a world's generated area: terrain (top blocks,
hill-shaded) beside the generator's biome factors, so artists see where to fly."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..core.errors import VoxelError
from .common import add_world, note, out_file, write_out

MAX_CHUNKS = 40000


def add_parser(sub):
    from ..opencl import BACKENDS
    p = sub.add_parser("map", help="top-down image of heights and biomes of the generated area")
    add_world(p)
    p.add_argument("--out", required=True, type=Path, metavar="map.png", help="PNG to write")
    p.add_argument("--backend", choices=BACKENDS, help="for the biome panel")
    return p


def run(args):
    from ..generation import for_file, topview
    from ..storage import WorldFile, check_path
    check_path(args.world)
    if args.out.suffix.lower() != ".png":
        raise VoxelError("--out must name a .png file")
    out_file(args.out, world=args.world)
    wf = WorldFile(args.world, readonly=True)
    try:
        keys = sorted(wf.chunk_keys())
        if not keys:
            raise VoxelError(f"{args.world} has no chunks yet (run generate first)")
        if len(keys) > MAX_CHUNKS:
            raise VoxelError(f"{len(keys)} chunks is more than map draws ({MAX_CHUNKS})")
        xs, ys = [k[0] for k in keys], [k[1] for k in keys]
        cx0, cy0 = min(xs), min(ys)
        span = (max(xs) - cx0 + 1, max(ys) - cy0 + 1)
        if span[0] * span[1] > MAX_CHUNKS:  # the picture covers the box, gaps and all
            raise VoxelError(f"the chunks span {span[0]} x {span[1]} chunks (x {16 * cx0}.."
                             f"{16 * max(xs) + 15}, y {16 * cy0}..{16 * max(ys) + 15}); map "
                             f"draws at most {MAX_CHUNKS} chunks")
        w, h = 16 * span[0], 16 * span[1]
        top = np.zeros((w, h), np.int64)
        z = np.zeros((w, h), np.int32)
        gz = np.zeros((w, h), np.int32)
        known = np.zeros((w, h), np.float32)
        for k in keys:
            blocks, _ = wf.read_chunk(k)
            sx, sy = 16 * (k[0] - cx0), 16 * (k[1] - cy0)
            sl = np.s_[sx:sx + 16, sy:sy + 16]
            top[sl], z[sl], gz[sl] = topview.summary(blocks)
            known[sl] = 1
        gen = for_file(wf, args.backend)
        sea = int(gen.params.get("sea_level", 62))
        panels = [topview.shade(top, z, gz, sea, known)]
        if hasattr(gen, "columns"):
            names = ["ocean", "mountain", "desert", "hills", "treeRate", "river"]
            cols = gen.columns(keys, names)
            f = {n: np.zeros((w, h), np.float32) for n in names}
            for i, k in enumerate(keys):
                sx, sy = 16 * (k[0] - cx0), 16 * (k[1] - cy0)
                for n in names:
                    f[n][sx:sx + 16, sy:sy + 16] = cols[n][i]
            b = topview.biome_rgb(f).astype(np.float32) * known.T[::-1][:, :, None]
            panels.append(b.astype(np.uint8))
    finally:
        wf.close()
    gap = np.full((panels[0].shape[0], 8, 3), 255, np.uint8)
    img = np.concatenate(sum([[p, gap] for p in panels], [])[:-1], axis=1)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    plt.imsave(buf, img, format="png")
    write_out(args.out, buf.getvalue())
    note(f"{len(keys)} chunks, blocks x {16 * cx0}..{16 * cx0 + w - 1}, "
         f"y {16 * cy0}..{16 * cy0 + h - 1}; left: terrain, right: biomes "
         "(ocean blue, desert tan, mountains brown, hills olive, forest green, rivers light blue)")
    print(args.out)
