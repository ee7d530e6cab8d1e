"""The shown area's outer wall where the meshes have none: chunks meshed against their
real neighbours (the live view's streamed chunks, update_chunks) have no faces on the
area's border, so from outside, or from a side view, the area was a slab open into its
caves. The deferred pass closes it (shaders/include/walls.glsl): where a camera ray
crosses the border plane below the top of the border column there, and nothing drawn
is nearer, it shades a stone wall. This keeps only the height of each border column,
taken from the chunks' own meshes (the top faces of opaque cubes), in a small texture:
a row per side of the area, and the texture layers the wall shows there: the top
block's side for one block (grass' green edge), its filler for 3 more (dirt under
grass and snow, else the block itself: sand, stone), stone below, as the closed wall's
real faces show the generator's surface layers. (set_area(closed=True) closes the wall with real faces
instead; the two agree where both are.)"""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY
from ..meshing import faces

TOP = 5  # the +z face code (meshing/mesh.py)
_SOLID = (faces.tables() & 2) != 0  # opaque cubes: what the wall stands for
_I = np.arange(16)
FILLER = 3  # blocks of the filler under the top block (the generator's dirt band)
_UNDER = {"grass": "dirt", "snow": "dirt"}


def _side_layers() -> tuple[np.ndarray, np.ndarray]:
    """Per block id: the texture layer of its side face, and of its filler's."""
    side = REGISTRY.face_texture[:, 0].astype(np.uint16)
    filler = side.copy()
    for top, under in _UNDER.items():
        filler[REGISTRY.id(top)] = side[REGISTRY.id(under)]
    return side, filler


_SIDE, _FILL = _side_layers()


def edges(mesh) -> np.ndarray:
    """(12, 16) uint16: rows 0-3 the height (top z + 1, 0: none) of a chunk's border
    columns from its mesh's top faces: x = 0 and x = 15 (along y), y = 0 and y = 15
    (along x); rows 4-7 the texture layer of the top block's side there, 8-11 of its
    filler's."""
    out = np.zeros((12, 16), np.uint16)
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
            h = np.where(cover, top[on, None], 0)
            out[row] = h.max(0)
            at = h.argmax(0)  # the quad that gives the column its top
            b = q["block"][on][at]
            out[4 + row] = np.where(out[row] > 0, _SIDE[b], 0)
            out[8 + row] = np.where(out[row] > 0, _FILL[b], 0)
    return out


def raise_to(e, heights) -> np.ndarray:
    """edges() `e` raised to `heights` ((4, 16), e.g. Minecraft model tops) where
    those are higher; such columns show stone's side and filler (a model's sprites
    are not block texture layers)."""
    out = e.copy()
    up = heights > e[:4]
    stone = REGISTRY.id("stone")
    out[:4][up] = heights[up]
    out[4:8][up] = _SIDE[stone]
    out[8:12][up] = _FILL[stone]
    return out


class Walls:
    """The border columns on the device: (width, 12) r16, row = side (x0, x1, y0, y1)
    for the heights, + 4 the top block's side layer, + 8 its filler's (edges), texel =
    column along it from the area's low corner."""

    def __init__(self, dev):
        self.dev = dev
        self.tex = dev.texture((16, 12), "r16", layers=1)

    def write(self, area, chunk_edges: dict) -> bool:
        """Write the heights of the area's border ((cx0, cy0, cx1, cy1); chunk_edges:
        {key: edges(mesh)}); returns whether the texture was made again (bigger: the
        passes that bind it are made again)."""
        if area is None:
            return False
        cx0, cy0, cx1, cy1 = area
        n = 16 * max(cx1 - cx0, cy1 - cy0)
        rows = np.zeros((12, max(n, self.tex.size[0])), np.uint16)
        none = np.zeros((12, 16), np.uint16)
        sides = (0, 4, 8)  # heights, top layers, filler layers
        for i, cy in enumerate(range(cy0, cy1)):
            for k in sides:
                rows[k, 16 * i:16 * i + 16] = chunk_edges.get((cx0, cy), none)[k]
                rows[k + 1, 16 * i:16 * i + 16] = chunk_edges.get((cx1 - 1, cy), none)[k + 1]
        for i, cx in enumerate(range(cx0, cx1)):
            for k in sides:
                rows[k + 2, 16 * i:16 * i + 16] = chunk_edges.get((cx, cy0), none)[k + 2]
                rows[k + 3, 16 * i:16 * i + 16] = chunk_edges.get((cx, cy1 - 1), none)[k + 3]
        grown = rows.shape[1] > self.tex.size[0]
        if grown:
            self.dev.release(self.tex)
            self.tex = self.dev.texture((rows.shape[1], 12), "r16", layers=1)
        self.dev.write_layer(self.tex, 0, rows)
        return grown

    def stone_layer(self) -> int:
        return int(REGISTRY.face_texture[REGISTRY.id("stone")][0])

    def release(self) -> None:
        self.dev.release(self.tex)
