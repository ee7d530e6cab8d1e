"""Large bakes with levels of detail (issue 30 e): the chunks within `near` of a point
baked in full (bake_world, models included), the far terrain beyond out to `far`
chunks as the live view draws it (far/: a quadtree cut of heightfield tiles, level L
sampling every 2^L blocks), one object per level: `FarPart`s of triangles with a
per-vertex albedo (the far tiles' colours) and the tiles' water apart. The near
square is exactly the far cut's hole, so the two meet without overlap.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class FarPart:
    name: str
    level: int
    positions: np.ndarray   # (n, 3) float32 world blocks
    normals: np.ndarray     # (n, 3) float32
    albedo: np.ndarray      # (n, 3) float32 sRGB 0..1
    ground: np.ndarray      # (m, 3) uint32 triangles: ground and skirts
    water: np.ndarray       # (w, 3) uint32 triangles: water surfaces

    @property
    def triangles(self) -> int:
        return len(self.ground) + len(self.water)


def near_box(x: float, y: float, near: int) -> tuple[int, int, int, int]:
    """The blocks baked in full: the view chunk and `near` chunks around it (the far
    cut's hole, far.grid.select)."""
    cx, cy = int(np.floor(x)) >> 4, int(np.floor(y)) >> 4
    return 16 * (cx - near), 16 * (cy - near), 16 * (cx + near + 1), 16 * (cy + near + 1)


def far_parts(meshes, hole=None) -> list[FarPart]:
    """Far meshes (far.mesh.FarMesh) merged into one FarPart per level; triangles over
    HOLE (x0, y0, x1, y1: the near square) dropped: a tile that straddles its edge
    keeps only what lies outside (cells are aligned to chunks up to level 4)."""
    from ..far.mesh import decode
    by: dict[int, list] = {}
    for m in meshes:
        by.setdefault(m.key[0], []).append(m)
    out = []
    for level in sorted(by):
        cols = {k: [] for k in ("positions", "normals", "albedo", "ground", "water")}
        base = 0
        for m in sorted(by[level], key=lambda m: m.key):
            d = decode(m)
            for k in ("positions", "normals", "albedo"):
                cols[k].append(d[k])
            for k in ("ground", "water"):
                t = getattr(m, k).reshape(-1, 3).astype(np.uint32)
                if hole is not None and len(t):
                    c = d["positions"][t].mean(axis=1)
                    inside = (c[:, 0] > hole[0]) & (c[:, 0] < hole[2]) & \
                        (c[:, 1] > hole[1]) & (c[:, 1] < hole[3])
                    t = t[~inside]
                cols[k].append(t + base)
            base += len(m.vertices)
        out.append(FarPart(f"far_level{level}", level,
                           *(np.concatenate(cols[k]) for k in ("positions", "normals", "albedo",
                                                             "ground", "water"))))
    return out


def bake_lod(world, x: float, y: float, near: int, far: int, *, detail: int | None = None,
             timeout: float = 600.0, **kw):
    """(Bake of the near square, [FarPart] per level beyond it to `far` chunks);
    `detail` as far.grid.DETAIL (samples per unit of distance over spacing: lower
    switches to coarser levels nearer)."""
    from . import bake_world
    from ..core.errors import VoxelError
    from ..far.builder import Builder
    if not 0 <= near < far:
        raise VoxelError(f"levels of detail need 0 <= near < far (chunks), got {near} and {far}")
    bk = bake_world(world, *near_box(x, y, near), **kw)
    with Builder.of(world) as b:
        if detail is None:
            b.set_view(x, y, far, near)
        else:
            b.set_view(x, y, far, near, detail)
        if not b.wait_ready(timeout):
            raise VoxelError(f"far terrain not built within {timeout:.0f} s")
        meshes, _ = b.drain(1e9)
    return bk, far_parts(meshes, near_box(x, y, near))
