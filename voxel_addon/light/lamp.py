"""A one-colour lamp set or taken out, in an incremental relight (incremental.update),
by component (they share only the costs): its colour flooded from the lamp alone
over the voxels within its reach (relight), or cleared and refilled on that lane
alone (refill), the other components on the sparse path (placed, taken); cheaper
than the box path, which unpacks, floods and packs all four components of a
29-voxel box (issue 29: a lamp click's relight)."""
from __future__ import annotations

import threading
from functools import lru_cache

import numpy as np

from . import flood, model, sparse

SHIFTS = flood.SHIFTS
LANES = 1  # rising components relight floods one by one (more: the box, all at once)


def relight(blocks, light, x, y, z, pval, part=False):
    """incremental.update's box path for p's new light `pval` (from its _local: only
    p changed, its rising components spread, nothing else falls; or a lamp set
    where no colour passed, its daylight relit already: placed) with one lane and
    no removal: each rising component floods from p alone over the voxels within
    its reach (value v: v - 1 steps), the rest of the light as it is. Writes p and
    the raised lanes, returns their bounds; None (nothing written) for more rising
    components than LANES, or with `part` where the reach meets the arrays' side
    faces."""
    w, h, zs = blocks.shape
    lp = light.item(x, y, z)
    rise = [(k, v) for k, v in enumerate(pval) if v > (lp >> SHIFTS[k]) & 15]
    if len(rise) > LANES:
        return None
    r = max([v for _, v in rise] + [1]) - 1
    if part and not inside(blocks.shape, x, y, r):
        return None
    light[x, y, z] = pval[0] | pval[1] << 4 | pval[2] << 8 | pval[3] << 12
    lo, hi = [x, y, z], [x + 1, y + 1, z + 1]
    if not rise or r < 1:
        return tuple(slice(a, b) for a, b in zip(lo, hi))
    sx = slice(max(x - r, 0), min(x + r + 1, w))
    sy = slice(max(y - r, 0), min(y + r + 1, h))
    sz = slice(max(z - r, 0), min(z + r + 1, zs))
    nx, ny, nz = sx.stop - sx.start, sy.stop - sy.start, sz.stop - sz.start
    gy, gz = nx + 2, (nx + 2) * (ny + 2)  # a one-voxel rim that never rises
    cost = _costs(blocks, sx, sy, sz)
    near = light[sx, sy, sz].T
    p = (z - sz.start + 1) * gz + (y - sy.start + 1) * gy + x - sx.start + 1
    for k, v in rise:
        fc = cost.copy()  # value + cost: >= 16 never rises (opaque, the rim)
        fc[1:-1, 1:-1, 1:-1] += ((near >> SHIFTS[k]) & 15).astype(np.uint8)
        fc = fc.reshape(-1)
        fc[p] = 255  # p holds its exact value
        n, nv = flood.spread(fc, cost.reshape(-1), [p], [v], gy, gz)
        if not n.size:
            continue
        i = n % gy + (sx.start - 1)
        j = n // gy % (ny + 2) + (sy.start - 1)
        l = n // gz + (sz.start - 1)
        m = ~np.uint16(15 << SHIFTS[k])
        light[i, j, l] = (light[i, j, l] & m) | (nv.astype(np.uint16) << SHIFTS[k])
        lo = [min(a, int(b.min())) for a, b in zip(lo, (i, j, l))]
        hi = [max(a, int(b.max()) + 1) for a, b in zip(hi, (i, j, l))]
    return tuple(slice(a, b) for a, b in zip(lo, hi))


def refill(blocks, light, x, y, z, k):
    """Component k after p stopped emitting it (a lamp taken out; p's cost did not
    rise): what may owe itself to p's old value is cleared (incremental._remove on
    one lane), given its start values back and refilled from around (flood.spread).
    Changes lie within 14 of p (the cleared voxels, and what p, now passing light,
    lets through), reads within 15. Writes lane k, returns the written bounds."""
    w, h, zs = blocks.shape
    r, sh = model.MAX, SHIFTS[k]
    sx = slice(max(x - r, 0), min(x + r + 1, w))
    sy = slice(max(y - r, 0), min(y + r + 1, h))
    sz = slice(max(z - r, 0), min(z + r + 1, zs))
    nx, ny, nz = sx.stop - sx.start, sy.stop - sy.start, sz.stop - sz.start
    gy, gz = nx + 2, (nx + 2) * (ny + 2)  # a one-voxel rim: dark, never rises
    cost = _costs(blocks, sx, sy, sz)
    cost = cost.reshape(-1)
    f = np.zeros((nz + 2, ny + 2, nx + 2), np.uint8)
    f[1:-1, 1:-1, 1:-1] = (light[sx, sy, sz].T >> sh) & 15
    f = f.reshape(-1)
    offs = np.array([-1, 1, -gy, gy, -gz, gz], np.int64)
    p = (z - sz.start + 1) * gz + (y - sy.start + 1) * gy + x - sx.start + 1
    idx, val = np.array([p], np.int64), f[[p]].astype(np.int16)
    f[p] = 0
    out = [idx]
    while idx.size:  # every neighbour below the voxel it was reached from may owe it
        n = (idx[:, None] + offs).ravel()
        v = f[n]
        n = np.unique(n[(v > 0) & (v < np.repeat(val, 6)) & (cost[n] <= model.MAX)])
        if not n.size:
            break
        val = f[n].astype(np.int16)
        f[n] = 0
        out.append(n)
        idx, val = n[val > 1], val[val > 1]
    gone = np.unique(np.concatenate(out))
    i = gone % gy + (sx.start - 1)
    j = gone // gy % (ny + 2) + (sy.start - 1)
    l = gone // gz + (sz.start - 1)
    f[gone] = np.minimum(model.tables()[3][blocks[i, j, l], k], model.MAX)  # start values
    seeds = np.concatenate([gone, (gone[:, None] + offs).ravel()])
    seeds = seeds[f[seeds] > 1]
    fc = f + np.minimum(cost, model.MAX + 1)  # the rim: 0 + 16, never rises
    n, nv = flood.spread(fc, cost, seeds, f[seeds], gy, gz)
    f[n] = nv
    v = np.concatenate([gone, n])
    i = v % gy + (sx.start - 1)
    j = v // gy % (ny + 2) + (sy.start - 1)
    l = v // gz + (sz.start - 1)
    m = ~np.uint16(15 << sh)
    light[i, j, l] = (light[i, j, l] & m) | (f[v].astype(np.uint16) << sh)
    return tuple(slice(int(a.min()), int(a.max()) + 1) for a in (i, j, l))


def placed(blocks, light, x, y, z, old, new, now, zc, brighter, part):
    """A lamp set where no colour passed (an opaque emitter in place of a block that
    emits nothing, p's colours at most 1 before): its daylight falls (p's and the
    column's below: sparse.relight on that lane alone) and its colours rise from p
    alone (relight); the components are independent. Nothing written and None
    otherwise, or where sparse.relight would leave it to the box."""
    cost_l, _, _, emis_l = model.lists()
    e = emis_l[new]
    lp = light.item(x, y, z)
    if (any(emis_l[old]) or cost_l[new] != model.OPAQUE_COST
            or any((lp >> SHIFTS[k]) & 15 > 1 for k in range(3))
            or sum(v > (lp >> SHIFTS[k]) & 15 for k, v in enumerate(e)) > LANES
            or part and not inside(blocks.shape, x, y, max(e) - 1)):
        return None
    try:
        box = sparse.relight(blocks, light, x, y, z, now, zc, brighter, part,
                             lanes=(3,))
    except sparse.Beyond:
        return None
    if box is None:
        return None
    got = relight(blocks, light, x, y, z, e + [light.item(x, y, z) >> 12], part)
    return tuple(slice(min(a.start, b.start), max(a.stop, b.stop)) if a.stop > a.start
                 else b for a, b in zip(box, got))


def taken(blocks, light, x, y, z, old, new, now, before, zc, part):
    """A one-colour lamp taken out (its block's cost not rising, no emission and no
    daylight falling): the other components only gain (sparse.relight, brighter,
    on them alone), its colour is cleared and refilled on that lane alone (refill).
    Nothing written and None otherwise, or where sparse.relight would leave it to
    the box."""
    cost_l, _, _, emis_l = model.lists()
    cols = [k for k, e in enumerate(emis_l[old]) if e]
    if (len(cols) != 1 or any(emis_l[new]) or cost_l[new] > cost_l[old]
            or not (now >= before).all()
            or part and not inside(blocks.shape, x, y, model.MAX)):
        return None
    k = cols[0]
    try:
        box = sparse.relight(blocks, light, x, y, z, now, zc, True, part,
                             lanes=tuple(c for c in range(4) if c != k))
    except sparse.Beyond:
        return None
    if box is None:
        return None
    got = refill(blocks, light, x, y, z, k)
    return tuple(slice(min(a.start, b.start), max(a.stop, b.stop)) if a.stop > a.start
                 else b for a, b in zip(box, got))


def inside(shape, x, y, r) -> bool:
    """Whether columns within r of (x, y) stay off the arrays' side faces."""
    return 0 < x - r and x + r < shape[0] - 1 and 0 < y - r and y + r < shape[1] - 1


_local = threading.local()


def _costs(blocks, sx, sy, sz) -> np.ndarray:
    """(nz + 2, ny + 2, nx + 2) uint8: _cost16 of blocks[sx, sy, sz] (z, y, x order)
    inside an opaque rim. The ids go through this thread's intp scratch: NumPy's take
    converts uint16 ids to a fresh intp copy (~200 KB for a lamp's 29-voxel box: its
    page faults, ~0.1 ms of a lamp click)."""
    b = blocks[sx, sy, sz].T
    cost = np.full(tuple(n + 2 for n in b.shape), model.OPAQUE_COST, np.uint8)
    idx = getattr(_local, "idx", None)
    if idx is None or idx.size < b.size:
        idx = _local.idx = np.empty(max(b.size, 1 << 15), np.intp)
    i = idx[:b.size].reshape(b.shape)
    i[...] = b
    cost[1:-1, 1:-1, 1:-1] = np.take(_cost16(), i, mode="clip")
    return cost


@lru_cache(maxsize=1)
def _cost16() -> np.ndarray:
    """Per block id its cost capped at 16 (relight's value + cost stays in a uint8)."""
    return np.minimum(model.tables()[0], model.MAX + 1).astype(np.uint8)
