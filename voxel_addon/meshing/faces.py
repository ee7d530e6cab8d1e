"""Block window -> quad list (the Blender-independent meshing result; see README.md).

The NumPy path here is the reference; `cl.py` runs the same rules in OpenCL.
"""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY, SHAPES, RENDERS
from ..core.errors import VoxelError
from . import aggregate

QUAD = np.dtype([("x", "u2"), ("y", "u2"), ("z", "u2"), ("face", "u1"), ("w", "u2"),
                 ("h", "u2"), ("block", "u2"), ("layer", "u2")])
METHODS = tuple(aggregate.METHODS)
BORDERS = ("context", "air")
BACKENDS = ("numpy", "opencl")
X_FACES = (6, 7)
HASH_FACES = (8, 9, 10, 11)


def tables(reg=REGISTRY):
    """Per-id uint8 flags the visibility rule needs (also uploaded to OpenCL).
    bit 0: cube; 1: opaque cube (hides the face of anything toward it); 2: hidden
    toward the same block (blend cubes, and # caps); 3: # block with top/bottom caps."""
    shape = reg.shape
    cube = shape == SHAPES.index("cube")
    opaque = cube & (reg.render == RENDERS.index("opaque"))
    blend = cube & (reg.render == RENDERS.index("blend"))
    cap = np.array([b.shape == "hash" and ("top" in b.textures or "all" in b.textures)
                    for b in reg.blocks], bool)
    return (cube * 1 | opaque * 2 | (blend | cap) * 4 | cap * 8).astype(np.uint8)


def check(blocks, border, method, backend, z0, z1):
    if method not in aggregate.METHODS:
        raise VoxelError(f"unknown meshing method {method!r} (known: {', '.join(METHODS)})")
    if border not in BORDERS:
        raise VoxelError(f"unknown border {border!r} (known: {', '.join(BORDERS)})")
    if backend not in BACKENDS:
        raise VoxelError(f"unknown meshing backend {backend!r} (known: {', '.join(BACKENDS)})")
    if blocks.ndim != 3 or blocks.shape[2] != 256:
        raise VoxelError(f"block window must be (W, H, 256), got {blocks.shape}")
    if border == "context" and (blocks.shape[0] < 3 or blocks.shape[1] < 3):
        raise VoxelError("a window with context needs a one-voxel ring: at least (3, 3, 256)")
    if not 0 <= z0 < z1 <= 256:
        raise VoxelError(f"z range {z0}..{z1} is not inside 0..256")


def padded(blocks, border, z0, z1):
    """(W+2, H+2, Z+2) window of ids around the meshed voxels; air outside the world."""
    b = np.asarray(blocks)
    if border == "air":
        W, H = b.shape[0], b.shape[1]
        P = np.zeros((W + 2, H + 2, z1 - z0 + 2), np.uint16, order="F")
        P[1:-1, 1:-1, 1:-1] = b[:, :, z0:z1]
        if z0 > 0:
            P[1:-1, 1:-1, 0] = b[:, :, z0 - 1]
        if z1 < 256:
            P[1:-1, 1:-1, -1] = b[:, :, z1]
        return P
    P = np.zeros((b.shape[0], b.shape[1], z1 - z0 + 2), np.uint16, order="F")
    P[:, :, 1:-1] = b[:, :, z0:z1]
    if z0 > 0:
        P[:, :, 0] = b[:, :, z0 - 1]
    if z1 < 256:
        P[:, :, -1] = b[:, :, z1]
    return P


def face_keys(P, flags=None):
    """Six (W, H, Z) uint16 arrays: block id where that cube face is emitted, else 0."""
    flags = tables() if flags is None else flags
    A = P[1:-1, 1:-1, 1:-1]
    fa = flags[A]
    out = []
    for d in range(6):
        a, sign = divmod(d, 2)
        sl = [slice(1, -1)] * 3
        sl[a] = slice(2, None) if sign else slice(0, -2)
        B = P[tuple(sl)]
        fb = flags[B]
        hide = (fb & 2).astype(bool) | ((fa & 4).astype(bool) & (A == B))
        want = (fa & (9 if a == 2 else 1)).astype(bool)
        out.append(np.where(want & ~hide, A, 0).astype(np.uint16))
    return out


# For each face axis: how the (W, H, Z) key array is viewed as (slice, row, col) and
# which quad field each of (s, v, u) is; w/h name the rect extent along t1/t2.
_VIEW = {0: ((0, 1, 2), ("x", "y", "z"), ("h", "w")),
         1: ((1, 0, 2), ("y", "x", "z"), ("h", "w")),
         2: ((2, 1, 0), ("z", "y", "x"), ("w", "h"))}


def rects_to_quads(d, rect, z0):
    s, v, u, rh, rw = rect
    perm, names, ext = _VIEW[d // 2]
    q = np.zeros(len(s), QUAD)
    for name, val in zip(names, (s, v, u)):
        q[name] = val
    q["z"] += z0
    q["w"], q["h"] = (rh, rw) if ext == ("h", "w") else (rw, rh)
    q["face"] = d
    return q


def aggregate_keys(keys, method, z0):
    fn = aggregate.METHODS[method]
    parts = []
    for d, K in enumerate(keys):
        perm = _VIEW[d // 2][0]
        rect = fn(np.ascontiguousarray(K.transpose(perm)))
        q = rects_to_quads(d, rect, z0)
        # block id is the key at the rect's first cell
        q["block"] = K[q["x"], q["y"], q["z"] - z0]
        parts.append(q)
    return parts


def shape_quads(P, z0):
    A = P[1:-1, 1:-1, 1:-1]
    parts = []
    for shape, faces in (("x", X_FACES), ("hash", HASH_FACES)):
        x, y, z = np.nonzero(REGISTRY.shape[A] == SHAPES.index(shape))
        for f in faces:
            q = np.zeros(len(x), QUAD)
            q["x"], q["y"], q["z"], q["face"] = x, y, z + z0, f
            q["w"] = q["h"] = 1
            q["block"] = A[x, y, z]
            parts.append(q)
    return parts


def finish(parts):
    q = np.concatenate(parts) if parts else np.zeros(0, QUAD)
    side = np.where(q["face"] < 6, q["face"], np.where(q["face"] >= 8, q["face"] - 8, 0))
    q["layer"] = REGISTRY.face_texture[q["block"], side]
    return q[np.lexsort((q["x"], q["y"], q["z"], q["face"]))]


def quads(blocks, *, border="context", method="greedy", backend="numpy", z0=0, z1=256,
          split=0):
    """The quad list of a block window (README.md): dtype QUAD, sorted by (face, z, y, x)."""
    blocks = np.asarray(blocks)
    check(blocks, border, method, backend, z0, z1)
    if split:  # render regions: mesh each z band alone so nothing merges across
        cuts = [z0] + list(range((z0 // split + 1) * split, z1, split)) + [z1]
        q = np.concatenate([quads(blocks, border=border, method=method, backend=backend,
                                  z0=a, z1=b) for a, b in zip(cuts, cuts[1:])])
        return q[np.lexsort((q["x"], q["y"], q["z"], q["face"]))]
    band = _band(blocks, border, z0, z1)
    if band is None:
        return np.zeros(0, QUAD)
    z0, z1 = band
    if backend == "opencl":
        from . import cl
        return cl.quads(blocks, border=border, method=method, z0=z0, z1=z1)
    P = padded(blocks, border, z0, z1)
    return finish(aggregate_keys(face_keys(P), method, z0) + shape_quads(P, z0))



def _band(blocks, border, z0, z1):
    """Shrink [z0, z1) to the layers that can have faces (terrain is mostly solid rock
    below and air above). z0 only moves by multiples of the 8×8 tile so the tiled
    methods give the same result as on the full range. None: nothing to mesh."""
    mn = blocks.min(axis=(0, 1))
    mx = blocks.max(axis=(0, 1))
    solid = (mn == mx) & ((tables()[mn] & 2) != 0)
    if border == "air":
        solid[:] = False
    below = np.concatenate([[False], solid[:-1]])
    above = np.concatenate([solid[1:], [False]])
    busy = (mx != 0) & ~(solid & below & above)
    z = np.nonzero(busy[z0:z1])[0]
    if not len(z):
        return None
    lo = z0 + z[0] // aggregate.TILE * aggregate.TILE
    return lo, z0 + z[-1] + 1
