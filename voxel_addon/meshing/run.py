"""Meshing on the chosen backend (opencl.pick): the NumPy reference (faces.py) or its
OpenCL twin (cl.py), which import nothing of each other's but the shared tables."""
from __future__ import annotations

import numpy as np

from .. import opencl
from ..core.errors import VoxelError
from . import cl, faces, tint
from .faces import BORDERS, METHODS, area, sort_key, to_quads


def check(blocks, border, method, backend, z0, z1) -> str:
    """Refuse bad arguments with one clear line; returns the backend to use."""
    if method not in METHODS:
        raise VoxelError(f"unknown meshing method {method!r} (known: {', '.join(METHODS)})")
    if border not in BORDERS:
        raise VoxelError(f"unknown border {border!r} (known: {', '.join(BORDERS)})")
    if blocks.ndim != 3 or blocks.shape[2] != 256:
        raise VoxelError(f"block window must be (W, H, 256), got {blocks.shape}")
    if border == "context" and (blocks.shape[0] < 3 or blocks.shape[1] < 3):
        raise VoxelError("a window with context needs a one-voxel ring: at least (3, 3, 256)")
    if not 0 <= z0 < z1 <= 256:
        raise VoxelError(f"z range {z0}..{z1} is not inside 0..256")
    return opencl.pick(backend, "meshing")


def rects(P, tile, *, method="greedy", backend="numpy", z0=0, z1=256, split=0, vtab=None):
    """Rect columns (faces.COLS -> int arrays, unordered) of every tile of area P
    ((W+2, H+2, 256) with ring); tiles are TW x TH, numbered x fastest. `vtab`: the
    OpenCL mesher may add "verts", the packed vertices (cl.rects)."""
    W, H = P.shape[0] - 2, P.shape[1] - 2
    nxy = (W // tile[0], H // tile[1])
    if backend == "opencl":
        got = cl.rects(P, tile, nxy, method, z0, z1, split, vtab)
        if got is not None:
            return got  # else a window wider than the kernel takes
    return faces.rects(P, tile, nxy, method, z0, z1, split)


def quads(blocks, *, border="context", method="greedy", backend="numpy", z0=0, z1=256,
          split=0, data=None):
    """The quad list of a block window (README.md): dtype QUAD, sorted by (face, z, y, x).
    `data`: the window's small data, so `color` voxels of different colours stay apart."""
    blocks = np.asarray(blocks)
    backend = check(blocks, border, method, backend, z0, z1)
    P = area(blocks, border)
    r = rects(P, (P.shape[0] - 2, P.shape[1] - 2), method=method, backend=backend,
              z0=z0, z1=z1, split=split)
    if data is not None:
        r = tint.split(r, area(data, border), (P.shape[0] - 2, P.shape[1] - 2), 1)
    return to_quads(r)[np.argsort(sort_key(r), kind="stable")]  # unique keys: same order
