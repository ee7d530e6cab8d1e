"""The incremental relight (incremental.update) in plain Python on the voxels it
touches, for an edit whose light barely moves (leaves or water on top: the daylight
of the column below p changes), or for some components of one (a lamp: lamp.py);
and the column-pass daylight of one column before and after an edit."""
from __future__ import annotations

import numpy as np

from . import model

BUDGET = 200  # lane writes a sparse relight may make before it leaves it to the box


def column_days(blocks: np.ndarray, x: int, y: int, z: int, old: int) -> np.ndarray:
    """Column-pass daylight of column (x, y) at layers 0..z with the block at z as it
    is now (row 0) and as `old` (row 1): (2, z + 1). Walked down in Python from the
    column's highest block below z to the first opaque voxel or the first 0 (below
    both it stays 0): a few layers at the surface, where NumPy's calls over the
    whole column cost more."""
    _, att, opaque, _, _, _ = model.tables()
    _, att_l, opaque_l, _ = model.lists()
    above = blocks[x, y, z + 1:]
    carry = model.MAX if not above.any() else \
        0 if opaque[above].any() else max(model.MAX - int(att[above].sum()), 0)
    out = np.zeros((2, z + 1), np.int16)
    item = blocks.item
    below = np.flatnonzero(blocks[x, y, :z])
    t = int(below[-1]) if below.size else -1    # air from t + 1 up to z: the carry stays
    for r, b in enumerate((item(x, y, z), old)):
        if opaque_l[b]:
            continue
        c = carry - att_l[b]
        if c <= 0:
            continue
        out[r, t + 1:z + 1] = c
        k = t
        while k >= 0:
            b = item(x, y, k)
            if opaque_l[b]:
                break
            c -= att_l[b]
            if c <= 0:
                break
            out[r, k] = c
            k -= 1
    return out


class Beyond(Exception):
    """relight with `part` reached the arrays' side faces."""


def relight(blocks, light, x, y, z, now, zc, brighter, part=False, lanes=(0, 1, 2, 3)):
    """The box path's relight (removal, then a brightest-first refill) in plain Python
    on the voxels it touches, for an edit whose light barely moves (leaves or water on
    top: the daylight of the column below p changes); None (nothing written) once it
    has written BUDGET lanes or, with `part` (see update), read a voxel on the
    arrays' side faces (the voxels it reads are those whose neighbours it visits).
    Its per-voxel reads are dict hits inlined in the loops (calls cost more here), a
    voxel keyed by its flat C-order index (as .item reads it: an int hashes and
    offsets faster than a tuple).
    `lanes`: the components it relights (the others stay as they are: lamp.py)."""
    cost_l, _, _, emis_l = model.lists()
    w, h, zs = blocks.shape
    SX, SY = h * zs, zs  # the key's steps in x and y (z: 1)
    last = (w - 1) * SX
    OPAQUE = model.OPAQUE_COST
    bitem, litem = blocks.item, light.item
    cur: dict = {}  # voxel -> its four lanes as now (read from `light` on first use)
    was: dict = {}  # voxel -> its packed light as read
    costs: dict = {}
    nbs: dict = {}  # voxel -> its neighbours in the arrays
    days: dict = {}  # column -> its column-pass daylight (blocks as they are now)

    def get(v):
        lv = cur.get(v)
        if lv is None:
            if part and not (SX <= v < last and 0 < v // SY % h < h - 1):
                raise Beyond
            pv = was[v] = litem(v)
            lv = cur[v] = [pv & 15, pv >> 4 & 15, pv >> 8 & 15, pv >> 12]
        return lv

    def cost(v):
        c = costs[v] = cost_l[bitem(v)]
        return c

    def near(v):
        k = v % SY
        j = v // SY % h
        out = []
        if v >= SX:
            out.append(v - SX)
        if v < last:
            out.append(v + SX)
        if j > 0:
            out.append(v - SY)
        if j < h - 1:
            out.append(v + SY)
        if k > 0:
            out.append(v - 1)
        if k < zs - 1:
            out.append(v + 1)
        nbs[v] = out
        return out

    def start(v, c):
        if c < 3:
            return emis_l[bitem(v)][c]
        col = days.get(v // SY)
        if col is None:
            i, j = divmod(v // SY, h)
            col = days[v // SY] = column_days(blocks, i, j, zs - 1, bitem(i, j, zs - 1))[0]
        return int(col[v % SY])

    p = (x * h + y) * SY + z
    column = [p - z + k for k in range(zc, z)]
    seeds = [(q, c) for q in near(p) for c in lanes]
    day = 3 in lanes
    writes = 0
    if brighter:
        for q in column if day else ():
            lq = get(q)
            lq[3] = max(lq[3], int(now[q - p + z]))
        lp = get(p)
        e = emis_l[bitem(p)] + [int(now[z])]
        top = (costs.get(p) or cost(p)) == OPAQUE
        for c in lanes:
            lp[c] = e[c] if top else max(lp[c], e[c])
        seeds += [(q, 3) for q in column if day] + [(p, c) for c in lanes]
    else:  # removal from the changed lanes, as _remove does
        stack = []
        gone = [(q, 3) for q in column if day] + [(p, c) for c in lanes]
        for q, c in gone:
            lq = get(q)
            if lq[c] > 1:
                stack.append((q, c, lq[c]))
            lq[c] = 0
        while stack:
            q, c, val = stack.pop()
            for n in nbs.get(q) or near(q):
                ln = cur.get(n) or get(n)
                if 0 < ln[c] < val and (costs.get(n) or cost(n)) != OPAQUE:
                    writes += 1
                    if writes > BUDGET:
                        return None
                    if ln[c] > 1:
                        stack.append((n, c, ln[c]))
                    ln[c] = 0
                    gone.append((n, c))
        for q, c in gone:
            get(q)[c] = start(q, c)
        seeds += gone + [(n, c) for q, c in gone for n in (nbs.get(q) or near(q))]
    buckets: list = [[] for _ in range(model.MAX + 1)]
    for q, c in seeds:
        buckets[(cur.get(q) or get(q))[c]].append((q, c))
    for val in range(model.MAX, 1, -1):
        for q, c in buckets[val]:
            if cur[q][c] != val:
                continue  # raised since: done at its new value
            for n in nbs.get(q) or near(q):
                nv = val - (costs.get(n) or cost(n))
                ln = cur.get(n) or get(n)
                if nv > ln[c]:
                    writes += 1
                    if writes > BUDGET:
                        return None
                    ln[c] = nv
                    buckets[nv].append((n, c))
    lo, hi = [x, y, z], [x, y, z]
    moved = False
    for v, lv in cur.items():
        pv = lv[0] | lv[1] << 4 | lv[2] << 8 | lv[3] << 12
        if pv != was[v]:
            i, j = divmod(v // SY, h)
            k = v % SY
            light[i, j, k] = pv
            moved = True
            lo = [min(lo[0], i), min(lo[1], j), min(lo[2], k)]
            hi = [max(hi[0], i), max(hi[1], j), max(hi[2], k)]
    if not moved:
        return (slice(x, x), slice(y, y), slice(z, z))
    return tuple(slice(a, b + 1) for a, b in zip(lo, hi))
