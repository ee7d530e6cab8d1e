"""Full light solves: a block array, a 3x3 chunk window, a wide region (issue 4 §1).

`solve` lights a whole (W, H, 256) block array (outside = dark air, see model.py);
`chunk_light` returns the exact light of the centre chunk of a (48, 48, 256) window;
`region_light` solves a wide array once and returns its interior (the 1-chunk ring is
context), tiling very wide arrays so memory stays bounded.
Backends: "opencl", "numpy" (the reference), None = OpenCL when available.
"""
from __future__ import annotations

import numpy as np

from .. import opencl
from ..core import chunk
from ..core.errors import VoxelError
from . import flood, model

TILE = 8  # interior chunks per tile side in region_light (10x10 solved per 8x8 kept)


def _check(blocks: np.ndarray) -> np.ndarray:
    blocks = np.asarray(blocks)
    if blocks.ndim != 3 or blocks.shape[2] != chunk.HEIGHT:
        raise VoxelError(f"block array must be (W, H, {chunk.HEIGHT}), got {blocks.shape}")
    return np.asfortranarray(blocks, dtype=np.uint16)


def solve(blocks: np.ndarray, backend: str | None = None) -> np.ndarray:
    """Light of every voxel of `blocks` ((W, H, 256) uint16) -> same-shape uint16
    packed per SPEC §3, Fortran order. Exact >= 15 columns inside the side edges."""
    blocks = _check(blocks)
    out = np.empty(blocks.shape, np.uint16, order="F")
    _solve_into(blocks, out, 0, backend)
    return out


def _solve_into(blocks: np.ndarray, out: np.ndarray, m: int, backend) -> None:
    """solve(blocks) without its `m`-voxel side margin, written into `out`: a wide
    region's tiles go straight into the result (no full-size temporary and copy)."""
    w, h = blocks.shape[0] - m, blocks.shape[1] - m
    z0, z1 = model.slab(blocks)
    _, _, _, _, packed, _ = model.tables()
    out[:, :, z1:] = model.SKY
    out[:, :, :z0] = packed[blocks[m:w, m:h, :z0]]
    if z1 > z0:
        if opencl.pick(backend, "light") == "opencl":
            from . import cl
            out[:, :, z0:z1] = cl.solve_slab(blocks[:, :, z0:z1])[m:w, m:h]
        else:
            out[:, :, z0:z1] = solve_slab(blocks[:, :, z0:z1])[m:w, m:h]


def solve_slab(blocks: np.ndarray) -> np.ndarray:
    """Light of a (W, H, Z) slab with open sky right above it and dark air around:
    start values, then flood.py from every voxel that can raise a neighbour."""
    w, h, zs = blocks.shape
    shape, (sy, sz) = flood.grid((zs, h, w))
    cost_t, _, _, _, packed, _ = model.tables()
    bt = blocks.T  # [z, y, x]
    cost = np.full(shape, model.OPAQUE_COST, np.uint8)
    inner = (slice(2, -2), slice(1, -1), slice(1, -1))
    cost[inner] = cost_t[bt]
    f = np.zeros(shape, np.uint16)
    em = _emitters(bt, packed)  # flat [z, y, x] indices of the inside
    pem = _padded(em, h, w, sy, sz)
    f.reshape(-1)[pem] = packed[bt.reshape(-1)[em]]
    # Daylight column pass, layer by layer from the top (carry 15 above the slab).
    carry = np.full((h, w), model.MAX, np.int16)
    dlo, dhi = zs, 0  # layers with a non-opaque voxel below 15 and a voxel >= 2
    for z in range(zs - 1, -1, -1):
        c = cost[z + 2, 1:-1, 1:-1]
        op = c == model.OPAQUE_COST
        carry -= c
        carry += 1
        np.maximum(carry, 0, out=carry)
        carry[op] = 0
        f[z + 2, 1:-1, 1:-1] |= carry.astype(np.uint16) << 12
        top = carry.max()
        if top >= 2 and (carry[~op] < model.MAX).any():
            dlo, dhi = z, max(dhi, z + 1)
        if top == 0:
            break
    f = f.reshape(-1)
    cost = cost.reshape(-1)
    em = pem
    if em.size:
        # Most emitters are weak ores walled in by stone: an emitter with no
        # non-opaque face neighbour raises nothing (values only rise, so it never
        # will), and dropping them here saves the floods a round over all of them.
        offs = np.array([-1, 1, -sy, sy, -sz, sz], np.int64)
        em = em[(cost[em[:, None] + offs] != model.OPAQUE_COST).any(axis=1)]
    for k, shift in enumerate(flood.SHIFTS[:3]):
        s = em[((f[em] >> shift) & 15) > 1]
        if s.size:
            flood.flood(f, cost, s, shift, sy, sz)
    if dhi > dlo:  # daylight only moves sideways from its column pass
        s = flood.seeds(f, cost, 12, (1, sy), (dlo + 2) * sz, (dhi + 2) * sz)
        flood.flood(f, cost, s, 12, sy, sz)
    return f.reshape(shape)[inner].T


def _emitters(bt: np.ndarray, packed: np.ndarray) -> np.ndarray:
    """Flat indices of the emitting voxels of C-order `bt`: a compare per emitting
    block id is ~10x cheaper than a table lookup over the whole slab."""
    ids = np.flatnonzero(packed)
    flat = bt.reshape(-1)
    if ids.size > 8:
        return np.flatnonzero(packed[flat])
    m = np.zeros(flat.shape, bool)
    for i in ids.tolist():
        m |= flat == i
    return np.flatnonzero(m)


def _padded(i: np.ndarray, h: int, w: int, sy: int, sz: int) -> np.ndarray:
    """Flat [z, y, x] indices of the inside -> flat indices of the padded grid."""
    z, r = np.divmod(i, h * w)
    y, x = np.divmod(r, w)
    return (z + 2) * sz + (y + 1) * sy + (x + 1)


def chunk_light(blocks3x3: np.ndarray, backend: str | None = None) -> np.ndarray:
    """Exact (16, 16, 256) light of the centre chunk of a (48, 48, 256) window."""
    b = _check(blocks3x3)
    if b.shape[:2] != (3 * chunk.SIZE, 3 * chunk.SIZE):
        raise VoxelError(f"blocks3x3 must be (48, 48, 256), got {b.shape}")
    s = chunk.SIZE
    return np.asfortranarray(solve(b, backend)[s:2 * s, s:2 * s])


def region_light(blocks: np.ndarray, backend: str | None = None, tile: int = TILE) -> np.ndarray:
    """Exact light of the interior of a chunk-aligned (16*(n+2), 16*(m+2), 256) array:
    returns (16*n, 16*m, 256). Solves overlapping tiles of (tile+2)^2 chunks."""
    b = _check(blocks)
    s = chunk.SIZE
    if b.shape[0] % s or b.shape[1] % s or b.shape[0] < 3 * s or b.shape[1] < 3 * s:
        raise VoxelError(f"region must be whole chunks, at least 3x3, got {b.shape}")
    n, m = b.shape[0] // s - 2, b.shape[1] // s - 2
    out = np.empty((n * s, m * s, chunk.HEIGHT), np.uint16, order="F")  # tiles cover it
    for i in range(0, n, tile):
        for j in range(0, m, tile):
            ti, tj = min(tile, n - i), min(tile, m - j)
            sub = _check(b[i * s:(i + ti + 2) * s, j * s:(j + tj + 2) * s])
            _solve_into(sub, out[i * s:(i + ti) * s, j * s:(j + tj) * s], s, backend)
    return out


def world_region(world, cx0: int, cy0: int, cx1: int, cy1: int,
                 backend: str | None = None) -> np.ndarray:
    """Light of chunks [cx0, cx1) x [cy0, cy1) of a world.World, solved at once
    (reads the 1-chunk ring around it through world.region_blocks)."""
    return region_light(world.region_blocks(cx0 - 1, cy0 - 1, cx1 + 1, cy1 + 1), backend)
