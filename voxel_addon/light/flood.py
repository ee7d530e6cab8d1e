"""Sparse NumPy relaxation: push light outwards from seed voxels only (the NumPy full
solve and the incremental relight).

Works on a padded C-order grid [z, y, x] flattened (`grid`): per voxel `cost` (uint8,
1 + attenuation; OPAQUE_COST for voxels that never receive: opaque blocks, the fixed
rim and two guard layers in z) and per component `fc` = value + cost (uint8). A voxel
at value v raises its neighbour n iff v > fc[n], to v - cost[n]: one gather and a
compare per candidate. Values are processed brightest first (`levels`: Dial's
buckets, 15 down to 2), so each voxel is written once, with its final value, and
when the buckets empty the grid is at the fixpoint of model.relax provided every
voxel whose start value can raise a neighbour was a seed (`edge` finds them densely
in a range of layers). Work is proportional to the light that actually moves (~5 %
of a generated slab), not to the volume. `levels_lanes` floods all four components
of a small box at once (the incremental relight).
"""
from __future__ import annotations

import threading

import numpy as np

from . import model

SHIFTS = (0, 4, 8, 12)  # R, G, B, D


def grid(shape_zyx: tuple[int, int, int]) -> tuple[tuple[int, int, int], tuple[int, int]]:
    """Padded shape for an inside of shape (z, y, x): 1 rim voxel around, plus one guard
    layer below and above in z so flat neighbour indices of rim voxels stay in range
    (x/y neighbours of the rim wrap onto rim voxels). Returns (shape, (sy, sz))."""
    z, y, x = shape_zyx
    return (z + 4, y + 2, x + 2), (x + 2, (x + 2) * (y + 2))


def levels(fc: np.ndarray, cost: np.ndarray, seeds: np.ndarray, vals: np.ndarray,
           sy: int, sz: int):
    """Flood one component to the fixpoint from `seeds` (distinct flat voxel indices,
    start values `vals`), brightest first (Dial's buckets, as Minecraft's light queue).

    `fc` holds per voxel value + cost (uint8; >= 16 never rises: opaque, rim): a source
    at v raises n iff v > fc[n], to v - cost[n], after which fc[n] = v. Processing the
    values from 15 down, a voxel is written once, with its final value (every better
    path comes through a brighter voxel, done earlier). One neighbour direction at a
    time, each claiming what it raised before the next looks, so every voxel enters a
    bucket once and no scatter has duplicates. Returns the written (indices, value)
    per level."""
    offs = (-1, 1, -sy, sy, -sz, sz)
    buckets = [[] for _ in range(model.MAX + 1)]
    seeds = np.asarray(seeds, np.int64)
    vals = np.asarray(vals)
    for v in np.unique(vals).tolist():
        if v > 1:
            buckets[v].append(seeds[vals == v])
    out = []
    for v in range(model.MAX, 1, -1):
        if not buckets[v]:
            continue
        idx = buckets[v][0] if len(buckets[v]) == 1 else np.concatenate(buckets[v])
        buckets[v] = None
        got = []
        for o in offs:  # a stale seed (raised since) finds nothing: harmless
            t = idx + o
            t = t[fc[t] < v]
            fc[t] = v
            got.append(t)
        n = np.concatenate(got)
        if not n.size:
            continue
        c = cost[n]
        if (c == 1).all():  # the common case: plain air
            out.append((n, v - 1))
            if v > 2:
                buckets[v - 1].append(n)
            continue
        for k in np.unique(c).tolist():
            t = n[c == k]
            out.append((t, v - k))
            if v - k > 1:
                buckets[v - k].append(t)
    return out


def edge(fc: np.ndarray, cost: np.ndarray, offs, lo: int, hi: int):
    """Flat indices in [lo, hi) (of a `levels` grid) whose value can raise a neighbour
    at one of the offsets `offs` (positive; both directions are checked) right now,
    and their values: v = fc - cost raises n iff v > fc[n]. A dense check, one
    Jacobi step's worth of work on that range."""
    assert lo >= max(offs) and hi + max(offs) <= fc.size
    v = fc[lo:hi] - cost[lo:hi]  # opaque and rim: 255 - 255 = 0
    o = offs[0]
    low = np.minimum(fc[lo + o:hi + o], fc[lo - o:hi - o])
    for o in offs[1:]:  # the neighbour easiest to raise decides
        np.minimum(low, fc[lo + o:hi + o], out=low)
        np.minimum(low, fc[lo - o:hi - o], out=low)
    i = np.flatnonzero(v > low)
    return i + lo, v[i]


_local = threading.local()


def _scratch(size: int):
    """This thread's int32 scratch of at least SIZE (stale values) and a ramp 0..4095:
    a fresh owner array per relight (144-576 KB) cost its page faults every edit."""
    a = getattr(_local, "owner", None)
    if a is None or a.size < size:
        a = _local.owner = np.empty(max(size, 1 << 16), np.int32)
        _local.ramp = np.arange(4096, dtype=np.int32)
    return a, _local.ramp


def levels_lanes(fc: np.ndarray, cost: np.ndarray, seeds: np.ndarray, vals: np.ndarray,
                 sy: int, sz: int):
    """`levels` for all four components at once on flat uint8 lanes (4 per voxel, R,
    G, B, D; lane i belongs to voxel i >> 2): fewer, larger NumPy steps for the small
    boxes of an edit. `fc` = lane value + cost of its voxel (>= 16 never rises),
    `cost` per voxel; `seeds` are lane indices (duplicates allowed) holding `vals`.
    Returns the written lanes and their values."""
    offs = 4 * np.array([-1, 1, -sy, sy, -sz, sz], np.int64)
    lanes, values = _rise(fc, cost, seeds, vals, offs, 2)
    if not lanes:
        return np.zeros(0, np.int64), np.zeros(0, np.uint8)
    return np.concatenate(lanes), np.concatenate(values).astype(np.uint8)


def spread(fc: np.ndarray, cost: np.ndarray, seeds: np.ndarray, vals: np.ndarray,
           sy: int, sz: int):
    """`levels` for one component (a lamp set or taken out: light/lamp.py), all six
    directions at once per level, on flat uint8 `fc` (value + cost, >= 16 never
    rises) and `cost`, from `seeds` (flat voxel indices, duplicates allowed) at
    `vals`. Returns the written voxels and their values (each voxel once, brightest
    first)."""
    offs = np.array([-1, 1, -sy, sy, -sz, sz], np.int64)
    out, values = _rise(fc, cost, seeds, vals, offs, 0)
    if not out:
        return np.zeros(0, np.int64), np.zeros(0, np.int16)
    return np.concatenate(out), np.concatenate(values)


def _rise(fc, cost, seeds, vals, offs, shift: int):
    """The level loop of `levels_lanes` and `spread`: all six directions at once per
    level (a level's writes to one index carry the same value, so duplicates only need
    dropping from the next bucket: `owner` keeps one); index i's voxel is i >> shift.
    Returns the lists of written indices and their int16 values, level by level."""
    buckets: list = [[] for _ in range(model.MAX + 1)]
    seeds, vals = np.asarray(seeds, np.int64), np.asarray(vals)
    for v in np.unique(vals).tolist():
        if v > 1:
            buckets[v].append(seeds[vals == v])
    out, values = [], []
    owner, ramp = _scratch(fc.size)  # owner: read only where just written
    for v in range(model.MAX, 1, -1):
        if not buckets[v]:
            continue
        idx = buckets[v][0] if len(buckets[v]) == 1 else np.concatenate(buckets[v])
        n = (idx[:, None] + offs).ravel()
        n = n[fc[n] < v]  # stale seeds (raised since) find nothing here
        if not n.size:
            continue
        i = ramp[:n.size] if n.size <= ramp.size else np.arange(n.size, dtype=np.int32)
        owner[n] = i
        n = n[owner[n] == i]  # once each (the last writer of each index)
        fc[n] = v
        nv = v - cost[n >> shift if shift else n].astype(np.int16)
        out.append(n)
        values.append(nv)
        if (nv == v - 1).all():  # the common case: plain air
            if v > 2:
                buckets[v - 1].append(n)
            continue
        for k in np.unique(nv).tolist():
            if k > 1:
                buckets[k].append(n[nv == k])
    return out, values


assert model.OPAQUE_COST > model.MAX  # v - OPAQUE_COST < 0: such voxels never rise
