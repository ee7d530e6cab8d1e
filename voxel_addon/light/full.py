"""Full light solves: a block array, a 3x3 chunk window, a wide region (issue 4 §1).

`solve` lights a whole (W, H, 256) block array (outside = dark air, see model.py);
`chunk_light` returns the exact light of the centre chunk of a (48, 48, 256) window;
`region_light` solves a wide array once and returns its interior (the 1-chunk ring is
context), tiling very wide arrays so memory stays bounded.
Backends: "opencl", "numpy" (the reference), None = OpenCL when available.
"""
from __future__ import annotations

from functools import lru_cache

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
        if pick(backend) == "opencl":
            from . import cl
            out[:, :, z0:z1] = cl.solve_slab(blocks[:, :, z0:z1])[m:w, m:h]
        else:
            out[:, :, z0:z1] = solve_slab(blocks[:, :, z0:z1])[m:w, m:h]


def pick(backend: str | None = None) -> str:
    """The light's backend: BACKEND if named, else OpenCL on a GPU, NumPy where the
    OpenCL device is the CPU (pocl): the NumPy flood (brightest first, each voxel
    written once) takes ~4.5x less CPU there than the kernel's sweeps (bench README)."""
    if backend is None and opencl.on_cpu():
        return "numpy"
    return opencl.pick(backend, "light")


def solve_slab(blocks: np.ndarray) -> np.ndarray:
    """Light of a (W, H, Z) slab with open sky right above it and dark air around:
    start values, then flood.levels from every voxel that can raise a neighbour.

    Works on a padded grid (flood.grid) of value + cost per component (flood.levels
    says why): `cost` is shared, the daylight's `fc` is dense (the column pass fills
    it), the colours flood one `fc` in turn, sparse (only emitters start above 0)."""
    w, h, zs = blocks.shape
    shape, (sy, sz) = flood.grid((zs, h, w))
    code_t, cost_c, packed = _codes()
    bt = blocks.T  # [z, y, x]
    code = _lookup(code_t, bt)  # every voxel's cost, emitters marked (codes 128-254)
    em = np.flatnonzero((code ^ 128) < 127)  # flat [z, y, x] indices of the inside
    eid = bt.reshape(-1)[em]
    pem = _padded(em, h, w, sy, sz)
    cost = np.full(shape, model.OPAQUE_COST, np.uint8)
    cost[2:-2, 1:-1, 1:-1] = code
    cost.reshape(-1)[pem] = cost_c[eid]
    # Daylight column pass, layer by layer from the top (carry 15 above the slab);
    # fc = D + cost (opaque: 0 + 255). Below the layer where every column is dark,
    # fc = cost already.
    fc = cost.copy()
    carry = np.full((h, w), model.MAX, np.uint8)
    att = np.empty((h, w), np.uint8)
    dlo, dhi = zs, 0  # D seeds lie in [dlo, dhi): below, D <= 1; above, all 15 and clear
    for z in range(zs - 1, -1, -1):
        c = cost[z + 2, 1:-1, 1:-1]
        np.subtract(c, 1, out=att)  # opaque: 254, takes any carry to 0
        np.maximum(carry, att, out=carry)
        carry -= att
        np.add(carry, c, out=fc[z + 2, 1:-1, 1:-1])
        top = carry.max()
        if top == 0:
            break
        if top > 1:  # a 1 raises nothing
            dlo = z
        if not dhi and carry.min() < model.MAX:
            dhi = z + 1
    fc = fc.reshape(-1)
    cost = cost.reshape(-1)
    if dhi > dlo:  # daylight only moves sideways from its column pass
        s, v = flood.edge(fc, cost, (1, sy), (dlo + 2) * sz, (dhi + 2) * sz)
        flood.levels(fc, cost, s, v, sy, sz)
    f = np.subtract(fc, cost).astype(np.uint16)  # D (opaque: 255 - 255)
    f <<= 12
    if pem.size:
        ep = packed[eid]
        # Most emitters are weak ores walled in by stone: an emitter with no
        # non-opaque face neighbour raises nothing (values only rise, so it never
        # will), and dropping them saves the floods a round over all of them.
        offs = np.array([-1, 1, -sy, sy, -sz, sz], np.int64)
        lit = (cost[pem[:, None] + offs] != model.OPAQUE_COST).any(axis=1)
        clear = cost[pem] != model.OPAQUE_COST  # these start at e + cost in fc
        fcl = fc  # the daylight is in f now: reuse its grid
        for shift in flood.SHIFTS[:3]:
            e = ((ep >> shift) & 15).astype(np.uint8)
            if not (e[lit] > 1).any():
                continue
            fcl[...] = cost
            fcl[pem[clear]] = e[clear] + cost[pem[clear]]
            out = flood.levels(fcl, cost, pem[lit], e[lit], sy, sz)
            if out:  # nibbles still 0 here: emitters come after
                n = np.concatenate([n for n, _ in out])
                v = np.concatenate([np.full(n.size, v << shift, np.uint16) for n, v in out])
                f[n] |= v
        # An emitter holds the larger of its emission and what reached it.
        cur = f[pem]
        for shift in flood.SHIFTS[:3]:
            m = np.uint16(15 << shift)
            cur = (cur & ~m) | np.maximum(cur & m, ep & m)
        f[pem] = cur
    return f.reshape(shape)[2:-2, 1:-1, 1:-1].T


def _lookup(code_t: np.ndarray, bt: np.ndarray) -> np.ndarray:
    """code_t[bt], C order: np.take without bounds checks (after one max) is ~2x
    cheaper than indexing. (bytes.translate would be cheaper still, but its fresh
    bytes objects page-fault on every solve.)"""
    top = int(bt.max()) if bt.size else 0
    if top >= code_t.size:
        raise VoxelError(f"block id {top} is unknown to the light tables "
                         f"(ids 0-{code_t.size - 1})")
    return np.take(code_t, bt, mode="clip")


@lru_cache(maxsize=1)
def _codes():
    """Per block id a uint8 code: its cost (>= 16 blocks like opaque: 255) or, for an
    emitter, 128 + its rank; the cost per id; packed emission per id."""
    cost, _, _, _, packed, _ = model.tables()
    c = np.where(cost > model.MAX, model.OPAQUE_COST, cost).astype(np.uint8)
    ids = np.flatnonzero(packed)
    code = c.copy()
    if ids.size < 127:
        code[ids] = 128 + np.arange(ids.size)
    else:  # too many emitters to mark: take every voxel as one (exact, slower)
        code[:] = 128
    return code, c, packed


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
