"""The shown area's outer wall where the meshes have none: chunks meshed against their
real neighbours (the live view's streamed chunks, update_chunks) have no faces on the
area's border, so from outside, or from a side view, the area was a slab open into its
caves. The deferred pass closes it (shaders/include/walls.glsl): where a camera ray
crosses the border plane below the top of the border column there, and nothing drawn
is nearer, it shades a stone wall. This keeps only the height of each border column,
taken from the chunks' own meshes (the top faces of opaque cubes), in a small texture:
a row per side of the area. (set_area(closed=True) closes the wall with real faces
instead; the two agree where both are.)"""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY
from ..meshing import faces

TOP = 5  # the +z face code (meshing/mesh.py)
_SOLID = (faces.tables() & 2) != 0  # opaque cubes: what the wall stands for
_I = np.arange(16)


def edges(mesh) -> np.ndarray:
    """(4, 16) uint16: the height (top z + 1, 0: none) of a chunk's border columns from
    its mesh's top faces: rows x = 0 and x = 15 (along y), y = 0 and y = 15 (along x)."""
    out = np.zeros((4, 16), np.uint16)
    q = getattr(mesh, "quads", None)
    if q is None or not len(q):
        return out
    q = q[(q["face"] == TOP) & _SOLID[np.minimum(q["block"], len(_SOLID) - 1)]]
    x, y, w, h = (q[k].astype(np.int32) for k in ("x", "y", "w", "h"))
    top = q["z"].astype(np.int32) + 1
    for row, on, lo, n in ((0, x == 0, y, h), (1, x + w == 16, y, h),
                           (2, y == 0, x, w), (3, y + h == 16, x, w)):
        if on.any():
            cover = (_I >= lo[on, None]) & (_I < (lo + n)[on, None])
            out[row] = np.where(cover, top[on, None], 0).max(0)
    return out


class Walls:
    """The border columns' heights on the device: (width, 4) r16, row = side (x0, x1,
    y0, y1), texel = column along it from the area's low corner."""

    def __init__(self, dev):
        self.dev = dev
        self.tex = dev.texture((16, 4), "r16", layers=1)

    def write(self, area, chunk_edges: dict) -> bool:
        """Write the heights of the area's border ((cx0, cy0, cx1, cy1); chunk_edges:
        {key: edges(mesh)}); returns whether the texture was made again (bigger: the
        passes that bind it are made again)."""
        if area is None:
            return False
        cx0, cy0, cx1, cy1 = area
        n = 16 * max(cx1 - cx0, cy1 - cy0)
        rows = np.zeros((4, max(n, self.tex.size[0])), np.uint16)
        none = np.zeros((4, 16), np.uint16)
        for i, cy in enumerate(range(cy0, cy1)):
            rows[0, 16 * i:16 * i + 16] = chunk_edges.get((cx0, cy), none)[0]
            rows[1, 16 * i:16 * i + 16] = chunk_edges.get((cx1 - 1, cy), none)[1]
        for i, cx in enumerate(range(cx0, cx1)):
            rows[2, 16 * i:16 * i + 16] = chunk_edges.get((cx, cy0), none)[2]
            rows[3, 16 * i:16 * i + 16] = chunk_edges.get((cx, cy1 - 1), none)[3]
        grown = rows.shape[1] > self.tex.size[0]
        if grown:
            self.dev.release(self.tex)
            self.tex = self.dev.texture((rows.shape[1], 4), "r16", layers=1)
        self.dev.write_layer(self.tex, 0, rows)
        return grown

    def stone_layer(self) -> int:
        return int(REGISTRY.face_texture[REGISTRY.id("stone")][0])

    def release(self) -> None:
        self.dev.release(self.tex)
