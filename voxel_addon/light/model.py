"""The cellular light model (SPEC F6, thesis §4.3), pinned exactly as issue 4 states it.

Per voxel four 4-bit components R, G, B, D (daylight), packed as SPEC §3
(bits 0-3 R, 4-7 G, 8-11 B, 12-15 D).
1. Every voxel starts at 0; an emitting block starts at its emission (r, g, b).
2. Daylight column pass: above z=255 a column carries 15. Going down, a voxel that is
   not light_opaque gets carry - attenuation (floored at 0) and passes it down;
   a light_opaque voxel gets 0 and passes 0.
3. Relaxation to the fixpoint: every non-opaque voxel takes, per component,
   max(v, n - 1 - attenuation(self)) over its 6 face neighbours n. Opaque voxels keep
   their emission (a lamp shines into its neighbours but receives nothing).

The fixpoint is unique: a voxel's value is the max over sources of the source's start
value minus the cost of a 6-connected path through non-opaque voxels (each step costs
1 + attenuation of the voxel entered). Every step costs >= 1 and values are <= 15, so
only paths of <= 14 steps matter; any algorithm reaching the fixpoint gives identical
results: `relax` here (Jacobi, the brute-force reference the tests compare against),
flood.py (sparse NumPy, used by full.py and incremental.py) and the OpenCL line
sweeps (cl.py, gpu/light.cl).

Outside the solved array: dark air. Neighbours outside the array contribute 0 and no
daylight enters sideways from outside; columns are always complete (z 0..255), so the
column pass is exact. Hence a voxel >= 15 columns away from the array's side edges is
exact, i.e. the centre chunk of a 3x3 window (and every interior chunk of a wider
region, the 1-chunk ring being context) has the true world light.

Internal working form ("lanes"): uint8 per component, arrays indexed [z, y, x, c]
(the C-order transpose of the (W, H, 256) Fortran block arrays, so x stays fastest).
"""
from __future__ import annotations

from functools import lru_cache

import sys

import numpy as np

from ..core.blocks import REGISTRY

MAX = 15
STEPS = MAX - 1  # Jacobi iterations that reach the fixpoint for sure
OPAQUE_COST = 255  # cost of entering an opaque voxel: nothing gets through
SKY = MAX << 12  # packed value of open sky: D=15, RGB=0
assert sys.byteorder == "little"  # lanes are uint32 viewed as 4 bytes R, G, B, D


@lru_cache(maxsize=1)
def tables():
    """Per block id: cost (1+att, OPAQUE_COST if opaque), att, opaque, emission (n,3),
    packed emission (what an opaque voxel's light is)."""
    r = REGISTRY
    opaque = r.light_opaque.astype(np.uint8)
    att = r.attenuation.astype(np.uint8)
    cost = np.where(r.light_opaque, OPAQUE_COST, 1 + r.attenuation.astype(np.int32)).astype(np.uint8)
    emis = np.minimum(r.emission, MAX).astype(np.uint8)
    packed = (emis[:, 0].astype(np.uint16) | (emis[:, 1].astype(np.uint16) << 4)
              | (emis[:, 2].astype(np.uint16) << 8))
    air = ~r.light_opaque & (r.shape == 0) & (emis.max(axis=1) == 0) & (r.attenuation == 0)
    return cost, att, opaque, emis, packed, air


@lru_cache(maxsize=1)
def lists():
    """tables()' cost, attenuation, opacity and emission as Python lists: an edit reads
    them for a handful of voxels, where NumPy's scalar indexing costs more."""
    cost, att, opaque, emis, _, _ = tables()
    return cost.tolist(), att.tolist(), opaque.tolist(), emis.tolist()


def pack(lanes: np.ndarray) -> np.ndarray:
    """[..., 4] uint8 R,G,B,D -> packed uint16."""
    l16 = lanes.astype(np.uint16)
    return l16[..., 0] | (l16[..., 1] << 4) | (l16[..., 2] << 8) | (l16[..., 3] << 12)


def unpack(light: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Packed uint16 -> [..., 4] uint8 R,G,B,D (into `out` when given)."""
    light = np.asarray(light, np.uint16)
    if out is None:
        out = np.empty(light.shape + (4,), np.uint8)
    if light.ndim == 0 or light.strides[-1] != 2:
        light = np.ascontiguousarray(light).reshape(light.shape or (1,))
    # bytes (R | G << 4, B | D << 4): low nibbles to lanes 0, 2, high to 1, 3
    b = light.view(np.uint8).reshape(out.shape[:-1] + (2,))
    np.bitwise_and(b, 15, out=out[..., 0::2])
    np.right_shift(b, 4, out=out[..., 1::2])
    return out


def slab(blocks: np.ndarray) -> tuple[int, int]:
    """z range [z0, z1) that needs relaxing; outside it the light is known.

    Above z1 everything is air far from any emitter: D=15, RGB=0 (z1 >= top solid + 2,
    >= top emitter + 15). Below z0 every layer is fully opaque, so those voxels hold
    their emission (layer z0 is still opaque and acts as the fixed floor of the slab).
    Scans layers in bands from the top and the bottom (F order: a band is contiguous).
    """
    cost, _, _, emis, _, air = tables()
    zs = blocks.shape[2]
    only0 = bool(air[0]) and int(air.sum()) == 1  # a compare is ~10x cheaper than a lookup
    top = _scan(blocks, range(zs - 1, -1, -1), (lambda b: b != 0) if only0 else (lambda b: ~_take(air, b)))
    top = -1 if top is None else top
    lit = emis.max(axis=1) > 0
    em = _scan(blocks, range(top, max(top - MAX + 2, 0) - 1, -1), lambda b: _take(lit, b))
    z1 = min(zs, max(top + 2, em + MAX if em is not None else 0, 1))
    clear = _scan(blocks, range(z1), lambda b: _take(cost, b) != OPAQUE_COST)
    z0 = max(0, clear - 1) if clear is not None else max(0, z1 - 1)
    return z0, z1


def _take(table: np.ndarray, b: np.ndarray) -> np.ndarray:
    """table[b] for a band of layers, in its own memory order: np.take without bounds
    checks is ~2x cheaper than indexing (the solve checks the ids)."""
    o = "F" if b.flags.f_contiguous else "C"
    return np.take(table, b.ravel(order=o), mode="clip").reshape(b.shape, order=o)


def _scan(blocks: np.ndarray, zs: range, hit, band: int = 16):
    """First z of `zs` (a step +-1 range) whose layer has any voxel with hit(ids)."""
    zs = list(zs)
    for i in range(0, len(zs), band):
        part = zs[i:i + band]
        lo, hi = min(part), max(part) + 1
        layers = np.flatnonzero(hit(blocks[:, :, lo:hi]).any(axis=(0, 1))) + lo
        layers = [z for z in part if z in set(layers.tolist())]
        if layers:
            return layers[0]
    return None


def start(blocks_t: np.ndarray) -> np.ndarray:
    """Steps 1-2 for a [z, y, x] block slab whose top has open sky above (carry 15).

    Returns lanes [z, y, x, 4] uint8 (R, G, B, D)."""
    _, att, opaque, emis, _, _ = tables()
    a = att[blocks_t].astype(np.int16)[::-1]
    blocked = np.maximum.accumulate(opaque[blocks_t][::-1], axis=0).astype(bool)
    d = np.where(blocked, 0, np.clip(MAX - np.cumsum(a, axis=0), 0, MAX))[::-1]
    lanes = _emis32()[blocks_t] | (d.astype(np.uint32) << 24)
    return np.ascontiguousarray(lanes).view(np.uint8).reshape(blocks_t.shape + (4,))


@lru_cache(maxsize=1)
def _emis32():
    e = tables()[3].astype(np.uint32)
    return e[:, 0] | (e[:, 1] << 8) | (e[:, 2] << 16)  # little-endian lanes R, G, B, D


def relax(lanes: np.ndarray, cost_t: np.ndarray, steps: int = STEPS) -> int:
    """Step 3 by Jacobi iteration (the reference; slow: every step touches every voxel), in place on lanes [z, y, x, 4]; neighbours outside
    are 0. Returns the number of iterations that changed something."""
    zs, ys, xs, _ = lanes.shape
    p = np.zeros((zs + 2, ys + 2, xs + 2, 4), np.uint8)
    p[1:-1, 1:-1, 1:-1] = lanes
    done = relax_padded(p, cost_t, steps)
    lanes[...] = p[1:-1, 1:-1, 1:-1]
    return done


def relax_padded(p: np.ndarray, cost_t: np.ndarray, steps: int = STEPS) -> int:
    """Jacobi relaxation, in place, of the inside of a C-contiguous padded lanes array
    [z+2, y+2, x+2, 4] whose 1-voxel rim holds fixed values; cost_t is [z, y, x].

    Works on the flat array so every neighbour is a contiguous shifted slice; rim
    voxels inside the flat range get cost 255 and so never change."""
    c = np.full(p.shape[:3], OPAQUE_COST, np.uint8)
    c[1:-1, 1:-1, 1:-1] = cost_t
    f = p.reshape(-1)
    sx, sy, sz = 4, 4 * p.shape[2], 4 * p.shape[2] * p.shape[1]
    lo = sz + sy + sx
    hi = f.size - lo
    if hi <= lo:
        return 0
    cc = np.repeat(c.reshape(-1), 4)[lo:hi]
    cur = f[lo:hi]
    m = np.empty_like(cur)
    done = 0
    for _ in range(steps):
        np.maximum(f[lo - sx:hi - sx], f[lo + sx:hi + sx], out=m)
        for o in (sy, sz):
            np.maximum(m, f[lo - o:hi - o], out=m)
            np.maximum(m, f[lo + o:hi + o], out=m)
        np.maximum(m, cc, out=m)
        m -= cc  # saturating m - cost (opaque cost 255 -> 0)
        np.maximum(m, cur, out=m)
        if np.array_equal(m, cur):
            break
        cur[...] = m
        done += 1
    return done
