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
    return edges_many([mesh])[0]


def edges_many(meshes) -> np.ndarray:
    """edges() of many meshes at once, (n, 12, 16): a whole view's chunks in a few NumPy
    calls (one call per chunk cost ~0.13 ms, most of set_meshes)."""
    n = len(meshes)
    out = np.zeros((n, 12, 16), np.uint16)
    qs = [getattr(m, "quads", None) for m in meshes]
    at = [i for i, q in enumerate(qs) if q is not None and len(q)]
    if not at:
        return out
    # joined as bytes (a structured concatenate checks the fields array by array)
    dt = qs[at[0]].dtype
    if all(qs[i].dtype == dt for i in at):
        q = np.concatenate([np.ascontiguousarray(qs[i]).view(np.uint8).reshape(-1)
                            for i in at]).view(dt)
    else:
        q = np.concatenate([qs[i] for i in at])
    starts = np.cumsum([0] + [len(qs[i]) for i in at])
    idx = np.flatnonzero(q["face"] == TOP)
    t = q[idx]
    x, y, w, h = (t[k].astype(np.int64) for k in ("x", "y", "w", "h"))
    keep = np.flatnonzero(_SOLID[np.minimum(t["block"], len(_SOLID) - 1)]
                          & ((x == 0) | (x + w == 16) | (y == 0) | (y + h == 16)))
    idx, x, y, w, h = idx[keep], x[keep], y[keep], w[keep], h[keep]
    chunk = np.array(at, np.int64)[np.searchsorted(starts, idx, "right") - 1]
    top = q["z"][idx].astype(np.int64) + 1
    block = q["block"][idx]
    # each quad's run of border columns, per side: (quad, row, first column, length)
    sides = [(np.flatnonzero(on), row, lo, ln) for row, on, lo, ln in (
        (0, x == 0, y, h), (1, x + w == 16, y, h), (2, y == 0, x, w), (3, y + h == 16, x, w))]
    k = np.concatenate([s[0] for s in sides])
    row = np.concatenate([np.full(len(s[0]), s[1]) for s in sides])
    lo = np.concatenate([s[2][s[0]] for s in sides])
    ln = np.concatenate([s[3][s[0]] for s in sides])
    # one entry per (quad, column) it covers
    rep = np.repeat(np.arange(len(k)), ln)
    col = lo[rep] + np.arange(len(rep)) - np.repeat(np.cumsum(ln) - ln, ln)
    k, row = k[rep], row[rep]
    cell = (chunk[k] * 4 + row) * 16 + col
    # per cell the highest top; of equal tops the quad first in the mesh (as argmax)
    order = np.lexsort((k, -top[k], cell))
    first = np.ones(len(order), bool)
    first[1:] = cell[order][1:] != cell[order][:-1]
    win = order[first]
    c, r, cc, b = chunk[k[win]], row[win], col[win], block[k[win]]
    out[c, r, cc] = top[k[win]]
    out[c, 4 + r, cc] = _SIDE[b]
    out[c, 8 + r, cc] = _FILL[b]
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
