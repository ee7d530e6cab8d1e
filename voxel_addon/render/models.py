"""Minecraft model quads (issue 30 d) on the device: the stack's sprites as one more
texture array (blocktex.py's layout: 16x16 and its mip chain side by side, rows
bottom first) and per chunk one triangle mesh per layer (solid, cutout, translucent),
drawn by block.vert/frag with MODEL into the passes "m_opaque", "m_cutout" and
"m_blend" beside the greedy ones. The quads come by duck typing (mcres.mesh.Mesh:
positions, uvs, normals, sprite, tint, layer); this module never reads a stack.

Vertex (uvec4): x, y in 1/1024 and z in 1/8192 of a block from the chunk's corner
minus 16 (an overlay 1/512 off its base stays apart), the sprite (10 bits), uv (11
bits each, v up as the texture rows), the normal (octahedral, 5 bits a side) and the
tint (sRGB, 8 bits a channel)."""
from __future__ import annotations

import numpy as np

NAMES = ("m_opaque", "m_cutout", "m_blend")   # per mcres layer (solid, cutout, translucent)
MAX_SPRITES = 1024


def sprite_array(images) -> np.ndarray:
    """(n, 16, 32, 4) uint8 layers of (h, w, 4) RGBA sprites (top row first; larger
    ones box-filtered to 16, smaller ones repeated)."""
    from .. import textures
    n = max(len(images), 1)
    base = np.zeros((n, 16, 16, 4), np.uint8)
    for i, im in enumerate(images):
        a = np.asarray(im, np.uint8)
        h, w = a.shape[:2]
        if h >= 16 and w >= 16 and h % 16 == 0 and w % 16 == 0:
            a = a.reshape(16, h // 16, 16, w // 16, 4).astype(np.float32).mean((1, 3))
        else:
            a = a[np.arange(16) * h // 16][:, np.arange(16) * w // 16]
        base[i] = np.rint(a)[::-1]          # rows bottom first, as the device takes them
    atlas = np.zeros((n, 16, 32, 4), np.uint8)
    for lvl, a in enumerate(textures.mipmaps(base)):
        s, x = 16 >> lvl, 32 - (32 >> lvl)
        atlas[:, :s, x:x + s] = a
    return atlas


def _oct(n: np.ndarray) -> np.ndarray:
    """Octahedral encoding of unit normals, 5 bits a side (0, 15, 30: -1, 0, 1)."""
    n = n / np.maximum(np.abs(n).sum(1, keepdims=True), 1e-9)
    e = n[:, :2].copy()
    low = n[:, 2] < 0
    e[low] = (1 - np.abs(n[low][:, [1, 0]])) * np.where(n[low, :2] >= 0, 1, -1)
    q = np.clip(np.rint((e * 0.5 + 0.5) * 30), 0, 30).astype(np.uint32)
    return q[:, 0] | q[:, 1] << 5


def words(m, keep: np.ndarray, corner) -> tuple[np.ndarray, np.ndarray]:
    """(vertices (4k, 4) uint32, indices (6k,) uint32) of the quads where KEEP."""
    v4 = np.repeat(keep, 4)
    p = m.positions[v4].astype(np.float64) - np.asarray(corner, np.float64) + 16.0
    if len(p) and (p.min() < 0 or p[:, :2].max() >= 64 or p[:, 2].max() >= 512):
        raise ValueError("a model quad lies outside its chunk's reach")
    q = np.rint(p * (1024, 1024, 8192)).astype(np.uint32)
    uv = m.uvs[v4].astype(np.float64)
    uv[:, 1] = 1.0 - uv[:, 1]                       # Minecraft's v runs down the sprite
    u = np.rint(np.clip(uv, 0, 1) * 2047).astype(np.uint32)
    sp = np.repeat(np.maximum(m.sprite[keep], 0), 4).astype(np.uint32)
    t = np.repeat(m.tint[keep].astype(np.uint32), 4, axis=0)
    w = np.empty((len(p), 4), np.uint32)
    w[:, 0] = np.minimum(q[:, 0], 65535) | np.minimum(q[:, 1], 65535) << 16
    w[:, 1] = q[:, 2] | sp << 22
    w[:, 2] = u[:, 0] | u[:, 1] << 11 | _oct(m.normals[v4].astype(np.float64)) << 22
    w[:, 3] = t[:, 0] | t[:, 1] << 8 | t[:, 2] << 16
    k = len(p) // 4
    idx = (np.arange(k, dtype=np.uint32)[:, None] * 4 + np.array([0, 1, 2, 0, 2, 3], np.uint32))
    return w, idx.reshape(-1)


class Models:
    """The shown chunks' model meshes and one texture of every sprite they have used
    (a sprite keeps its layer while the renderer lives; new ones make the texture
    again at the next frame: `commit`)."""

    def __init__(self, dev):
        self.dev = dev
        self.tex = None
        self.chunks: dict = {}    # (cx, cy) -> [trimesh or None per layer]
        self.tris: dict = {}      # (cx, cy) -> [triangles per layer]
        self.zs: dict = {}        # (cx, cy) -> (lowest, highest) z of its quads
        self.layer: dict = {}     # sprite id -> layer of the texture
        self.images: list = []    # per layer its RGBA (top row first)
        self._stale = False

    def update(self, items: dict) -> None:
        """{(cx, cy): the chunk's models (.mesh: mcres.mesh.Mesh in world voxels, .images:
        {sprite id: RGBA}) or None (none)}."""
        for key, cm in items.items():
            key = (int(key[0]), int(key[1]))
            self.remove([key])
            if cm is None or not cm.mesh.quads:
                continue
            self._add(key, cm.mesh, cm.images, np.ones(cm.mesh.quads, bool))

    def _add(self, key, mesh, images: dict, inside) -> None:
        remap = np.zeros(len(mesh.sprites) + 1, np.int64)   # (-1, unset: the last, 0)
        for i, sid in enumerate(mesh.sprites):
            j = self.layer.get(sid)
            if j is None:
                if len(self.images) >= MAX_SPRITES:
                    j = 0                      # (a pack past the limit: its first sprite)
                else:
                    j = self.layer[sid] = len(self.images)
                    self.images.append(images[sid])
                    self._stale = True
            remap[i] = j
        g = _Remapped(mesh, remap[mesh.sprite])
        row, tris = [], []
        for li in range(len(NAMES)):
            keep = inside & (mesh.layer == li)
            if not keep.any():
                row.append(None)
                tris.append(0)
                continue
            w, idx = words(g, keep, (key[0] * 16, key[1] * 16, 0))
            row.append(self.dev.trimesh(w, idx))
            tris.append(len(idx) // 3)
        self.chunks[key] = row
        self.tris[key] = tris
        z = mesh.positions[np.repeat(inside, 4), 2]
        self.zs[key] = (float(z.min()), float(z.max()))

    def remove(self, keys) -> None:
        for k in keys:
            row = self.chunks.pop((int(k[0]), int(k[1])), None)
            if row is not None:
                self.dev.release(*row)
                del self.tris[(int(k[0]), int(k[1]))], self.zs[(int(k[0]), int(k[1]))]

    def commit(self) -> bool:
        """Make the sprites' texture again if new ones came; returns whether it did
        (the passes that bind it are made again)."""
        if not self._stale:
            return False
        old = self.tex
        self.tex = self.dev.texture((32, 16), "rgba8", layers=max(len(self.images), 1),
                                    data=sprite_array(self.images))
        self.dev.release(old)
        self._stale = False
        return True

    def batches(self, names, mvp) -> dict:
        """{pass name: [(trimesh, -1, triangles, origin)] or None}: the chunks whose
        quads' box may be inside the clip volume of MVP."""
        from . import camera
        keys = list(self.chunks)
        if keys:
            k = np.array(keys, np.float64)
            zs = np.array([self.zs[c] for c in keys])
            lo = np.c_[k * 16, zs[:, :1]] - 0.5
            hi = np.c_[k * 16 + 16, zs[:, 1:]] + 0.5
            seen = camera.visible_boxes(mvp, camera.boxes(lo, hi))
            keys = [c for c, v in zip(keys, seen) if v]
        out = {}
        for n in names:
            if n not in NAMES:
                continue
            li = NAMES.index(n)
            out[n] = [(self.chunks[c][li], -1, self.tris[c][li], (c[0] * 16.0, c[1] * 16.0, 0.0, 0.0))
                      for c in keys if self.chunks[c][li] is not None] or None
        return out

    def clear(self) -> None:
        self.remove(list(self.chunks))
        self.dev.release(self.tex)
        self.tex, self.layer, self.images, self._stale = None, {}, [], False


class _Remapped:
    """A mesh with its sprites as layers of the texture."""

    def __init__(self, mesh, sprite):
        self.positions, self.uvs, self.normals = mesh.positions, mesh.uvs, mesh.normals
        self.tint, self.layer, self.sprite = mesh.tint, mesh.layer, sprite


def edges(cm, key) -> np.ndarray:
    """(4, 16) uint16 as rows 0-3 of walls.edges: the height of a chunk's border columns from
    its model quads that face up (a model stone floor stands on the area's wall too)."""
    out = np.zeros((4, 16), np.uint16)
    if cm is None or not cm.mesh.quads:
        return out
    m = cm.mesh
    up = m.normals[::4, 2] > 0.5
    c = m.positions.reshape(-1, 4, 3).mean(1)[up]
    x = np.floor(c[:, 0]).astype(np.int64) - 16 * key[0]
    y = np.floor(c[:, 1]).astype(np.int64) - 16 * key[1]
    top = np.ceil(c[:, 2]).astype(np.int64)
    ok = (x >= 0) & (x < 16) & (y >= 0) & (y < 16)
    x, y, top = x[ok], y[ok], top[ok]
    for row, on, at in ((0, x == 0, y), (1, x == 15, y), (2, y == 0, x), (3, y == 15, x)):
        np.maximum.at(out[row], at[on], top[on].astype(np.uint16))
    return out
