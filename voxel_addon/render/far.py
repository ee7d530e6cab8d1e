"""Far terrain (issue 22): the ring of far tiles beyond the chunks, out to `far`
chunks, drawn into the G-buffer after the chunks (shaders/far.vert, far.frag), so
the deferred light, fog, sky and the debug views treat it like any surface.

Tiles come as voxel_addon/far/mesh.py FarMeshes, by duck typing (`key` = (level, tx,
ty), `origin`, `spacing`, `vertices` (n, 3) uint32, `ground` and `water` indices,
`zrange`). Culling is on the CPU per tile (its box against the view), shadows are not
cast by far tiles (beyond the shadow distance they would not show), and a far pixel
is dropped where a chunk is drawn (the near mask), so the two never double up and
meet at the chunks' edge.

Depth: one buffer, its range split. The chunks' projection (the camera's, or
Blender's) is squeezed into [0, 0.5), far tiles get their own projection from a near
plane at about half the view distance out to `far` in [0.5, 1]: at 4 km a 24-bit or
32F buffer then resolves ~0.03 blocks instead of ~10 with one projection. The chunks
are always in front of the far ring (the camera is inside the chunks' square), so
comparing across the two halves is right; `scene_pos` (include/eye.glsl) reads a
depth back with the half's inverse (`far_split`, `far_inv_vp`).
"""
from __future__ import annotations

import numpy as np

from .device import State

TILE = 32              # far/grid.py TILE: cells a side
MORPH = (0.65, 0.95)   # far/grid.py MORPH: the share of a level's switch distance
DETAIL = 64            # far/grid.py DETAIL
COARSEST = 5           # far/grid.py LEVELS[-1]: does not morph
SPLIT = 0.5
_NEAR = np.diag([1.0, 1.0, 0.5, 1.0])  # clip z -> 0.5 z - 0.5 w: depth [0, 0.5]
_NEAR[2, 3] = -0.5
_FAR = np.diag([1.0, 1.0, 0.5, 1.0])   # clip z -> 0.5 z + 0.5 w: depth [0.5, 1]
_FAR[2, 3] = 0.5
DEPTH = State("less", True, False)


class _Tile:
    __slots__ = ("mesh", "tile", "morph", "box", "tris", "nbytes")


def coarse(m) -> np.ndarray:
    """A far mesh's triangles at half its resolution (draft frames): its surface on
    every other vertex, which with the morph at 1 (z = zc) is exactly the next
    coarser level's surface (far/mesh.py), with every skirt and water triangle."""
    nv = (TILE + 1) ** 2  # the grid's vertices come first, id = kx * (TILE + 1) + ky
    g = np.asarray(m.ground, np.uint32).reshape(-1, 3)
    on = (g < nv).all(1)
    used = np.zeros(nv, bool)
    used[g[on].ravel()] = True
    u = used.reshape(TILE + 1, TILE + 1)
    ok = np.ones((TILE // 2, TILE // 2), bool)
    for i in range(3):
        for j in range(3):
            ok &= u[i:i + TILE - 1:2, j:j + TILE - 1:2]
    zc = (np.asarray(m.vertices[:nv, 2], np.int64) & 8191).reshape(TILE + 1, TILE + 1)
    vid = np.arange(nv, dtype=np.uint32).reshape(TILE + 1, TILE + 1)
    s = np.s_
    a, b, c, d = (vid[s[0:-1:2, 0:-1:2]], vid[s[2::2, 0:-1:2]], vid[s[2::2, 2::2]],
                  vid[s[0:-1:2, 2::2]])
    za, zb, zcc, zd = (zc[s[0:-1:2, 0:-1:2]], zc[s[2::2, 0:-1:2]], zc[s[2::2, 2::2]],
                       zc[s[0:-1:2, 2::2]])
    flip = (np.abs(zb - zd) < np.abs(za - zcc))[ok]  # as far/mesh.py splits a cell
    a, b, c, d = a[ok], b[ok], c[ok], d[ok]
    t1 = np.where(flip[:, None], np.stack([a, b, d], 1), np.stack([a, b, c], 1))
    t2 = np.where(flip[:, None], np.stack([b, c, d], 1), np.stack([a, c, d], 1))
    # water: the quads of every other corner (its surface is flat)
    w = np.unique(np.asarray(m.water, np.uint32))
    wq = np.zeros(0, np.uint32)
    if len(w):
        w0 = np.asarray(m.vertices[w, 0], np.int64)
        at = np.full((TILE + 1, TILE + 1), -1, np.int64)
        at[w0 & 63, (w0 >> 6) & 63] = w
        a, b, c, d = (at[s[0:-1:2, 0:-1:2]], at[s[2::2, 0:-1:2]], at[s[2::2, 2::2]],
                      at[s[0:-1:2, 2::2]])
        k = (a >= 0) & (b >= 0) & (c >= 0) & (d >= 0)
        a, b, c, d = a[k], b[k], c[k], d[k]
        wq = np.stack([a, b, c, a, c, d], 1).ravel().astype(np.uint32)
    return np.concatenate([np.concatenate([t1, t2], 1).ravel(), g[~on].ravel(),
                           wq]).astype(np.uint32)


class FarRing:
    def __init__(self, dev):
        self.dev = dev
        self.tiles: dict = {}
        self.prog = None
        self._mask = None            # near mask texture
        self._box = (0.0, 0.0, 0.0, 0.0)
        self._near_keys = None       # the chunk keys the mask was made for
        self._boxes = np.zeros((0, 6))
        self._order: list = []

    # ------------------------------------------------------------------ data
    def update(self, meshes) -> None:
        """Show or replace far tiles (FarMesh-like)."""
        for m in meshes:
            old = self.tiles.pop(tuple(m.key), None)
            if old is not None:
                self.dev.release(old.mesh)
            idx = np.concatenate([m.ground, m.water]).astype(np.uint32)
            if not len(idx):
                continue
            t = _Tile()
            low = coarse(m)
            t.mesh = self.dev.trimesh(m.vertices, idx, low)
            level, s = int(m.key[0]), float(m.spacing)
            t.tile = (float(m.origin[0]), float(m.origin[1]), s, 0.0)
            if level >= COARSEST:  # k = 0 everywhere
                t.morph = (0.0, 0.0, 0.0, 0.0)
            else:  # far/grid.py morph(): t = (d / D - M0) / (M1 - M0), D = DETAIL * 2s
                D = DETAIL * 2 * s
                t.morph = (1.0 / (D * (MORPH[1] - MORPH[0])), MORPH[0] / (MORPH[1] - MORPH[0]),
                           0.0, 0.0)
            n = TILE * s
            ox, oy = m.origin[0] + 0.5, m.origin[1] + 0.5
            # (down to the seam wall under the chunks, far.vert: z = -16)
            t.box = (ox, oy, min(float(m.zrange[0]) - 1.0, -16.0), ox + n, oy + n,
                     float(m.zrange[1]) + 1.0)
            t.tris = (len(idx) // 3, len(low) // 3)
            t.nbytes = int(m.vertices.nbytes + idx.nbytes + low.nbytes)
            self.tiles[tuple(m.key)] = t
        self._boxes = None

    def remove(self, keys) -> None:
        for k in keys:
            t = self.tiles.pop(tuple(k), None)
            if t is not None:
                self.dev.release(t.mesh)
        self._boxes = None

    def clear(self) -> None:
        self.remove(list(self.tiles))

    @property
    def triangles(self) -> int:
        return sum(t.tris[0] for t in self.tiles.values())

    @property
    def nbytes(self) -> int:
        return sum(t.nbytes for t in self.tiles.values())

    def set_near(self, keys) -> None:
        """The chunks drawn as chunks: far pixels over them are dropped."""
        keys = frozenset(keys)
        if keys == self._near_keys:
            return
        self._near_keys = keys
        self.dev.release(self._mask)
        if not keys:
            self._mask, self._box = self.dev.texture((1, 1), "r8", data=np.zeros((1, 1), np.uint8)), \
                (0.0, 0.0, 0.0, 0.0)
            return
        k = np.array(sorted(keys), np.int64)
        x0, y0 = k.min(0)
        w, h = k.max(0) - (x0, y0) + 1
        a = np.zeros((h, w), np.uint8)
        a[k[:, 1] - y0, k[:, 0] - x0] = 255
        self._mask = self.dev.texture((int(w), int(h)), "r8", data=a)
        self._box = (float(x0), float(y0), float(w), float(h))

    # ------------------------------------------------------------------ frame
    def view(self, camera, vp: np.ndarray, near_edge: float, reach: float):
        """(near vp, its inverse, far vp, its inverse), all with the depth range
        split, for a perspective camera whose chunks' projection is vp; near_edge:
        the horizontal distance from the camera to the chunks' edge, reach: how far
        the far ring goes (blocks)."""
        n = max(1.0, 0.5 * near_edge)
        f = max(reach * 1.5 + 512.0, n * 2)
        A, B = (f + n) / (n - f), 2 * f * n / (n - f)
        fvp = vp.copy()
        fvp[2] = -A * vp[3]  # vp's w row is minus the view depth
        fvp[2, 3] += B
        nv, fv = _NEAR @ vp, _FAR @ fvp
        return nv, np.linalg.inv(nv), fv, np.linalg.inv(fv), f

    def visible(self, fvp: np.ndarray, eye, reach: float) -> list:
        """Tiles whose box is in the view (fvp: the far projection) within reach."""
        if self._boxes is None:
            self._order = list(self.tiles.values())
            self._boxes = np.array([t.box for t in self._order], np.float64).reshape(-1, 6)
        b = self._boxes
        if not len(b):
            return []
        ix = np.array([[0, 1, 2], [3, 1, 2], [0, 4, 2], [3, 4, 2],
                       [0, 1, 5], [3, 1, 5], [0, 4, 5], [3, 4, 5]])
        c = b[:, ix]                                     # (T, 8, 3)
        clip = c @ fvp[:, :3].T + fvp[:, 3]              # (T, 8, 4)
        x, y, z, w = clip[..., 0], clip[..., 1], clip[..., 2], clip[..., 3]
        out = ((x > w).all(1) | (x < -w).all(1) | (y > w).all(1) | (y < -w).all(1)
               | (z > w).all(1) | (w <= 0).all(1))
        dx = np.maximum(np.maximum(b[:, 0] - eye[0], 0), eye[0] - b[:, 3])
        dy = np.maximum(np.maximum(b[:, 1] - eye[1], 0), eye[1] - b[:, 4])
        out |= np.hypot(dx, dy) > reach
        return [self._order[i] for i in np.flatnonzero(~out)]

    def draw(self, target, tiles, fvp, stats=None, draft: bool = False,
             samples: int = 1) -> None:
        """The tiles into the G-buffer target (after the chunks: depth tested, kept);
        draft: at half their resolution (coarse()); samples: the target's (MSAA: the
        chunks' edge is tested per sample)."""
        if not tiles:
            return
        dev = self.dev
        if self.prog is None or self.prog[0] != samples:
            self.prog = (samples, dev.program("far.vert", "far.frag", {"SAMPLES": samples}))
        if self._mask is None:
            self.set_near(())
        with dev.begin(target, DEPTH, False):
            dev.use(self.prog[1], {"near_mask": self._mask},
                    {"far_vp": fvp, "near_box": self._box})
            part = int(draft)
            for t in tiles:
                dev.push({"tile": t.tile, "morph": (0.0, -1.0, 0.0, 0.0) if draft else t.morph})
                dev.draw_tris(t.mesh, part)
        if stats is not None:
            tris = sum(t.tris[part] for t in tiles)
            stats.add(tris, len(tiles), False)
            stats["far_triangles"] = tris
            stats["far_tiles"] = len(tiles)

    def release(self) -> None:
        self.clear()
        self.dev.release(self._mask)
        self._mask, self._near_keys = None, None


def near_edge(camera, area) -> float:
    """Horizontal distance from the camera to the nearest edge of the chunks' box
    (area: cx0, cy0, cx1, cy1), 0 outside it."""
    if area is None:
        return 0.0
    x0, y0, x1, y1 = (16.0 * v for v in area)
    return max(0.0, min(camera.x - x0, x1 - camera.x, camera.y - y0, y1 - camera.y))
