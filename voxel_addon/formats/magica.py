"""A .vox model into a world, a box of a world out to a .vox (issue 21).

Import: every voxel of the scene (vox.voxels: placed by its scene graph, the
bounding box corner at `at`) becomes a `color` block whose data is the voxel's
colour in the world's palette (core.colors), exact, so an export gives the same
colours back. The voxels are kept like edits (they survive a regeneration) and
written in one transaction. Export: the box's non-air voxels, coloured by their
own colour (`color` blocks) or their block's texture average, quantised to 255
colours.
"""
from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np

from ..core import chunk as C
from ..core import colors
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError
from ..core.files import write_whole
from . import vox

COLOR = REGISTRY.id("color")
MAX_FILE = 256 << 20


def read_file(path) -> vox.Scene:
    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_FILE:
            raise VoxelError(f"{path} is larger than {MAX_FILE >> 20} MiB")
        return vox.read(path.read_bytes())
    except OSError as e:
        raise VoxelError(f"cannot read {path} ({e.strerror})") from None
    except vox.VoxError as e:
        raise VoxelError(f"{path.name} is not a readable .vox file ({e})") from None


def stamp(scene: vox.Scene, at, palette: np.ndarray):
    """(positions (n, 3) in the world, data values (n,), new world palette) of a
    scene placed with its bounding box corner at `at`."""
    xyz, col, size = vox.voxels(scene)
    xyz = xyz + np.asarray(at, np.int64)
    if len(xyz) and (xyz[:, 2].min() < 0 or xyz[:, 2].max() >= C.HEIGHT):
        raise VoxelError(f"the model spans z {int(xyz[:, 2].min())}..{int(xyz[:, 2].max())}, "
                         f"outside the world (0..{C.HEIGHT - 1}); choose another --at Z")
    used = np.unique(col)
    palette, idx = colors.add(palette, scene.palette[used, :3])
    lut = np.zeros(256, np.int64)
    lut[used] = idx
    return xyz, lut[col].astype(np.uint16), palette


def import_vox(world, path, at=(0, 0, 0)) -> dict:
    """Place a .vox into `world` (one transaction); returns a small report."""
    return place(world, read_file(path), at)


def place(world, scene: vox.Scene, at=(0, 0, 0)) -> dict:
    """Place a read scene into `world`, its bounding box corner at `at`, kept like
    edits and written in one transaction; returns a small report."""
    from ..storage.meta import while_moved

    def attempt():
        base = world.file.meta.get(colors.KEY)
        xyz, data, pal = stamp(scene, at, colors.parse(world.file.meta))
        world.set_blocks(xyz, np.full(len(xyz), COLOR, np.uint16), data)
        # written with the voxels, unless another writer added colours meanwhile:
        # then the indices again, from the palette the file holds now
        world.file.stage_meta(colors.KEY, colors.dump(pal), base=base)
        world.flush()
        return xyz
    xyz = while_moved(attempt, "colours")
    lo = xyz.min(0).tolist() if len(xyz) else list(at)
    hi = (xyz.max(0) + 1).tolist() if len(xyz) else list(at)
    return {"voxels": int(len(xyz)), "models": len(scene.models),
            "instances": len(scene.instances), "box": lo + hi}


@lru_cache(maxsize=None)
def block_colors() -> np.ndarray:
    """(n blocks, 3) uint8: each block's side texture averaged (alpha-weighted)."""
    from .. import textures
    out = np.zeros((len(REGISTRY), 3), np.uint8)
    for i, b in enumerate(REGISTRY.blocks):
        if b.shape == "none":
            continue
        img = textures.image(b.texture("-x"))[0].astype(np.float64)
        a = img[..., 3:4] / 255
        out[i] = np.rint((img[..., :3] * a).sum((0, 1)) / max(a.sum(), 1e-9))
    return out


def _pieces(world, box):
    """(destination slices in the box, blocks, data or None) of each chunk the half-open
    box [x0, x1) x [y0, y1) x [z0, z1) touches, cut to the box; the box checked."""
    x0, y0, z0, x1, y1, z1 = box
    if not (x0 < x1 and y0 < y1 and z0 < z1):
        raise VoxelError(f"--box {' '.join(map(str, box))} is empty (X0 < X1, Y0 < Y1, Z0 < Z1)")
    if z0 < 0 or z1 > C.HEIGHT:
        raise VoxelError(f"--box z {z0}..{z1} outside the world (0..{C.HEIGHT})")
    if (x1 - x0) * (y1 - y0) * (z1 - z0) > 1 << 28:
        raise VoxelError("--box holds more than 2^28 voxels")
    cx0, cy0, cx1, cy1 = x0 >> 4, y0 >> 4, ((x1 - 1) >> 4) + 1, ((y1 - 1) >> 4) + 1
    for cx in range(cx0, cx1):
        for cy in range(cy0, cy1):
            c = world.chunk_at(cx, cy)
            ax0, ay0 = max(x0, 16 * cx), max(y0, 16 * cy)
            ax1, ay1 = min(x1, 16 * cx + 16), min(y1, 16 * cy + 16)
            src = (slice(ax0 - 16 * cx, ax1 - 16 * cx), slice(ay0 - 16 * cy, ay1 - 16 * cy),
                   slice(z0, z1))
            yield ((slice(ax0 - x0, ax1 - x0), slice(ay0 - y0, ay1 - y0)), c.blocks[src],
                   None if c.data is None else c.data[src])


def _keys(blocks, data) -> np.ndarray:
    """block << 16 | data of non-air voxels (data only where it picks a colour)."""
    solid = blocks != 0
    k = blocks[solid].astype(np.uint32) << 16
    if data is not None:
        own = blocks[solid] == COLOR
        k[own] |= data[solid][own]
    return k


def export_vox(world, box, out) -> dict:
    """The non-air voxels of the box as a .vox at OUT. Chunk by chunk, twice (each
    (block, data) pair counted, then the grid of palette indices): the whole box's
    arrays at once took ~26 bytes per voxel (7 GB at the 2^28 limit), now ~1."""
    x0, y0, z0, x1, y1, z1 = box
    tally: dict = {}
    for _, b, d in _pieces(world, box):
        k, n = np.unique(_keys(b, d), return_counts=True)
        for key, cnt in zip(k.tolist(), n.tolist()):
            tally[key] = tally.get(key, 0) + cnt
    keys = np.array(sorted(tally), np.uint32)
    counts = np.array([tally[k] for k in keys.tolist()], np.int64)
    pal = colors.parse(world.file.meta)
    rgb = block_colors()[keys >> 16]
    own = (keys >> 16) == COLOR
    rgb[own] = pal[np.minimum(keys[own] & 0xFFFF, len(pal) - 1)]
    code = (rgb[:, 0].astype(np.int64) << 16) | (rgb[:, 1].astype(np.int64) << 8) | rgb[:, 2]
    uniq, inv = np.unique(code, return_inverse=True)
    ucount = np.bincount(inv, weights=counts, minlength=len(uniq)).astype(np.int64)
    ucol = np.stack([(uniq >> 16) & 255, (uniq >> 8) & 255, uniq & 255], 1)
    qpal, lab = vox.quantise(ucol, ucount)
    index = (lab[inv] + 1).astype(np.uint8)   # per key, in keys' order
    grid = np.zeros((x1 - x0, y1 - y0, z1 - z0), np.uint8)
    for dst, b, d in _pieces(world, box):
        cut = grid[dst]
        cut[b != 0] = index[np.searchsorted(keys, _keys(b, d))]
    full = np.zeros((256, 3), np.uint8)
    full[1:len(qpal) + 1] = qpal
    data = vox.write(grid, full)
    write_whole(out, data)
    return {"voxels": int(counts.sum()), "colors": int(len(qpal)), "exact": len(ucol) <= 255,
            "models": -(-grid.shape[0] // 256) * -(-grid.shape[1] // 256) * -(-grid.shape[2] // 256)}
