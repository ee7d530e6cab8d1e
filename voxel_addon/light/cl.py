"""OpenCL backend of the full light solve (gpu/light.cl): the twin of full.solve_slab,
the NumPy reference.

Directional line sweeps (z, x, y, z, ...) with per-line dirty flags until two sweeps in
a row change nothing (gpu/light.cl says why that is the fixpoint); z lines only run
over the [lo, hi) range of their group of 4 columns where anything can change.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .. import opencl
from . import model

MAX_SWEEPS = 600  # safety net; values only grow, so sweeps end long before
STATS = {"sweeps": 0}
BLOCK = 8  # groups of 4 columns per work-item (gpu/light.cl BLOCK)


@lru_cache(maxsize=1)
def _table():
    """uchar4 per block id (R, G, B, cost), plus one padding id (cost 255, dark)."""
    import pyopencl as cl
    ctx, _, _ = opencl.context()
    cost, _, _, emis, _, _ = model.tables()
    t = np.zeros((len(cost) + 1, 4), np.uint8)
    t[:-1, :3] = emis
    t[:-1, 3] = cost
    t[-1, 3] = model.OPAQUE_COST
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    return cl.Buffer(ctx, ro, hostbuf=t), len(cost)


@lru_cache(maxsize=1)
def _kernels():
    import pyopencl as cl
    prg = opencl.program("light.cl")
    return tuple(cl.Kernel(prg, n) for n in ("light_start", "light_sweep_z", "light_sweep_x",
                                             "light_sweep_y", "light_pack_out"))


def reach(em: np.ndarray) -> np.ndarray:
    """Per column, 1 + the highest z an emitter's light can reach, from the top emitter
    z per column ([y, x], -1 for none): max over columns at horizontal L1 distance d
    of em + 15 - d."""
    r = np.where(em >= 0, em + model.MAX, 0).astype(np.int32)
    for _ in range(model.MAX - 1):
        n = r.copy()
        np.maximum(n[1:], r[:-1] - 1, out=n[1:])
        np.maximum(n[:-1], r[1:] - 1, out=n[:-1])
        np.maximum(n[:, 1:], r[:, :-1] - 1, out=n[:, 1:])
        np.maximum(n[:, :-1], r[:, 1:] - 1, out=n[:, :-1])
        r = n
    return r


def _local():
    """The launches' work-group size: (1, 1) on a CPU device, else the driver's choice.
    pocl compiles a kernel's work-group function per local size at its first launch,
    and left to choose it picked one from the global size: ~5 new functions per area
    shape (~1 s CPU cold). An item here is a whole line in explicit vectors, nothing
    for its work-group vectorizer: as fast, with one function per kernel."""
    return (1, 1) if opencl.on_cpu() else None


def solve_slab(blocks: np.ndarray) -> np.ndarray:
    """(W, H, Z) uint16 F-order slab -> packed light, same shape, F-order."""
    import pyopencl as cl
    ctx, q, _ = opencl.context()
    k_start, k_z, k_x, k_y, k_pack = _kernels()
    tab, pad_id = _table()
    w, h, z = blocks.shape
    groups = (w + 3) // 4
    w4 = 4 * groups
    sx = w4 + 8
    nvox = sx * (h + 2) * (z + 2)
    mf = cl.mem_flags
    bt = blocks.T  # [z, y, x], C-contiguous for an F-order slab
    if w4 != w:
        bt = np.pad(bt, ((0, 0), (0, 0), (0, w4 - w)), constant_values=pad_id)
    b = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(bt))
    cost = cl.Buffer(ctx, mf.READ_WRITE, nvox)
    cl.enqueue_fill_buffer(q, cost, np.uint8(model.OPAQUE_COST), 0, nvox)
    lanes = cl.Buffer(ctx, mf.READ_WRITE, 4 * nvox + 64)
    cl.enqueue_fill_buffer(q, lanes, np.uint8(0), 0, 4 * nvox + 64)
    info = np.empty((3, h, w4), np.int32)
    ibuf = cl.Buffer(ctx, mf.READ_WRITE, info.nbytes)
    dims = (np.int32(h), np.int32(z), np.int32(sx))
    loc = _local()
    nb = (groups + BLOCK - 1) // BLOCK
    k_start(q, (nb, h), loc, b, tab, cost, lanes, ibuf, *dims)
    cl.enqueue_copy(q, info, ibuf)
    lo = info[0]
    hi = np.minimum(np.maximum(info[1], reach(info[2])), z)
    lo = np.where(lo < hi, lo, z)  # empty columns must not widen their group's range
    lo = lo.reshape(h, groups, 4).min(axis=2)
    hi = hi.reshape(h, groups, 4).max(axis=2)
    rng = np.ascontiguousarray(np.stack([lo, hi], axis=-1).astype(np.int32))
    rbuf = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=rng)
    seg = 16
    nseg = ((groups + 3) // 4 * h * z, (h + seg - 1) // seg * groups * z,
            (z + seg - 1) // seg * groups * h)  # dx, dy, dz
    fl = [cl.Buffer(ctx, mf.READ_WRITE, n) for n in nseg]
    for f, n in zip(fl, nseg):
        cl.enqueue_fill_buffer(q, f, np.uint8(0), 0, n)
    dx, dy, dz = fl
    flag = np.zeros(1, np.int32)
    fbuf = cl.Buffer(ctx, mf.READ_WRITE, 4)
    sweeps = [(k_z, (nb, h), (rbuf,)), (k_x, (h, z), ()), (k_y, (nb, z), ())]
    quiet = 0
    for k in range(MAX_SWEEPS):
        kern, size, extra = sweeps[k % 3]
        init = (np.int32(k == 0),) if kern is k_z else ()
        cl.enqueue_fill_buffer(q, fbuf, np.int32(0), 0, 4)
        kern(q, size, loc, lanes, cost, *extra, dz, dy, dx, fbuf, *init, *dims)
        cl.enqueue_copy(q, flag, fbuf)
        quiet = 0 if flag[0] else quiet + 1
        if quiet >= 2 and k >= 2:
            break
    STATS["sweeps"] = k + 1
    out = np.empty((z, h, w4), np.uint16)
    obuf = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    k_pack(q, (h, z), loc, lanes, obuf, *dims)
    cl.enqueue_copy(q, out, obuf)
    return out[:, :, :w].T
