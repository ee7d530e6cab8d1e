"""The packed viewport vertex (4 B, one uint; layout in README.md and
shaders/include/vertex.glsl) and per-chunk render data split into regions and passes."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.blocks import ANIMATIONS, REGISTRY, RENDERS
from ..core.errors import VoxelError
from .faces import quads
from .mesh import corner_positions

# Bench (region-height trade-off, cf. table 6.5): 64 builds fastest (one meshing call per
# region) with the fewest draw ranges and no extra triangles vs 16/32; the thesis chose 64 too.
REGION_H = 64
MAX_REGION_H = 64
PASSES = ("opaque", "cutout", "cutout2", "blend")
BYTES_PER_VERTEX = 4
_ANIM = np.array([ANIMATIONS.index(b.animation) for b in REGISTRY.blocks], np.uint32)
_INSET = np.array([min(b.inset, 7) for b in REGISTRY.blocks], np.uint32)


def _pass_table():
    r = REGISTRY.render
    ds = np.array([b.double_sided for b in REGISTRY.blocks])
    p = np.zeros(len(r), np.uint8)
    p[r == RENDERS.index("alpha_test")] = 1
    p[(r == RENDERS.index("alpha_test")) & ds] = 2
    p[r == RENDERS.index("blend")] = 3
    return p


PASS_OF = _pass_table()


def quad_indices(n: int) -> np.ndarray:
    """Shared index pattern for n quads of 4 vertices: (0,1,2, 0,2,3) + 4k, uint32."""
    k = 4 * np.arange(n, dtype=np.uint32)[:, None]
    return (k + np.array([0, 1, 2, 0, 2, 3], np.uint32)).ravel()


def pack(q, origin=(0, 0, 0)) -> np.ndarray:
    """Quads -> (4N,) uint32 packed vertices; `origin` (voxel units) is subtracted from the
    quad positions so they must land in 0..16 × 0..16 × 0..64."""
    q = np.asarray(q)
    p = corner_positions(q, inset=False).astype(np.int64) - np.asarray(origin, np.int64)
    if len(q) and (p.min() < 0 or p[..., :2].max() > 16 or p[..., 2].max() > MAX_REGION_H):
        raise ValueError("quads do not fit one render region (x, y 0..16, z 0..64)")
    if len(q) and q["layer"].max() > 63:
        raise ValueError("texture layer above 63 does not fit the packed vertex")
    f = q["face"].astype(np.uint32)
    b = q["block"]
    per_quad = ((f << 17) | (q["layer"].astype(np.uint32) << 21) | (_ANIM[b] << 27)
                | (np.where(f >= 8, _INSET[b], 0).astype(np.uint32) << 29))
    p = p.astype(np.uint32)
    v = p[..., 0] | (p[..., 1] << 5) | (p[..., 2] << 10) | per_quad[:, None]
    return v.ravel().astype(np.uint32)


def unpack(v) -> dict:
    """NumPy mirror of GLSL decode(): grid position, face, layer, anim, inset."""
    v = np.asarray(v, np.uint32)
    return {"x": v & 31, "y": (v >> 5) & 31, "z": (v >> 10) & 127, "face": (v >> 17) & 15,
            "layer": (v >> 21) & 63, "anim": (v >> 27) & 3, "inset": v >> 29}


@dataclass
class ChunkMesh:
    vertices: np.ndarray   # (V,) uint32, 4 per quad
    ranges: np.ndarray     # (n_regions, n_passes, 2) int32: first vertex, vertex count
    region_h: int
    quads: np.ndarray      # the QUAD list, in vertex order (debug views, counts)


def build_chunk(blocks, method="greedy", backend="numpy", region_h=REGION_H) -> ChunkMesh:
    """Viewport data of one chunk from its (18, 18, 256) window (chunk + one-voxel ring)."""
    blocks = np.asarray(blocks)
    if blocks.shape != (18, 18, 256):
        raise VoxelError(f"build_chunk wants the chunk plus a one-voxel ring (18, 18, 256), "
                         f"got {blocks.shape}")
    if not (0 < region_h <= MAX_REGION_H and 256 % region_h == 0):
        raise VoxelError(f"region height must divide 256 and be at most {MAX_REGION_H}")
    q = quads(blocks, method=method, backend=backend, split=region_h)
    region = q["z"] // region_h
    ps = PASS_OF[q["block"]]
    nreg = 256 // region_h
    order = np.lexsort((ps, region))
    q = q[order]
    region, ps = region[order], ps[order]
    verts = np.empty(4 * len(q), np.uint32)
    counts = np.zeros((nreg, len(PASSES)), np.int64)
    np.add.at(counts, (region, ps), 4)
    first = np.concatenate([[0], np.cumsum(counts.ravel())[:-1]]).reshape(counts.shape)
    for r in np.unique(region):
        m = region == r
        verts[np.repeat(m, 4)] = pack(q[m], (0, 0, int(r) * region_h))
    return ChunkMesh(verts, np.stack([first, counts], -1).astype(np.int32), region_h, q)
