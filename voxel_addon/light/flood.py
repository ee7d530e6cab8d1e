"""Sparse NumPy relaxation: push light outwards from seed voxels only (the NumPy full
solve and the incremental relight).

Works on a padded C-order grid [z, y, x] flattened: `f` packed uint16 light (SPEC §3
nibbles), `cost` uint8 per voxel (1 + attenuation; OPAQUE_COST for voxels that never
receive: opaque blocks, the fixed rim and two guard layers in z). A frontier of voxels
pushes `v - cost(n)` into its 6 neighbours n; neighbours that rise form the next
frontier. Values only rise and never beyond the fixpoint (each write is a path value),
and after k rounds every voxel holds at least its best path of <= k steps from a seed,
so when the frontier empties the grid is at the fixpoint of model.relax provided every
voxel whose start value can raise a neighbour was a seed. Work is proportional to the
light that actually moves (~5 % of a generated slab), not to the volume.

Components are separate passes (one nibble each), so a scatter never writes two
different nibbles of one uint16 at once.
"""
from __future__ import annotations

import numpy as np

from . import model

SHIFTS = (0, 4, 8, 12)  # R, G, B, D


def grid(shape_zyx: tuple[int, int, int]) -> tuple[tuple[int, int, int], tuple[int, int]]:
    """Padded shape for an inside of shape (z, y, x): 1 rim voxel around, plus one guard
    layer below and above in z so flat neighbour indices of rim voxels stay in range
    (x/y neighbours of the rim wrap onto rim voxels). Returns (shape, (sy, sz))."""
    z, y, x = shape_zyx
    return (z + 4, y + 2, x + 2), (x + 2, (x + 2) * (y + 2))


def flood(f: np.ndarray, cost: np.ndarray, seeds: np.ndarray, shift: int,
          sy: int, sz: int) -> None:
    """Raise nibble `shift` of flat `f` in place to the fixpoint reachable from `seeds`
    (flat voxel indices, any order, duplicates allowed)."""
    offs = np.array([-1, 1, -sy, sy, -sz, sz], np.int64)
    idx = np.asarray(seeds, np.int64)
    sh = np.uint16(shift)
    keep = ~np.uint16(15 << shift)
    owner = np.empty(f.size, np.int32)
    while idx.size:
        val = ((f[idx] >> sh) & np.uint16(15)).astype(np.int16)
        live = val > 1  # a 1 pushes 0: nothing
        if not live.all():
            idx, val = idx[live], val[live]
            if not idx.size:
                break
        n = (idx[:, None] + offs).ravel()
        cand = np.repeat(val, 6) - cost[n]
        m = cand > ((f[n] >> sh) & np.uint16(15)).astype(np.int16)
        n, cand = n[m], cand[m]
        if not n.size:
            break
        idx = _raise(f, n, cand, sh, keep, owner)  # the next frontier


def _raise(f, n, cand, sh, keep, owner):
    """Write each target's best candidate into nibble `sh` without sorting: write
    all (an arbitrary one wins among duplicates), then rewrite those that lost to a
    better one until none did (values only rise, so this ends). Returns the targets
    once each (`owner`: int32 scratch as large as f, read only where written)."""
    a, c = n, cand.astype(np.uint16)
    while a.size:
        f[a] = (f[a] & keep) | (c << sh)
        lost = ((f[a] >> sh) & np.uint16(15)) < c
        a, c = a[lost], c[lost]
    i = np.arange(n.size, dtype=np.int32)
    owner[n] = i
    return n[owner[n] == i]


def _best(n: np.ndarray, cand: np.ndarray):
    """One write per target, its best candidate: sort (target, value) keys and keep
    each target's last. Returns (targets, values 0..15)."""
    key = (n << 4) | cand.astype(np.int64)
    key.sort()
    last = np.empty(key.size, bool)
    last[-1] = True
    np.not_equal(key[1:] >> 4, key[:-1] >> 4, out=last[:-1])
    key = key[last]
    return key >> 4, key & 15


def seeds(f: np.ndarray, cost: np.ndarray, shift: int, offs, lo: int, hi: int) -> np.ndarray:
    """Flat indices in [lo, hi) whose nibble can raise a neighbour at one of the
    offsets `offs` (positive; both directions are checked) right now: a dense check,
    one Jacobi step's worth of work on that range."""
    m = max(offs)
    assert lo >= m and hi + m <= f.size
    a0, a1 = lo - m, hi + m
    v = ((f[a0:a1] >> np.uint16(shift)) & np.uint16(15)).astype(np.int16)
    c = cost[a0:a1].astype(np.int16)
    lo, hi = lo - a0, hi - a0
    out = np.zeros(hi - lo, bool)
    for o in offs:
        # i raises i+o: v[i] - c[i+o] > v[i+o]; i raises i-o likewise.
        out |= v[lo:hi] - c[lo + o:hi + o] > v[lo + o:hi + o]
        out |= v[lo:hi] - c[lo - o:hi - o] > v[lo - o:hi - o]
    return np.flatnonzero(out) + (lo + a0)


def flood_lanes(f: np.ndarray, cost: np.ndarray, seeds: np.ndarray, sy: int, sz: int,
                written: list | None = None) -> None:
    """`flood` for all four components at once on flat uint8 lanes (4 per voxel, R, G,
    B, D; lane i belongs to voxel i >> 2): fewer, larger NumPy steps for small boxes.
    `seeds` are lane indices; `written`, when given, gets the lanes each round wrote."""
    offs = 4 * np.array([-1, 1, -sy, sy, -sz, sz], np.int64)
    idx = np.asarray(seeds, np.int64)
    while idx.size:
        val = f[idx].astype(np.int16)
        live = val > 1
        if not live.all():
            idx, val = idx[live], val[live]
            if not idx.size:
                break
        n = (idx[:, None] + offs).ravel()
        cand = np.repeat(val, 6) - cost[n >> 2]
        m = cand > f[n]
        n, cand = n[m], cand[m]
        if not n.size:
            break
        idx, v = _best(n, cand)
        f[idx] = v.astype(np.uint8)
        if written is not None:
            written.append(idx)


def seeds_lanes(f: np.ndarray, cost: np.ndarray, offs, lo: int, hi: int) -> np.ndarray:
    """`seeds` for flat lanes: lane indices of voxels [lo, hi) that can raise a
    neighbour at +-offs (voxel strides) in that component."""
    m = max(offs)
    assert lo >= m and hi + m <= cost.size
    # i raises its neighbour j iff v[i] - c[j] > v[j], i.e. v[i] > w[j] = v[j] + c[j]:
    # uint8 throughout (a cost above MAX + 1 blocks like 16 does), no int16 copies;
    # some neighbour can be raised iff v[i] > the least w of the six.
    v = f.reshape(-1, 4)[lo - m:hi + m]
    w = np.minimum(cost[lo - m:hi + m], np.uint8(model.MAX + 1))[:, None] + v
    a, b = m, m + hi - lo
    low = np.minimum(w[a + offs[0]:b + offs[0]], w[a - offs[0]:b - offs[0]])
    for o in offs[1:]:  # the neighbour easiest to raise decides
        np.minimum(low, w[a + o:b + o], out=low)
        np.minimum(low, w[a - o:b - o], out=low)
    return np.flatnonzero(v[a:b] > low) + 4 * lo


assert model.OPAQUE_COST > model.MAX  # v - OPAQUE_COST < 0: such voxels never rise
