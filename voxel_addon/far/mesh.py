"""A far tile's mesh: a heightfield over its TILE x TILE cells with skirts, and its
water surfaces, in an 8-byte vertex (two uints, decoded by the far shader):

    word 0: bits 0-5 kx, 6-11 ky (vertex 0..TILE of the tile: x = origin + kx*s + 0.5),
            12-24 z in 1/8 blocks (0..511.875), 25-26 kind (0 ground, 1 water,
            2 skirt)
    word 1: bits 0-7 normal x, 8-15 normal y (int8, /127; z = sqrt(1 - x² - y²) >= 0),
            16-31 albedo RGB565. Water (its normal is up): bits 0-23 its floor's
            colour (RGB888: the near/far match needs more than 565's steps), 24-31
            the depth to that floor (1/8 blocks, to 31.875)
    word 2: bits 0-12 zc: z on the next coarser level's surface (1/8 blocks),
            13-21 the water over the vertex (its block's z + 1; 0: none): such a
            vertex stays under the chunks (far.vert) and its ground is lit as under
            that water (far.frag); water: 16-31 the water's own colour (RGB565)

No popping (geomorphing): a vertex is drawn at mix(z, zc, grid.morph(d, level)),
d its horizontal distance to the view. The next level's samples are this tile's
even ones (point samples), so zc is that level's mesh exactly: its own height at
even vertices, the mean of the two ends on a coarse edge, of the coarse cell's
chosen diagonal in a cell centre. A tile appears when its parent is split, i.e.
when the parent is nearer than DETAIL x the parent's spacing, where morph is 1: it
starts as its parent's surface and gets its own shape as the view comes nearer.

The ground vertex of sample (kx, ky) sits on the column's top face (z = height + 1),
raised under a canopy by its cover x CANOPY blocks and tinted toward leaves. Skirts:
every edge vertex has a twin below it, as deep as the height changes around it plus
a spacing, and quads hang between them, so a neighbour of another level (whose edge
is interpolated differently) never shows a crack. Water: the cells with water at any
corner get a quad at the water surface (z = water + 1, the near water's top face).
Samples without data (-1) leave holes. Quads are split along the shorter diagonal.

Water is coloured per pixel as a near water layer over its floor looks (block.frag's
water_body over the floor lit by the light under that much water), with the depth
along the view ray (far.frag, twin of `water_over`): from high up shallow water
shows its floor, seen flat the same water shows more of its own colour, as the near
water beside it does.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..core.blocks import REGISTRY
from . import grid

GROUND, WATER, SKIRT = 0, 1, 2
CANOPY = 5.0            # blocks a full canopy stands above the ground
WATER_TOP = 1.0         # the water face's height in its block: the near water's top face
# (a full block; its waves only lower it, block.vert). At 7/8 the near water by the
# chunks' edge stood above the far water beside it: seen through it, a line of water.
BYTES_PER_VERTEX = 12
T = grid.TILE


@lru_cache(maxsize=None)
def palette() -> np.ndarray:
    """(blocks, 3) float32 albedo per block id: its top face's texture, averaged as
    the near chunks' mipmaps average it from far away."""
    from .. import textures
    avg = textures.mipmaps(textures.texture_array())[-1][:, 0, 0].astype(np.float32)
    out = np.zeros((len(REGISTRY), 3), np.float32)
    for i in range(len(REGISTRY)):
        if REGISTRY.blocks[i].shape != "none":
            out[i] = avg[REGISTRY.face_texture[i, 5], :3]
    return out


def _under_water(floor: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """(n, 3) sRGB 0..255: a floor of that colour as lit under water `depth` blocks
    deep (from the water face to the floor's top face; far.frag's twin): the near
    floor there sees the sky light of the water voxel above it, 15 less the water's
    attenuation per block of water (light/), and is lit by its square (level^2.2,
    include/shade.glsl). An exp(-depth / 2) here made far shallows darker than near."""
    n = np.maximum(np.rint(np.asarray(depth, np.float64) + 1.0 - WATER_TOP), 0.0)
    level = np.maximum(15.0 - float(REGISTRY.attenuation[REGISTRY.id("water")]) * n, 0.0) / 15.0
    return ((floor / 255.0) ** 2.2 * (level ** 2.2)[:, None]) ** (1 / 2.2) * 255.0


def water_over(floor_lit: np.ndarray, own: np.ndarray, ray: np.ndarray) -> np.ndarray:
    """(n, 3) sRGB 0..255: water over its floor (`_under_water`), `ray` blocks of it
    along the view ray, as a near water layer looks over that floor (block.frag's
    water_body: its own colour the more and the floor the less the deeper, alpha
    0.3..0.95); far.frag computes the same per pixel (its twin)."""
    k = (1.0 - np.exp(-np.maximum(ray, 0.0) * 0.25))[:, None]
    f = np.array([0.5, 0.6, 0.5]) + (np.array([0.08, 0.2, 0.16]) - [0.5, 0.6, 0.5]) * k
    a = 0.3 + 0.65 * k
    lin = (floor_lit / 255.0) ** 2.2 * (1.0 - a) + (own / 255.0) ** 2.2 * f * a
    return (lin ** (1 / 2.2) * 255.0).astype(np.float32)


def _water_over(floor: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """Water `depth` blocks deep over a floor of colour `floor` seen from straight
    above (sRGB 0..255): bakes and tests."""
    own = np.broadcast_to(palette()[REGISTRY.id("water")], np.shape(floor))
    return water_over(_under_water(floor, depth), own, np.asarray(depth, np.float64))


def _rgb888(c: np.ndarray) -> np.ndarray:
    c = np.clip(np.rint(c), 0, 255).astype(np.uint32)
    return c[..., 0] | (c[..., 1] << 8) | (c[..., 2] << 16)


def _rgb565(c: np.ndarray) -> np.ndarray:
    c = np.clip(np.rint(c), 0, 255).astype(np.uint32)
    return ((c[..., 0] >> 3) << 11) | ((c[..., 1] >> 2) << 5) | (c[..., 2] >> 3)


@dataclass
class FarMesh:
    """What the renderer gets for one tile (render takes it by duck typing)."""
    key: tuple
    origin: tuple      # (x, y) of vertex (0, 0) minus 0.5, blocks
    spacing: int
    vertices: np.ndarray   # (n, 3) uint32
    ground: np.ndarray     # (m,) uint32 triangle indices: ground and skirts
    water: np.ndarray      # (w,) uint32 triangle indices: water surfaces
    zrange: tuple      # (lowest, highest) z of the mesh, blocks
    version: int = 0

    @property
    def triangles(self) -> int:
        return (len(self.ground) + len(self.water)) // 3

    @property
    def nbytes(self) -> int:
        return self.vertices.nbytes + self.ground.nbytes + self.water.nbytes


def _normals(z: np.ndarray, s: int) -> tuple[np.ndarray, np.ndarray]:
    """Normals of the (N, N) surface at the inner (T+1, T+1) vertices."""
    gx = (z[2:, 1:-1] - z[:-2, 1:-1]) / (2.0 * s)
    gy = (z[1:-1, 2:] - z[1:-1, :-2]) / (2.0 * s)
    inv = 1.0 / np.sqrt(gx * gx + gy * gy + 1.0)
    return -gx * inv, -gy * inv


def _corners(ok: np.ndarray) -> np.ndarray:
    """Cells whose 4 corners are ok."""
    return ok[:-1, :-1] & ok[1:, :-1] & ok[1:, 1:] & ok[:-1, 1:]


def _quads(m: np.ndarray, zc: np.ndarray, vid: np.ndarray) -> np.ndarray:
    """Two triangles per cell of mask m, split along the diagonal whose ends differ
    less in height (counter-clockwise seen from +z)."""
    a, b = vid[:-1, :-1], vid[1:, :-1]      # (kx, ky), (kx+1, ky)
    c, d = vid[1:, 1:], vid[:-1, 1:]        # (kx+1, ky+1), (kx, ky+1)
    flip = np.abs(zc[1:, :-1] - zc[:-1, 1:]) < np.abs(zc[:-1, :-1] - zc[1:, 1:])
    a, b, c, d, flip = a[m], b[m], c[m], d[m], flip[m]
    t1 = np.where(flip[:, None], np.stack([a, b, d], 1), np.stack([a, b, c], 1))
    t2 = np.where(flip[:, None], np.stack([b, c, d], 1), np.stack([a, c, d], 1))
    return np.concatenate([t1, t2], 1).reshape(-1).astype(np.uint32)


def _coarse(z: np.ndarray, ok: np.ndarray) -> np.ndarray:
    """zc of the (T+1, T+1) vertices: the next coarser level's surface (see above)."""
    zc = z.copy()
    zc[1::2, ::2] = (z[:-1:2, ::2] + z[2::2, ::2]) / 2     # on coarse edges along x
    zc[::2, 1::2] = (z[::2, :-1:2] + z[::2, 2::2]) / 2     # along y
    a, b = z[:-1:2, :-1:2], z[2::2, :-1:2]                 # coarse cell corners
    c, d = z[2::2, 2::2], z[:-1:2, 2::2]
    flip = np.abs(b - d) < np.abs(a - c)                   # as _quads splits
    zc[1::2, 1::2] = np.where(flip, (b + d) / 2, (a + c) / 2)
    # next to a hole the coarse surface is undefined: no morph there
    return np.where(_grow(~ok), z, zc)


def _grow(m: np.ndarray) -> np.ndarray:
    """m and its 8 neighbours."""
    n0, n1 = m.shape
    p = np.pad(m, 1)
    out = np.zeros_like(m)
    for dx in (0, 1, 2):
        for dy in (0, 1, 2):
            out |= p[dx:dx + n0, dy:dy + n1]
    return out


def build(key, a: dict, version: int = 0) -> FarMesh:
    """The mesh of tile `key` from its sample arrays (far/tiles.py)."""
    level = key[0]
    s = grid.spacing(level)
    h = a["height"].astype(np.float32)
    have = a["height"] >= 0
    cover = a["trees"].astype(np.float32) / 255.0
    zf = np.where(have, h + 1.0 + cover * CANOPY, 0.0)
    # border samples without data: copy the inner neighbour so normals stay sane
    zf[0] = np.where(have[0], zf[0], zf[1])
    zf[-1] = np.where(have[-1], zf[-1], zf[-2])
    zf[:, 0] = np.where(have[:, 0], zf[:, 0], zf[:, 1])
    zf[:, -1] = np.where(have[:, -1], zf[:, -1], zf[:, -2])
    nx, ny = _normals(zf, s)
    inner = np.s_[1:-1, 1:-1]
    z, ok = zf[inner], have[inner]
    pal = palette()
    col = pal[a["top"][inner]]
    leaves = pal[REGISTRY.id("leaves")]
    col = col + (leaves - col) * cover[inner][..., None]
    kx, ky = np.meshgrid(np.arange(T + 1, dtype=np.uint32), np.arange(T + 1, dtype=np.uint32),
                         indexing="ij")
    n1 = (np.rint(nx * 127).astype(np.int32).astype(np.uint32) & 255) \
        | ((np.rint(ny * 127).astype(np.int32).astype(np.uint32) & 255) << 8)
    w1 = n1 | (_rgb565(col) << 16)

    def word0(z8, kind, ix=kx, iy=ky):
        z8 = np.clip(np.rint(z8 * 8), 0, 8191).astype(np.uint32)
        return ix | (iy << 6) | (z8 << 12) | (np.uint32(kind) << 25)

    def word2(z8, wl):
        return np.clip(np.rint(z8 * 8), 0, 8191).astype(np.uint32) | (wl << 13)

    # water: the cells with water at a corner; a corner's water: the highest of the
    # wet cells around it
    wz = a["water"][inner].astype(np.float32)
    wet = wz >= 0
    cell = wet[:-1, :-1] | wet[1:, :-1] | wet[1:, 1:] | wet[:-1, 1:]
    level_z = np.maximum.reduce([wz[:-1, :-1], wz[1:, :-1], wz[1:, 1:], wz[:-1, 1:]])
    wzc = np.full((T + 1, T + 1), -1.0, np.float32)
    for sl in (np.s_[:-1, :-1], np.s_[1:, :-1], np.s_[1:, 1:], np.s_[:-1, 1:]):
        wzc[sl] = np.maximum(wzc[sl], np.where(cell, level_z, -1.0))
    corner = wzc >= 0
    wl = np.where(corner, wzc + 1, 0).astype(np.uint32)  # word 2's water level
    zc = _coarse(z, ok)
    verts = [np.stack([word0(z, GROUND), w1, word2(zc, wl)], -1).reshape(-1, 3)]
    vid = np.arange((T + 1) ** 2, dtype=np.uint32).reshape(T + 1, T + 1)
    tris = [_quads(_corners(ok), z, vid)]
    nv = (T + 1) ** 2

    # skirts: per edge, the edge vertices and twins hanging below them
    zn = zf.copy()
    drop = np.zeros_like(z)
    for dx in (-1, 0, 1):  # the largest height step around each vertex
        for dy in (-1, 0, 1):
            drop = np.maximum(drop, z - zn[1 + dx:T + 2 + dx, 1 + dy:T + 2 + dy])
    depth = drop + s
    for edge in (np.s_[:, 0], np.s_[-1, :], np.s_[::-1, -1], np.s_[0, ::-1]):
        top = vid[edge]
        e_ok = ok[edge]
        bottom = np.arange(nv, nv + len(top), dtype=np.uint32)
        zb = np.maximum(z[edge] - depth[edge], 0.0)
        zcb = np.maximum(zc[edge] - depth[edge], 0.0)
        verts.append(np.stack([word0(zb, SKIRT, kx[edge], ky[edge]), w1[edge],
                               word2(zcb, wl[edge])], -1))
        nv += len(top)
        m = e_ok[:-1] & e_ok[1:]
        t0, t1, b0, b1 = top[:-1][m], top[1:][m], bottom[:-1][m], bottom[1:][m]
        # outward-facing: the edge runs counter-clockwise around the tile
        tris.append(np.stack([t0, b0, b1, t0, b1, t1], 1).reshape(-1))
    ground = np.concatenate(tris).astype(np.uint32)

    # water: a quad at the surface over every wet cell
    water = np.zeros(0, np.uint32)
    if wet.any():
        wid = np.full((T + 1, T + 1), 0, np.uint32)
        wid[corner] = np.arange(nv, nv + corner.sum(), dtype=np.uint32)
        wtop = wzc[corner] + WATER_TOP
        depth = np.maximum(wtop - z[corner], 0.0)
        w1w = _rgb888(col[corner]) | (np.minimum(np.rint(depth * 8), 255).astype(np.uint32) << 24)
        w2w = word2(wtop, np.uint32(0)) | (_rgb565(pal[REGISTRY.id("water")]) << 16)
        verts.append(np.stack([word0(wtop, WATER, kx[corner], ky[corner]),
                               w1w.astype(np.uint32), w2w], -1))
        nv += int(corner.sum())
        water = _quads(cell, wzc, wid)
    v = np.concatenate([x.reshape(-1, 3) for x in verts]).astype(np.uint32)
    zs = np.r_[z[ok], zc[ok]]
    zr = (float(max(zs.min() - depth.max(), 0.0)) if zs.size else 0.0,
          float(max(zs.max() if zs.size else 0.0,
                    (wz.max() + 1.0) if wet.any() else 0.0)))
    x0, y0 = grid.origin(key)
    return FarMesh(key, (x0, y0), s, v, ground, water, zr, version)


def decode(m: FarMesh) -> dict:
    """The packed vertices of M as arrays (what the far shader reads, without the
    geomorph): positions (n, 3) float32 in blocks, normals (n, 3), albedo (n, 3)
    sRGB 0..1, kind (n,) (GROUND, WATER, SKIRT). For bakes and tests."""
    w0, w1 = m.vertices[:, 0], m.vertices[:, 1]
    kx, ky = (w0 & 63).astype(np.float32), ((w0 >> 6) & 63).astype(np.float32)
    pos = np.stack([m.origin[0] + kx * m.spacing + 0.5, m.origin[1] + ky * m.spacing + 0.5,
                    ((w0 >> 12) & 8191).astype(np.float32) / 8.0], -1).astype(np.float32)
    kind = ((w0 >> 25) & 3).astype(np.uint8)
    wet = kind == WATER
    nx = (w1 & 255).astype(np.uint8).view(np.int8).astype(np.float32) / 127.0
    ny = ((w1 >> 8) & 255).astype(np.uint8).view(np.int8).astype(np.float32) / 127.0
    nx[wet], ny[wet] = 0.0, 0.0
    nz = np.sqrt(np.clip(1.0 - nx * nx - ny * ny, 0.0, 1.0))
    rgb = _from565((w1 >> 16) & 0xFFFF).astype(np.float64)
    if wet.any():  # water seen from straight above
        ww = w1[wet].astype(np.int64)
        floor = np.stack([ww & 255, (ww >> 8) & 255, (ww >> 16) & 255], -1)
        own = _from565((m.vertices[wet, 2] >> 16) & 0xFFFF)
        depth = (ww >> 24) / 8.0
        rgb[wet] = water_over(_under_water(floor, depth), own, depth)
    return {"positions": pos, "normals": np.stack([nx, ny, nz], -1).astype(np.float32),
            "albedo": (rgb / 255.0).astype(np.float32), "kind": kind}


def _from565(c: np.ndarray) -> np.ndarray:
    """RGB565 -> (n, 3) 0..255, as the far shader expands it."""
    c = np.asarray(c, np.int64)
    return np.stack([(c >> 11) * 255 // 31, ((c >> 5) & 63) * 255 // 63, (c & 31) * 255 // 31], -1)
