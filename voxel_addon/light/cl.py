"""OpenCL backend of the full light solve (gpu/light.cl); twin of solve.solve_slab_numpy."""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from .. import opencl
from . import model


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


STATS = {"passes": 0}


def solve_slab(blocks: np.ndarray) -> np.ndarray:
    """(W, H, Z) uint16 F-order slab -> packed light, same shape, F-order."""
    import pyopencl as cl
    ctx, q, _ = opencl.context()
    k_start, k_relax, k_pack = _kernels()
    w, h, z = blocks.shape
    mf = cl.mem_flags
    b = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR,
                  hostbuf=np.ascontiguousarray(blocks.T))
    cost = cl.Buffer(ctx, mf.READ_WRITE, w * h * z)
    lanes = cl.Buffer(ctx, mf.READ_WRITE, 4 * (w + 2) * (h + 2) * (z + 2))
    cl.enqueue_fill_buffer(q, lanes, np.uint8(0), 0, 4 * (w + 2) * (h + 2) * (z + 2))
    flag = np.zeros(1, np.int32)
    fbuf = cl.Buffer(ctx, mf.READ_WRITE, 4)
    dims = (np.int32(w), np.int32(h), np.int32(z))
    opaque, att, emis = _tables()
    k_start(q, (w, h), None, b, opaque, att, emis, cost, lanes, *dims)
    for STATS["passes"] in range(1, model.STEPS + 1):
        cl.enqueue_fill_buffer(q, fbuf, np.int32(0), 0, 4)
        k_relax(q, (w, h), None, cost, lanes, fbuf, *dims)
        cl.enqueue_copy(q, flag, fbuf)
        if not flag[0]:
            break
    out = np.empty((z, h, w), np.uint16)
    obuf = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
    k_pack(q, (w, h), None, lanes, obuf, *dims)
    cl.enqueue_copy(q, out, obuf)
    return out.T
