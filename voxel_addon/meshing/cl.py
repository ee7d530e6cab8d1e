"""OpenCL twin of faces.rects: many tiles (chunks) per launch. `greedy` and `none` run
wholly on the device (gpu/mesh_greedy.cl: layer flags, z band, aggregation, X/# planes),
and only the compacted quad records are read back; the tiled thesis methods take the
face keys from gpu/mesh_faces.cl and aggregate them with NumPy. Output equals NumPy.
"""
from __future__ import annotations

import os
import threading
from functools import lru_cache

import numpy as np

from .. import opencl
from . import faces as Q

UMAX = 256          # columns per slice the greedy kernel keeps state for (mesh_rows.h)
ZK = 8              # z items per direction and tile (mesh_greedy.cl)
MASKS = True        # block flags as compiled-in bit masks (False: table loads; tests)
CPU_TUNED = True    # CPU-only kernel forms on a CPU device (False: portable ones; tests)
PATHS = ("tile", "slices")  # greedy kernels (gpu/mesh_greedy.cl), see `path`
PATH = None         # force one of PATHS (tests); None: VOXEL_MESH_KERNEL, else by device
START_CAP = 1 << 16  # quad records the output buffer holds at first; grows on overflow
_lock = threading.Lock()
_bufs: dict = {}
_local = threading.local()   # per-thread host scratch (_scratch)


def _options():
    """Flag tables as 64-bit masks compiled into the kernels (mesh.h FLAG_MASKS): faster
    than table loads; the table path stays for registries of more than 64 blocks.
    CPU_DEVICE: clang builtins (ctz, prefetch) and unaligned vector loads that pocl's
    CPU compiler inlines; other devices get the portable OpenCL C 1.2 forms."""
    cpu = CPU_TUNED and _on_cpu()
    return _options_for(Q.FLAGS.tobytes(), MASKS, cpu)  # per launch: cached, not re-derived


def _on_cpu() -> bool:  # a seam: the GPU-configuration test pretends a GPU here
    return opencl.on_cpu()


def path() -> str:
    """The greedy kernel: `tile` (one work item per chunk, its layers while they are in
    the cache) on a CPU device, `slices` (one per chunk, direction and slice: enough
    work items to fill a GPU) elsewhere; VOXEL_MESH_KERNEL=tile|slices overrides."""
    p = PATH or os.environ.get("VOXEL_MESH_KERNEL", "")
    if not p:
        return "tile" if _on_cpu() else "slices"
    if p not in PATHS:
        from ..core.errors import VoxelError
        raise VoxelError(f"VOXEL_MESH_KERNEL={p!r}: expected one of {', '.join(PATHS)}")
    return p


@lru_cache(maxsize=8)
def _options_for(flags: bytes, masks: bool, cpu: bool = False):
    F = np.frombuffer(flags, Q.FLAGS.dtype).astype(np.uint64)
    if len(F) > 64 or not masks:
        return ("-DCPU_DEVICE",) if cpu else ()

    def mask(bits):
        return int(sum(1 << int(i) for i in np.flatnonzero(F & np.uint64(bits))))
    return ("-DFLAG_MASKS", f"-DM_CUBE={mask(1)}UL", f"-DM_CUBE_CAP={mask(9)}UL",
            f"-DM_OPAQUE={mask(2)}UL", f"-DM_SAME={mask(4)}UL",
            f"-DM_SHAPE={mask(48)}UL") + (("-DCPU_DEVICE",) if cpu else ())


def _kernel(file, name):
    return _kernel_built(file, name, _options())


@lru_cache(maxsize=None)
def _kernel_built(file, name, options):
    import pyopencl as cl
    return cl.Kernel(opencl.program(file, options), name)


def _group(k) -> int:
    """Work group size of the per-slice kernel: 1 on a CPU (pocl runs a group's items as
    one loop: idle or divergent ones cost), else up to 64 (whole warps/wavefronts; the
    launch is padded, items past the last tile return)."""
    if _on_cpu():
        return 1
    import pyopencl as cl
    g = min(64, k.get_work_group_info(cl.kernel_work_group_info.WORK_GROUP_SIZE,
                                      opencl.context()[2]))
    return 1 << (g.bit_length() - 1)


def _up(n, k):
    return -(-n // k) * k


def _buf(name, nbytes):
    """Device buffer reused across calls, grown by doubling (allocation and transfers of
    fresh buffers would otherwise dominate small batches)."""
    import pyopencl as cl
    b = _bufs.get(name)
    if b is None or b.size < nbytes:
        ctx, _, _ = opencl.context()
        size = max(nbytes, 2 * b.size if b is not None else 0, 4096)
        b = _bufs[name] = cl.Buffer(ctx, cl.mem_flags.READ_WRITE, size)
    return b


def _flags():
    import pyopencl as cl
    if "flags" not in _bufs:
        ctx, _, _ = opencl.context()
        _bufs["flags"] = cl.Buffer(ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                                   hostbuf=Q.FLAGS)
    return _bufs["flags"]


def _scratch(n, width):
    """(n, width) uint32 host records, a view of this thread's buffer (valid until its
    next call): a fresh MB-sized array per batch costs page faults, ~1 ms per 8x8 batch."""
    buf = getattr(_local, "rec", None)
    if buf is None or buf.size < n * width:
        buf = _local.rec = np.empty(max(n * width, 2 * (0 if buf is None else buf.size)), np.uint32)
    return buf[:n * width].reshape(n, width)


def _vtab(vtab):
    """Device copy of the vertex tables (vertex.vtab), one per distinct table."""
    import pyopencl as cl
    key = ("vt", vtab.tobytes())
    if key not in _bufs:
        ctx, _, _ = opencl.context()
        _bufs[key] = cl.Buffer(ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.COPY_HOST_PTR,
                               hostbuf=vtab)
    return _bufs[key]


def rects(P, tile, nxy, method, z0, z1, split, vtab=None):
    """Rect columns like faces.rects, or None when the window does not fit the kernel.
    With `vtab` (vertex.VTAB: its tables, blocks; 16 x 16 tiles) {"rec": (n, 12) uint32}
    instead: the kernel's records (see gpu/mesh_rows.h `put`: order key, QUAD bytes,
    tile, the rect's four packed viewport vertices, z region-local by `split`); a view of
    this thread's scratch, valid until its next call (`columns` turns it into rect
    columns, `quads_of` into QUADs)."""
    TW, TH = tile
    if TW > UMAX or max(TW, TH) >= 1 << 16:
        return None
    if method not in ("greedy", "none"):
        return _tiled(P, tile, nxy, method, z0, z1, split)
    import pyopencl as cl
    _, queue, _ = opencl.context()
    PW, PH = P.shape[:2]
    nx, ny = nxy
    nt = nx * ny
    nreg = len(Q.regions(z0, z1, split))
    merge = method == "greedy"
    tiled = merge and path() == "tile"
    rb = 48 if vtab is not None else 32      # bytes per record (gpu/mesh_rows.h `put`)
    if vtab is not None and (TW, TH) != (16, 16):
        raise ValueError("packed vertices need 16 x 16 tiles")
    ni = 2 * (TW + TH) + 2 * ZK
    i32 = np.int32
    ctx = opencl.context()[0]
    host = np.asfortranarray(P, np.uint16).ravel(order="K")
    with _lock:
        # the kernels read the caller's array in place (a CPU device: no copy; the
        # blocking reads below end every use of it before this returns)
        bp = cl.Buffer(ctx, cl.mem_flags.READ_ONLY | cl.mem_flags.USE_HOST_PTR, hostbuf=host)
        lay, busy, count = _buf("lay", nt * 256), _buf("busy", nt * 32), _buf("count", 4)
        flags = _flags()
        vt, nb = (_vtab(vtab[0]), vtab[1]) if vtab is not None else (flags, 0)
        _kernel("mesh_greedy.cl", "layers")(
            queue, (256,), (1,), bp, flags, i32(PW), i32(PH), i32(nx), i32(TW), i32(TH),
            i32(nt), lay, count)     # (also zeroes the count)
        if tiled:
            masks = _buf("masks", nt * TW * TH * 160)
        else:
            _kernel("mesh_greedy.cl", "band")(queue, (nt,), (1,), lay, i32(z0), i32(z1),
                                              i32(nt), busy)
        need = _bufs.get("cap", START_CAP)   # records (not the buffer's size: records
        while True:                          # of 32 and 48 bytes alternate; it doubled)
            out = _buf("out", need * rb)
            cap = out.size // rb
            if tiled:   # a tile per work item (gpu/mesh_greedy.cl `tile`)
                _kernel("mesh_greedy.cl", "tile")(
                    queue, (nt,), (1,), bp, flags, i32(PW), i32(PH), i32(nx), i32(TW),
                    i32(TH), i32(nt), i32(z0), i32(z1), i32(split), lay, masks, out, count,
                    np.uint32(cap), vt, i32(nb))
            else:
                k = _kernel("mesh_greedy.cl", "slices")
                g = _group(k)
                k(queue, (_up(nt * ni, g),), (g,), bp, flags, i32(PW),
                    i32(PH), i32(nx), i32(TW), i32(TH), i32(nt), i32(z0), i32(z1),
                    i32(split), i32(nreg), i32(merge), busy, out, count, np.uint32(cap),
                    vt, i32(nb))
            n = np.empty(1, np.uint32)
            cl.enqueue_copy(queue, n, count)
            n = int(n[0])
            if n <= cap:
                break
            need = n         # overflow: grow to the exact need and run again
            cl.enqueue_fill_buffer(queue, count, np.uint32(0), 0, 4)
        _bufs["cap"] = need
        rec = _scratch(n, rb // 4)
        if n:
            cl.enqueue_copy(queue, rec, out)
    if vtab is not None:
        return {"rec": rec}
    return columns(rec)


def columns(rec):
    """Rect columns (faces.COLS) of raw records (rects(..., vtab) or without)."""
    if rec.shape[1] == 12:      # with vertices: the QUAD bytes and the tile
        q = quads_of(rec)
        return {c: (rec[:, 7] if c == "t" else q[c]).astype(np.int32) for c in Q.COLS}
    r1, r2, r3 = rec[:, 1], rec[:, 2], rec[:, 3]
    cols = (rec[:, 0], r1 & 0xFFFF, r1 >> 16, r2 & 0xFF, (r2 >> 8) & 0xFF, r3 & 0xFFFF,
            r3 >> 16, r2 >> 16)
    return {c: v.astype(np.int32) for c, v in zip(Q.COLS, cols)}


def blocks_of(rec):
    """Block ids of records with vertices (QUAD bytes 11, 12)."""
    return (rec[:, 4] >> 24) | ((rec[:, 5] & 0xFF) << 8)


def quads_of(rec):
    """The meshing.QUAD array of records with vertices (their bytes 8..24)."""
    return np.ascontiguousarray(rec.view(np.uint8)[:, 8:8 + Q.QUAD.itemsize]).view(Q.QUAD).ravel()


def face_keys(P, za, zb):
    """faces.face_keys(faces.slab(P, za, zb)) computed on the device."""
    import pyopencl as cl
    _, queue, _ = opencl.context()
    W, H = P.shape[0] - 2, P.shape[1] - 2
    Z = zb - za
    keys = np.empty(6 * W * H * Z, np.uint16)
    with _lock:
        bp = _buf("P", P.nbytes)
        bk = _buf("keys", keys.nbytes)
        cl.enqueue_copy(queue, bp, np.asfortranarray(P, np.uint16).ravel(order="K"),
                        is_blocking=False)
        _kernel("mesh_faces.cl", "faces")(
            queue, (_up(W, 8), _up(H, 8), Z), (8, 8, 1), bp, _flags(), np.int32(W),
            np.int32(H), np.int32(za), np.int32(Z), bk)
        cl.enqueue_copy(queue, keys, bk)
    return [a.reshape((W, H, Z), order="F") for a in keys.reshape(6, -1)]


def _tiled(P, tile, nxy, method, z0, z1, split):
    return Q.mesh_pieces(P, Q.plan(P, z0, z1, split, Q.STEP[method]), tile, method,
                         lambda za, zb: face_keys(P, za, zb))
