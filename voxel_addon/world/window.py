"""An edit's windows: voxel columns of the active chunks copied into per-thread
scratch buffers (the relight's blocks and light, the remesh's strips), so that an edit
allocates nothing large (a fresh 1.3 MB array costs page faults: ~0.5 ms in a big
process). Call with the world's lock held."""
from __future__ import annotations

import threading

from ..core import chunk as C

S = C.SIZE
SCRATCH = threading.local()  # per-thread window buffers (gather)
EXACT_KEPT = 4  # shapes of exact buffers kept per thread (gather)


def gather(world, x0, y0, x1, y1, attr, z0=0, z1=C.HEIGHT, exact=False, fill=True,
           writes=0, name=None):
    """Voxel columns [x0, x1) x [y0, y1) of active chunks' `attr` as one array
    (zeros where a chunk or its array is missing). Call with the world's lock held.
    The array is a view of this thread's scratch buffer for `attr`, valid until the
    next call: a fresh 1.3 MB array per edit costs page faults (~0.5 ms in a big
    process). Only layers [z0, z1) are filled; the others hold stale values.
    `exact`: a Fortran-contiguous buffer of just this shape (the mesher's input; the
    last EXACT_KEPT shapes are kept: one chunk, two side by side either way, 2x2 —
    a click on a chunk's edge remeshes two, and a new 0.3 MB buffer each time the
    shape changed cost page faults: up to 0.25 ms of such a click). `fill=False`:
    the buffer alone, its values stale (the caller fills what it reads, cross).

    Blocks to the world's top (the relight's window): the air above the chunks'
    highest non-air section is copied only where the buffer may not hold zeros
    already (~2/3 of a surface window's layers; the copy is most of a window's
    cost). `writes`: the caller writes non-zero values into the window below this
    layer only (the stroke's voxels), so the buffer stays known to be air above.
    `name`: another buffer than `attr`'s (an edit's part window: its own, so a
    lower window after a whole one zeroes the layers between only over its 11 x 11
    columns, not the whole buffer's 31 x 31)."""
    w, h = x1 - x0, y1 - y0
    if exact:
        bufs = getattr(SCRATCH, "exact", None)
        if bufs is None:
            bufs = SCRATCH.exact = {}
        out = bufs.get((attr, w, h))
        if out is None:
            if len(bufs) >= EXACT_KEPT:
                del bufs[next(iter(bufs))]   # the oldest shape
            out = bufs[(attr, w, h)] = C.empty(width=w, depth=h)
    else:
        name = name or attr
        buf = getattr(SCRATCH, name, None)
        if buf is None or buf.shape[0] < w or buf.shape[1] < h:
            n = max(w, h, 0 if buf is None else max(buf.shape[:2]))
            buf = C.empty(width=n, depth=n)
            setattr(SCRATCH, name, buf)
            setattr(SCRATCH, "air_" + name, 0)
        out = buf[:w, :h]
    if fill and attr == "blocks" and not exact and z1 == C.HEIGHT:
        top = z0
        for cx in range(x0 >> 4, ((x1 - 1) >> 4) + 1):
            for cy in range(y0 >> 4, ((y1 - 1) >> 4) + 1):
                c = world.chunks.get((cx, cy))
                if c is not None:
                    top = max(top, c.air_from(z0))
        air = getattr(SCRATCH, "air_" + name)   # buf[:, :, air:] holds zeros
        if top < air:
            buf[:, :, top:air] = 0
        copy_into(world, out, x0, y0, x0, y0, x1, y1, attr, z0, top)
        setattr(SCRATCH, "air_" + name, max(top, writes))
    elif fill:
        copy_into(world, out, x0, y0, x0, y0, x1, y1, attr, z0, z1)
    return out


def copy_into(world, out, ox, oy, x0, y0, x1, y1, attr, z0, z1):
    """out[x0 - ox:x1 - ox, y0 - oy:y1 - oy, z0:z1] = the world's `attr` there (a
    window whose column (0, 0) is world column (ox, oy)); nothing where it is empty."""
    if x1 <= x0 or y1 <= y0 or z1 <= z0:
        return
    for cx in range(x0 >> 4, ((x1 - 1) >> 4) + 1):
        for cy in range(y0 >> 4, ((y1 - 1) >> 4) + 1):
            c = world.chunks.get((cx, cy))
            ax0, ay0 = max(x0, cx * S), max(y0, cy * S)
            ax1, ay1 = min(x1, cx * S + S), min(y1, cy * S + S)
            dst = out[ax0 - ox:ax1 - ox, ay0 - oy:ay1 - oy, z0:z1]
            xs, ys = slice(ax0 - cx * S, ax1 - cx * S), slice(ay0 - cy * S, ay1 - cy * S)
            if c is None:
                dst[...] = 0
            elif attr == "light":
                c.light_into(dst, xs, ys, z0, z1)
            elif attr == "blocks":
                c.blocks_into(dst, xs, ys, z0, z1)
            else:
                a = getattr(c, attr)
                dst[...] = 0 if a is None else a[xs, ys, z0:z1]


def cross(world, gx, gy, gx1, gy1, last, remesh, za, zb):
    """The remesh window [gx, gx1) x [gy, gy1) x [za, zb) with only what meshing.patch
    reads filled (the rest stale): per changed voxel and remeshed chunk, the columns
    within 1 of the voxel's x (its rows in the chunk, the ring's columns) and of its
    y (likewise) and the layers within 1 of its z (in the chunk). The slices it
    meshes again lie within 1 of the voxel along their axis, and their faces look
    along that axis (meshing/slices.py): their cells and the cells they face lie
    inside; a slice's rows and a z slice never read the ring across them."""
    sub = gather(world, gx, gy, gx1, gy1, "blocks", exact=True, fill=False)
    for kx, ky in remesh:
        x0, y0 = kx * S, ky * S
        for x, y, z in last:
            copy_into(world, sub, gx, gy, max(x - 1, x0 - 1), y0, min(x + 2, x0 + S + 1),
                      y0 + S, "blocks", za, zb)
            copy_into(world, sub, gx, gy, x0, max(y - 1, y0 - 1), x0 + S,
                      min(y + 2, y0 + S + 1), "blocks", za, zb)
            copy_into(world, sub, gx, gy, x0, y0, x0 + S, y0 + S, "blocks",
                      max(z - 1, za), min(z + 2, zb))
    return sub
