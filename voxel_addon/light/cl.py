"""OpenCL backend of the full light solve (gpu/light.cl); twin of solve.solve_slab_numpy.

Passes run until none changes anything; each pass only touches groups of 4 columns
next to a group that changed in the pass before, and only their [lo, hi) z range.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .. import opencl
from . import model

MAX_PASSES = 512  # safety net; values only grow, so passes end long before
STATS = {"passes": 0}


@lru_cache(maxsize=1)
def _tables():
    import pyopencl as cl
    ctx, _, _ = opencl.context()
    _, att, opaque, emis, _, _ = model.tables()
    e4 = np.zeros((len(emis), 4), np.uint8)
    e4[:, :3] = emis
    ro = cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR
    return tuple(cl.Buffer(ctx, ro, hostbuf=np.ascontiguousarray(a)) for a in (opaque, att, e4))


@lru_cache(maxsize=1)
def _kernels():
    import pyopencl as cl
    prg = opencl.program("light.cl")
    return tuple(cl.Kernel(prg, n) for n in ("light_start", "light_relax", "light_pack_out"))


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


def solve_slab(blocks: np.ndarray) -> np.ndarray:
    """(W, H, Z) uint16 F-order slab -> packed light, same shape, F-order."""
    import pyopencl as cl
    ctx, q, _ = opencl.context()
    k_start, k_relax, k_pack = _kernels()
    w, h, z = blocks.shape
    groups = (w + 3) // 4
    sx = 4 * groups + 8
    nvox = sx * (h + 2) * (z + 2)
    mf = cl.mem_flags
    b = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=np.ascontiguousarray(blocks.T))
    cost = cl.Buffer(ctx, mf.READ_WRITE, nvox)
    cl.enqueue_fill_buffer(q, cost, np.uint8(model.OPAQUE_COST), 0, nvox)
    lanes = cl.Buffer(ctx, mf.READ_WRITE, 4 * nvox + 64)
    cl.enqueue_fill_buffer(q, lanes, np.uint8(0), 0, 4 * nvox + 64)
    info = np.empty((h, w, 4), np.int32)
    ibuf = cl.Buffer(ctx, mf.READ_WRITE, info.nbytes)
    dims = (np.int32(w), np.int32(h), np.int32(z), np.int32(sx))
    k_start(q, (w, h), None, b, *_tables(), cost, lanes, ibuf, *dims)
    cl.enqueue_copy(q, info, ibuf)
    lo = info[..., 0]
    hi = np.minimum(np.maximum(info[..., 1], reach(info[..., 2])), z)
    lo = np.where(lo < hi, lo, z)  # empty columns must not widen their group's range
    pad = 4 * groups - w
    lo = np.pad(lo, ((0, 0), (0, pad)), constant_values=z).reshape(h, groups, 4).min(axis=2)
    hi = np.pad(hi, ((0, 0), (0, pad)), constant_values=0).reshape(h, groups, 4).max(axis=2)
    rng = np.ascontiguousarray(np.stack([lo, hi], axis=-1).astype(np.int32))
    rbuf = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=rng)
    flags = [cl.Buffer(ctx, mf.READ_WRITE, groups * h) for _ in range(2)]
    cl.enqueue_fill_buffer(q, flags[0], np.uint8(1), 0, groups * h)
    flag = np.zeros(1, np.int32)
    fbuf = cl.Buffer(ctx, mf.READ_WRITE, 4)
    STATS["passes"] = 0
    for k in range(MAX_PASSES):
        cl.enqueue_fill_buffer(q, fbuf, np.int32(0), 0, 4)
        k_relax(q, (groups, h), None, lanes, cost, rbuf, flags[k % 2], flags[1 - k % 2],
                fbuf, *dims)
        cl.enqueue_copy(q, flag, fbuf)
        STATS["passes"] += 1
        if not flag[0]:
            break
    out = np.empty((z, h, w), np.uint16)
    obuf = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    k_pack(q, (w, h), None, lanes, obuf, *dims)
    cl.enqueue_copy(q, out, obuf)
    return out.T
