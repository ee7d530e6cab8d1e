"""OpenCL twin of faces.py: face visibility (gpu/mesh_faces.cl) and greedy aggregation
(gpu/mesh_greedy.cl). Other methods aggregate the OpenCL face keys with NumPy; X/#
shape quads are cheap and always come from NumPy. Output equals the NumPy path exactly.
"""
from __future__ import annotations

import threading
from functools import lru_cache

import numpy as np

from .. import opencl
from . import faces as Q

_lock = threading.Lock()
_bufs: dict = {}


@lru_cache(maxsize=None)
def _kernel(file, name):
    import pyopencl as cl
    return cl.Kernel(opencl.program(file), name)


def _up(n, k):
    return -(-n // k) * k


def _buffers(shape):
    """Device buffers reused per window shape (W, H, Z rounded up to 64): allocation and
    pocl's per-launch-shape JIT would otherwise dominate chunk-sized calls."""
    import pyopencl as cl
    shape = (shape[0], shape[1], _up(shape[2], 64))
    if shape not in _bufs:
        ctx, _, _ = opencl.context()
        W, H, Z = shape
        n = W * H * Z
        mf = cl.mem_flags
        cap = 6 * n
        _bufs[shape] = dict(
            P=cl.Buffer(ctx, mf.READ_ONLY, (W + 2) * (H + 2) * (Z + 2) * 2),
            keys=cl.Buffer(ctx, mf.READ_WRITE, 6 * n * 2),
            seen=cl.Buffer(ctx, mf.READ_WRITE, 6 * n),
            out=cl.Buffer(ctx, mf.READ_WRITE, cap * 16),
            count=cl.Buffer(ctx, mf.READ_WRITE, 4),
            flags=cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=Q.tables()),
            cap=cap)
        if len(_bufs) > 8:
            _bufs.pop(next(iter(_bufs)))
    return _bufs[shape]


def keys_and_rects(P, greedy: bool):
    """P: padded window. Returns six (W,H,Z) key arrays (garbage when greedy: they stay on
    the device) and, if greedy, the raw rects."""
    import pyopencl as cl
    _, queue, _ = opencl.context()
    W, H, Z = (s - 2 for s in P.shape)
    with _lock:
        b = _buffers((W, H, Z))
        cl.enqueue_copy(queue, b["P"], np.asfortranarray(P, np.uint16).ravel(order="F"))
        k = _kernel("mesh_faces.cl", "faces")
        k(queue, (_up(W, 8), _up(H, 8), Z), (8, 8, 1), b["P"], b["flags"], np.int32(W), np.int32(H), np.int32(Z),
          b["keys"])
        keys = np.empty(6 * W * H * Z, np.uint16)
        rect = None
        if greedy:
            cl.enqueue_copy(queue, b["count"], np.zeros(1, np.uint32))
            g = _kernel("mesh_greedy.cl", "greedy")
            g(queue, (_up(2 * (W + H + Z), 16),), (16,), b["keys"], b["seen"], np.int32(W), np.int32(H),
              np.int32(Z), b["out"], b["count"], np.uint32(b["cap"]))
            n = np.empty(1, np.uint32)
            cl.enqueue_copy(queue, n, b["count"])
            rect = np.empty((int(n[0]), 4), np.uint32)
            if len(rect):
                cl.enqueue_copy(queue, rect, b["out"])
        else:
            cl.enqueue_copy(queue, keys, b["keys"])
    keys = [a.reshape((W, H, Z), order="F") for a in keys.reshape(6, -1)]
    return keys, rect


def quads(blocks, *, border, method, z0, z1):
    P = Q.padded(blocks, border, z0, z1)
    keys, rect = keys_and_rects(P, method == "greedy")
    if method != "greedy":
        return Q.finish(Q.aggregate_keys(keys, method, z0) + Q.shape_quads(P, z0))
    d = (rect[:, 0] & 0xFF).astype(np.int64)
    cols = (rect[:, 0] >> 8, rect[:, 1] & 0xFFFF, rect[:, 1] >> 16,
            rect[:, 2] & 0xFFFF, rect[:, 2] >> 16)
    parts = []
    for f in range(6):
        m = d == f
        q = Q.rects_to_quads(f, tuple(c[m].astype(np.int64) for c in cols), z0)
        q["block"] = rect[m, 3]
        parts.append(q)
    return Q.finish(parts + Q.shape_quads(P, z0))
