"""Incremental relight after one block edit (issue 4 §2); equals a full `solve`.

Why the box is enough: only the start values of the edited voxel p and of its column
below p can change, and a changed value travels at most 14 steps. So light can only
change within horizontal distance 14 of column (x, y) and between 14 below the lowest
changed start value and 14 above p. Everything outside that box is the old (exact)
light, so the box is re-solved from scratch with its 1-voxel rim held fixed: a path
from outside enters the box through the rim, whose values already account for it.

Otherwise (darkening, e.g. clearing a lamp or closing a daylight shaft) light that
may have come through the changed voxels is removed first, as in Minecraft's light
removal: from each changed lane outwards, every neighbour whose value is below the
value of the voxel it was reached from could owe its light to it and is cleared
(over-clearing is harmless). What stays is then a lower bound of the new light
(any remaining value has a path from an unchanged source avoiding cleared voxels).
The cleared voxels get their start values back and, with the voxels around them,
seed the flood to the fixpoint. Work follows the light that moved, not the box.

When the edit can only add light (p's cost does not rise and no emission falls, e.g.
placing a lamp or digging out a block), the new light is >= the old everywhere and is
the fixpoint reached from max(old light, new start values): the box keeps the old
light and floods only from the voxels whose start value rose (flood.py).

The four components are independent (they share only the costs): a lamp of one
colour set where no colour passed, or taken out, is relit per component (lamp.py),
not as a box: its colour on one lane, the others on the sparse path (sparse.py).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..core import chunk
from . import flood, lamp, model, sparse

R = model.MAX - 1  # reach of a change


@lru_cache(maxsize=1)
def _lut() -> np.ndarray:
    """Packed uint16 light -> its four lanes as one little-endian uint32 (256 KiB):
    one gather unpacks a box."""
    return model.unpack(np.arange(1 << 16, dtype=np.uint16)).view(np.uint32).reshape(-1)


STATS = {"local": 0, "sparse": 0, "lamp": 0, "box": 0}  # how edits were relit (tests check each runs)
SPARSE_EMISSION = 3  # a lamp placed or removed floods thousands of voxels: box at once
SHIFTS = (0, 4, 8, 12)


def _local(blocks, light, x, y, z, now, zc, brighter):
    """Relight an edit that changes no voxel but p = (x, y, z), as most edits do
    (digging in the dark or in the open, a block placed where nothing depends on the
    light at p):
    p's new light, written, and its box; None when other voxels may lose light; p's
    new light (a list, nothing written) when only p's brighter components spread (a
    lamp set in the open: the box floods from p, no removal). Exact because:
    - p's new value is max(start, neighbour - cost) per component (an opaque p holds
      its emission) with every other voxel unchanged;
    - a p that brightens raises nothing unless some neighbour n < value - cost(n)
      (a block dug out in the open: its neighbours are in daylight already);
    - a p that darkens from v >= 2 only darkens a neighbour n whose value is v -
      cost(n) if n has no other support: its emission, or a neighbour m != p with
      L(m) - cost(n) >= L(n); such an m has L(m) >= v, so its own best path cannot
      run through p (that would leave it <= v - 2): n keeps its value, and so does
      everything lit through n;
    - the column below p: rising start values there must not exceed the old light
      (brighter edits); a darker edit must not change it at all."""
    w, h, zs = blocks.shape
    if zc < z and not (brighter and (now[zc:z] <= (light[x, y, zc:z] >> 12)).all()):
        return None
    new = blocks.item(x, y, z)
    nb = [q for q in ((x - 1, y, z), (x + 1, y, z), (x, y - 1, z), (x, y + 1, z),
                      (x, y, z - 1), (x, y, z + 1))
          if 0 <= q[0] < w and 0 <= q[1] < h and 0 <= q[2] < zs]
    cost_l, _, _, emis_l = model.lists()
    lp = light.item(x, y, z)
    was = [(lp >> k) & 15 for k in SHIFTS]
    c = cost_l[new]
    e = emis_l[new]
    if c == model.OPAQUE_COST:
        val = e + [0]
    else:
        val = e + [int(now[z])]
        for q in nb:
            lq = light.item(q)
            val = [max(a, ((lq >> k) & 15) - c) for a, k in zip(val, SHIFTS)]
    spreads = False
    for k, (a, b) in enumerate(zip(val, was)):
        if a > b and a > 1 and _raises(blocks, light, nb, k, a):
            spreads = True  # p shines further than before
        if a < b and b > 1 and not _kept(blocks, light, (x, y, z), nb, k, b):
            return None
    if spreads:
        return val
    if val == was:
        return (slice(x, x), slice(y, y), slice(z, z))
    light[x, y, z] = val[0] | val[1] << 4 | val[2] << 8 | val[3] << 12
    return (slice(x, x + 1), slice(y, y + 1), slice(z, z + 1))


def _raises(blocks, light, nb, k, v):
    """Whether p at value v of component k raises one of its neighbours `nb`."""
    cost_l = model.lists()[0]
    sh = SHIFTS[k]
    return any(v - cost_l[blocks.item(q)] > (light.item(q) >> sh) & 15 for q in nb)


def _kept(blocks, light, p, nb, k, v):
    """Whether every neighbour of p that may owe component k to p's old value v has
    another support (see _local)."""
    cost_l, _, _, emis_l = model.lists()
    w, h, zs = blocks.shape
    sh = SHIFTS[k]
    for q in nb:
        bq = blocks.item(q)
        cq = cost_l[bq]
        lq = (light.item(q) >> sh) & 15
        if cq == model.OPAQUE_COST or lq != v - cq or lq == 0:
            continue  # opaque, lit better elsewhere, or dark anyway
        if k < 3 and emis_l[bq][k] >= lq:
            continue
        i, j, l = q
        if not any(0 <= m[0] < w and 0 <= m[1] < h and 0 <= m[2] < zs and m != p
                   and ((light.item(m) >> sh) & 15) - cq >= lq
                   for m in ((i - 1, j, l), (i + 1, j, l), (i, j - 1, l), (i, j + 1, l),
                             (i, j, l - 1), (i, j, l + 1))):
            return False
    return True


def update(blocks: np.ndarray, light: np.ndarray, x: int, y: int, z: int, old: int,
           part: bool = False):
    """Fix `light` (the exact `solve` of the array before the edit) in place after
    blocks[x, y, z] changed from block id `old` to its current value.

    Returns a box holding every voxel whose light changed, as slices (sx, sy, sz)
    of the array (outside it `light` is untouched): the written voxels' bounds,
    usually far smaller than the relight box (callers copy it out).

    `part`: the arrays are only part of the world's columns around (x, y) (at least
    3 on each side), so their sides are no boundary: relit where the light reads no
    voxel on their side faces (the local and sparse paths), else None and nothing
    written (the caller then relights on every column the relight box reaches)."""
    new = int(blocks[x, y, z])
    w, h, zs = blocks.shape
    if old == new:
        return (slice(x, x), slice(y, y), slice(z, z))
    cost_t, _, _, emis, _, _ = model.tables()
    now, before = sparse.column_days(blocks, x, y, z, old)
    diff = np.flatnonzero(now != before)
    zc = int(diff[0]) if diff.size else z
    cost_l, _, _, emis_l = model.lists()
    en, eo = emis_l[new], emis_l[old]
    brighter = (cost_l[new] <= cost_l[old] and all(a >= b for a, b in zip(en, eo))
                and bool((now >= before).all()))
    box = _local(blocks, light, x, y, z, now, zc, brighter)
    if isinstance(box, tuple):
        STATS["local"] += 1
        return box
    pval = box  # p's exact new light when only its rising components must flood
    if max(en + eo) <= SPARSE_EMISSION:
        try:
            box = sparse.relight(blocks, light, x, y, z, now, zc, brighter, part)
        except sparse.Beyond:
            return None
        if box is not None:
            STATS["sparse"] += 1
            return box
    if pval is not None:
        box = lamp.relight(blocks, light, x, y, z, pval, part)
    else:
        box = lamp.placed(blocks, light, x, y, z, old, new, now, zc, brighter, part)
        if box is None:
            box = lamp.taken(blocks, light, x, y, z, old, new, now, before, zc, part)
    if box is not None:
        STATS["lamp"] += 1
        return box
    if part:
        return None
    STATS["box"] += 1
    sx = slice(max(x - R, 0), min(x + R + 1, w))
    sy = slice(max(y - R, 0), min(y + R + 1, h))
    sz = slice(max(zc - R, 0), min(z + R + 1, zs))
    # Padded box (flood.grid): the rim is the current light (0 outside the array).
    ex = slice(max(sx.start - 1, 0), min(sx.stop + 1, w))
    ey = slice(max(sy.start - 1, 0), min(sy.stop + 1, h))
    ez = slice(max(sz.start - 1, 0), min(sz.stop + 1, zs))
    nx, ny, nz = sx.stop - sx.start, sy.stop - sy.start, sz.stop - sz.start
    shape, (gy, gz) = flood.grid((nz, ny, nx))
    f = np.zeros(shape + (4,), np.uint8)  # lanes: all components flood at once
    ox, oy, oz = 1 - (sx.start - ex.start), 1 - (sy.start - ey.start), 2 - (sz.start - ez.start)
    f.view(np.uint32).reshape(shape)[oz:oz + ez.stop - ez.start, oy:oy + ey.stop - ey.start,
                                     ox:ox + ex.stop - ex.start] = np.take(
        _lut(), light[ex, ey, ez].T, mode="clip")
    cost = np.full(shape, model.OPAQUE_COST, np.uint8)
    cost[2:-2, 1:-1, 1:-1] = np.take(cost_t, blocks[sx, sy, sz].T, mode="clip")
    px, py = x - sx.start + 1, y - sy.start + 1
    if brighter or pval is not None:
        # Old light stays; raise p and the column below it to their new start values
        # (or set p to its new light: what fell there took nothing else with it).
        pz = np.arange(zc, z + 1) - sz.start + 2
        new_start = np.zeros((pz.size, 4), np.uint8)
        new_start[:, 3] = now[zc:z + 1]
        new_start[-1, :3] = emis[new]
        f[pz, py, px] = np.maximum(f[pz, py, px], new_start)
        if cost_t[new] == model.OPAQUE_COST:  # an opaque voxel holds exactly its emission
            f[pz[-1], py, px] = new_start[-1]
        if pval is not None:
            f[pz[-1], py, px] = pval
        vox = pz * gz + py * gy + px
        # ... and p's neighbours, which may now shine into it (its cost may have dropped).
        vox = np.concatenate([vox, vox[-1] + np.array([-1, 1, -gy, gy, -gz, gz])])
        seeds = (4 * vox.astype(np.int64)[:, None] + np.arange(4)).ravel()
        written = [4 * vox[:-6].astype(np.int64)]
    else:
        pz = np.arange(zc, z + 1) - sz.start + 2
        vox = pz * gz + py * gy + px
        # the changed lanes: every component of p, daylight of the column below it
        lanes = np.concatenate([4 * vox[:-1] + 3, 4 * vox[-1] + np.arange(4)])
        seeds, gone = _remove(f.reshape(-1), cost.reshape(-1), lanes, blocks,
                              (sx.start, sy.start, sz.start), (gy, gz))
        written = [gone]
        # ... and p's neighbours, which may now shine into it (its cost may have dropped)
        seeds = np.concatenate([seeds, (4 * (vox[-1] + np.array([-1, 1, -gy, gy, -gz, gz]))
                                        [:, None] + np.arange(4)).ravel()])
    # value + cost per lane (a cost >= 16 blocks like 255 does and cannot overflow)
    fc = f.view(np.uint32).reshape(shape) + (np.minimum(cost, model.MAX + 1).astype(np.uint32)
                                             * np.uint32(0x01010101))  # 4 lanes a word
    fc = fc.view(np.uint8).reshape(-1)
    fl, cost = f.reshape(-1), cost.reshape(-1)
    n, nv = flood.levels_lanes(fc, cost, seeds, fl[seeds], gy, gz)
    fl[n] = nv
    written.append(n)
    # only the written voxels can differ: pack and store their bounds (padded grid
    # coordinates: the inside starts at x, y = 1 and z = 2, flood.grid)
    v = np.concatenate(written) >> 2
    zz, yy, xx = v // gz, v % gz // gy, v % gy
    lo = [max(int(a.min()), o) for a, o in ((xx, 1), (yy, 1), (zz, 2))]
    hi = [min(int(a.max()) + 1, o + n) for a, o, n in ((xx, 1, nx), (yy, 1, ny), (zz, 2, nz))]
    if any(b <= a for a, b in zip(lo, hi)):
        return (slice(x, x), slice(y, y), slice(z, z))
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    bx = slice(sx.start + x0 - 1, sx.start + x1 - 1)
    by = slice(sy.start + y0 - 1, sy.start + y1 - 1)
    bz = slice(sz.start + z0 - 2, sz.start + z1 - 2)
    light[bx, by, bz] = model.pack(f[z0:z1, y0:y1, x0:x1]).T
    return bx, by, bz


def _remove(f, cost, lanes, blocks, base, strides):
    """Clear light that may owe itself to `lanes` (flat lane indices of the padded
    box `f`, whose start values changed) and restore the start values of what was
    cleared. Returns the seeds that refill it (the cleared lanes and their
    neighbours) and the cleared lanes. `base` = array coordinates of the box's first inside voxel."""
    gy, gz = strides
    offs = 4 * np.array([-1, 1, -gy, gy, -gz, gz], np.int64)
    idx = np.asarray(lanes, np.int64)
    val = f[idx].astype(np.int16)
    f[idx] = 0
    out = [idx]
    live = val > 1  # a 1 lights nothing around it
    idx, val = idx[live], val[live]
    while idx.size:
        n = (idx[:, None] + offs).ravel()
        v = f[n]
        m = (v > 0) & (v < np.repeat(val, 6)) & (cost[n >> 2] != model.OPAQUE_COST)
        n = np.unique(n[m])
        if not n.size:
            break
        val = f[n].astype(np.int16)
        f[n] = 0
        out.append(n)
        idx = n[val > 1]
        val = val[val > 1]
    gone = np.unique(np.concatenate(out))
    f[gone] = _starts(gone, blocks, base, gy, gz)
    near = (gone[:, None] + offs).ravel()
    return np.concatenate([gone, near[f[near] > 1]]), gone


def _starts(lanes, blocks, base, gy, gz):
    """Start values (emission, column daylight) of flat lanes of the padded box."""
    _, att, opaque, emis, _, _ = model.tables()
    v = lanes >> 2
    c = lanes & 3
    x = v % gy - 1 + base[0]
    y = v // gy % (gz // gy) - 1 + base[1]
    z = v // gz - 2 + base[2]
    ids = blocks[x, y, z]
    out = np.zeros(lanes.size, np.uint8)
    rgb = c < 3
    out[rgb] = emis[ids[rgb], c[rgb]]
    d = ~rgb
    if d.any():
        cols, inv = np.unique(x[d] * blocks.shape[1] + y[d], return_inverse=True)
        z0 = int(z[d].min())
        col = blocks[cols // blocks.shape[1], cols % blocks.shape[1], z0:]  # (n, zs - z0)
        a = np.cumsum(att[col[:, ::-1]].astype(np.int16), axis=1)[:, ::-1]
        blocked = np.maximum.accumulate(opaque[col[:, ::-1]], axis=1)[:, ::-1].astype(bool)
        day = np.where(blocked, 0, np.clip(model.MAX - a, 0, model.MAX))
        out[d] = day[inv, z[d] - z0]
    return out


def edit(blocks: np.ndarray, light: np.ndarray, x: int, y: int, z: int, block: int):
    """Set blocks[x, y, z] = block and relight incrementally; returns the changed box."""
    chunk.check_z(z)
    old = int(blocks[x, y, z])
    blocks[x, y, z] = block
    return update(blocks, light, x, y, z, old)
