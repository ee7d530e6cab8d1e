"""The packed viewport vertex (4 B, one uint; layout in README.md and
shaders/include/vertex.glsl) and per-chunk render data split into regions and passes."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.blocks import ANIMATIONS, REGISTRY, RENDERS
from ..core.errors import VoxelError
from .faces import area, sort_key, to_quads
from .run import check, rects
from . import cl, tint
from .mesh import CORNERS, SIDE, T1, T2, quad_indices  # noqa: F401  (index pattern: API)

# Bench (region-height trade-off, cf. table 6.5): 64 builds fastest (one meshing call per
# region) with the fewest draw ranges and no extra triangles vs 16/32; the thesis chose 64 too.
REGION_H = 64
MAX_REGION_H = 64
PASSES = ("opaque", "cutout", "cutout2", "blend")
BYTES_PER_VERTEX = 4
_ANIM = np.array([ANIMATIONS.index(b.animation) for b in REGISTRY.blocks], np.int64)
_INSET = np.array([min(b.inset, 7) for b in REGISTRY.blocks], np.int64)


def _pass_table():
    r = REGISTRY.render
    ds = np.array([b.double_sided for b in REGISTRY.blocks])
    p = np.zeros(len(r), np.uint8)
    p[r == RENDERS.index("alpha_test")] = 1
    p[(r == RENDERS.index("alpha_test")) & ds] = 2
    p[r == RENDERS.index("blend")] = 3
    return p


PASS_OF = _pass_table()


def _corner_tables():
    """Integer corner p = (x, y, z) + A*w + B*h + C per face code and corner (the same
    corners as mesh.corner_positions, without the # inset)."""
    A = np.zeros((12, 4, 3), np.int32)
    B = np.zeros((12, 4, 3), np.int32)
    C = np.rint(CORNERS).astype(np.int32)
    for f in range(6):
        t1, t2 = T1[f], T2[f]
        A[f, :, t1], B[f, :, t2] = C[f, :, t1], C[f, :, t2]
        C[f, :, t1] = C[f, :, t2] = 0
    return A, B, C


_CA, _CB, _CC = _corner_tables()
_XYZ = np.array([1, 32, 1024], np.int64)       # the position bits are a sum (no carries)
_PA, _PB, _PC = ((t @ _XYZ).astype(np.uint32) for t in (_CA, _CB, _CC))  # (12, 4) packed
_PAk, _PBk, _PCk = ([np.ascontiguousarray(t[:, k]) for k in range(4)] for t in (_PA, _PB, _PC))
_HI = np.stack([t.max(1) for t in (_CA, _CB, _CC)])         # (3, 12, 3) per-axis maxima
_BLOCK_BITS = (_ANIM << 27).astype(np.uint32)
_INSET_BITS = (_INSET << 29).astype(np.uint32)


def _vtab():
    """The tables of `_pack` and PASS_OF in one uint32 array for the OpenCL mesher
    (gpu/mesh_rows.h `put` packs each quad's vertices and order key as it emits
    it), and the block count."""
    layer = REGISTRY.face_texture[:, SIDE].astype(np.uint32)    # (blocks, 12)
    assert len(PASSES) == 4   # the kernel's order key has 2 bits for the pass
    t = np.concatenate([_PA.ravel(), _PB.ravel(), _PC.ravel(), _BLOCK_BITS, _INSET_BITS,
                        layer.ravel(), PASS_OF]).astype(np.uint32)
    return t, len(REGISTRY.blocks)


VTAB = _vtab()


def pack(q, origin=(0, 0, 0)) -> np.ndarray:
    """Quads -> (4N,) uint32 packed vertices; `origin` ((3,) or per quad (N, 3), voxel
    units) is subtracted from the quad positions so they must land in 0..16² × 0..64."""
    q = np.asarray(q)
    f = q["face"].astype(np.intp)
    base = np.stack([q["x"], q["y"], q["z"]], -1).astype(np.int64) - np.asarray(origin, np.int64)
    w, h = q["w"].astype(np.int64), q["h"].astype(np.int64)
    if len(q):
        hi = base + _HI[0][f] * w[:, None] + _HI[1][f] * h[:, None] + _HI[2][f]
        if base.min() < 0 or hi[:, :2].max() > 16 or hi[:, 2].max() > MAX_REGION_H:
            raise ValueError("quads do not fit one render region (x, y 0..16, z 0..64)")
        if q["layer"].max() > 63:
            raise ValueError("texture layer above 63 does not fit the packed vertex")
    return _pack(f, *base.T, w, h, q["block"], q["layer"])


def _pack(f, x, y, z, w, h, block, layer):
    """Packed vertices from quad columns already inside their region (no checks)."""
    u = np.uint32
    f, block = f.astype(np.intp), block.astype(np.intp)   # intp: fast table lookups
    w, h = w.astype(u), h.astype(u)
    per_quad = (x.astype(u) | (y.astype(u) << 5) | (z.astype(u) << 10) | (f.astype(u) << 17)
                | (layer.astype(u) << 21) | _BLOCK_BITS[block]
                | np.where(f >= 8, _INSET_BITS[block], u(0)))
    v = np.empty((len(f), 4), u)
    for k in range(4):   # per corner: 1D table lookups are much faster than (N, 4) ones
        v[:, k] = per_quad + _PAk[k][f] * w + _PBk[k][f] * h + _PCk[k][f]
    return v.ravel()


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
    colors: np.ndarray | None = None  # (V,) uint16 palette index per vertex (the `color`
    # block; core.colors), None when the chunk has none: the packed vertex has no bits left
    models: object = None  # Minecraft model quads drawn beside (world/models.py), or None


def warm_cache(options) -> None:
    """Build and launch the OpenCL mesher's kernels once, on one chunk, with the
    program OPTIONS (cl._options() of the process that asks: the same source and
    options then hit pocl's kernel cache there): run by opencl.helper in a process of
    its own while the asking one builds the generator's kernels (world.build.warm)."""
    opts = tuple(options)
    cl._options = lambda: opts  # this process does nothing else
    from ..core import chunk as C
    b = C.empty(width=18, depth=18)
    b[:, :, :40], b[:, :, 40] = 1, 2  # any blocks: the code built is the same
    build_chunks(b, (0, 0), backend="opencl")


def _check_region(region_h):
    if not (0 < region_h <= MAX_REGION_H and 256 % region_h == 0):
        raise VoxelError(f"region height must divide 256 and be at most {MAX_REGION_H}")


def build_chunks(blocks, origin=(0, 0), *, method="greedy", backend="numpy",
                 region_h=REGION_H, keys=None, regions=None, data=None) -> dict:
    """Viewport data of every chunk of an area in one batch: `blocks` is
    (16*nx + 2, 16*ny + 2, 256), the chunks plus a one-voxel ring of neighbours;
    `origin` = (cx, cy) of its first chunk. Returns {(cx, cy): ChunkMesh}; `keys`
    optionally limits the result to those chunks (the whole area is still meshed).
    `regions` = (r0, r1): mesh only render regions r0..r1-1 (the others come out
    empty; `splice` puts them into a full mesh). `data`: the small data of the same
    window (or None): `color` voxels of different colours are not merged."""
    blocks = np.asarray(blocks)
    W, H = blocks.shape[0] - 2, blocks.shape[1] - 2
    if blocks.ndim != 3 or blocks.shape[2] != 256 or W <= 0 or H <= 0 or W % 16 or H % 16:
        raise VoxelError(f"build_chunks wants chunks plus a one-voxel ring (16*nx + 2, "
                         f"16*ny + 2, 256), got {blocks.shape}")
    _check_region(region_h)
    backend = check(blocks, "context", method, backend, 0, 256)
    nx, ny = W // 16, H // 16
    r0, r1 = regions or (0, 256 // region_h)
    r = rects(area(blocks, "context"), (16, 16), method=method, backend=backend, split=region_h,
              z0=r0 * region_h, z1=r1 * region_h, vtab=VTAB)
    nreg, npass, nt = 256 // region_h, len(PASSES), nx * ny
    rec = r.get("rec")   # the OpenCL mesher's records, vertices packed
    if rec is not None and data is not None and (cl.blocks_of(rec) == tint.COLOR).any():
        r, rec = cl.columns(rec), None  # colour strips are cut from the rects: pack here
    if rec is not None:
        q, verts, slot = _from_records(rec, region_h, nt, nreg)
    else:
        q, verts, slot = _from_columns(tint.split(r, data, (16, 16), nx), region_h, nt, nreg)
    counts = 4 * np.bincount(slot, minlength=nt * nreg * npass).reshape(nt, nreg, npass)
    per_tile = counts.reshape(nt, -1).sum(1)
    qstart = np.concatenate([[0], np.cumsum(per_tile // 4)])
    first = (np.cumsum(counts.reshape(nt, -1), 1) - counts.reshape(nt, -1)).reshape(counts.shape)
    ranges = np.stack([first, counts], -1).astype(np.int32)
    cx0, cy0 = origin
    want = None if keys is None else {tuple(k) for k in keys}
    out = {}
    qs = qstart.tolist()
    tinted = bool(q["color"].any())
    for i in range(nt):
        key = (cx0 + i % nx, cy0 + i // nx)
        if want is not None and key not in want:
            continue
        a, b = qs[i], qs[i + 1]
        col = q["color"][a:b] if tinted else None
        out[key] = ChunkMesh(verts[4 * a:4 * b], ranges[i], region_h, q[a:b],
                             np.repeat(col, 4) if tinted and col.any() else None)
    return out


def _from_records(rec, region_h, nt, nreg):
    """(quads, vertices, (tile, region, pass) slot per quad) from the kernel's records
    (cl.rects with vtab: each holds its order key, QUAD bytes and vertices): sorted
    once as whole records, quads and vertices sliced from the sorted ones."""
    lo, hi = rec[:, 0], rec[:, 1]     # (z, y, x) and ((tile, region, pass), face)
    o1 = np.argsort(lo.astype(np.uint16), kind="stable")   # radix sorts (see _order)
    h = hi[o1]
    order = o1[np.argsort(h.astype(np.uint16) if nt * nreg * len(PASSES) * 16 <= 1 << 16
                          else h, kind="stable")]
    s = np.take(rec, order, axis=0)
    return cl.quads_of(s), np.ascontiguousarray(s[:, 8:]).ravel(), hi >> 4


def _from_columns(r, region_h, nt, nreg):
    """The same from rect columns (NumPy mesher, colour strips): vertices packed here."""
    region = r["z"] // region_h
    ps = PASS_OF[r["block"]]
    order = _order(r, region, ps, nt, nreg)
    r = {c: v[order] for c, v in r.items()}
    region, ps = region[order], ps[order]
    q = to_quads(r)
    # the mesher keeps quads inside their region: pack without the checks
    verts = _pack(r["face"], r["x"], r["y"], r["z"] - region * region_h, r["w"], r["h"],
                  r["block"], q["layer"])
    return q, verts, (r["t"] * nreg + region) * len(PASSES) + ps


def _order(r, region, ps, nt, nreg):
    """Vertex order of the rects (tile, region, pass, face, z, y, x); keys are unique.
    Two stable sorts of 16-bit keys (NumPy sorts those by radix: ~2x faster than one sort
    of the 64-bit key) where (tile, region, pass, face) fits 16 bits, else the 64-bit
    key (its stable sort is ~3x faster than quicksort on the kernels' sorted runs)."""
    npass = len(PASSES)
    if nt * nreg * npass * 16 <= 1 << 16:
        lo = ((r["z"] << 8) | (r["y"] << 4) | r["x"]).astype(np.uint16)
        hi = ((((r["t"] * nreg + region) * npass + ps) << 4) | r["face"]).astype(np.uint16)
        o1 = np.argsort(lo, kind="stable")
        return o1[np.argsort(hi[o1], kind="stable")]
    return np.argsort(sort_key(r, (region, 8), (ps, 2), xy_bits=5), kind="stable")


def splice(old: ChunkMesh, new: ChunkMesh, r0: int, r1: int) -> ChunkMesh:
    """`old` with render regions r0..r1-1 taken from `new` (built with regions=(r0, r1)):
    the same mesh as a full build (regions are meshed independently, vertices are
    ordered region by region)."""
    a = int(old.ranges[r0, 0, 0])
    b = a + int(old.ranges[r0:r1, :, 1].sum())
    n0, n1 = int(new.ranges[r0, 0, 0]), int(new.ranges[r0, 0, 0] + new.ranges[r0:r1, :, 1].sum())
    counts = old.ranges[..., 1].copy()
    counts[r0:r1] = new.ranges[r0:r1, :, 1]
    flat = counts.reshape(-1)
    first = (np.cumsum(flat) - flat).reshape(counts.shape)
    verts = np.concatenate([old.vertices[:a], new.vertices[n0:n1], old.vertices[b:]])
    quads = np.concatenate([old.quads[:a // 4], new.quads[n0 // 4:n1 // 4], old.quads[b // 4:]])
    col = quads["color"]
    return ChunkMesh(verts, np.stack([first, counts], -1).astype(np.int32), old.region_h, quads,
                     np.repeat(col, 4) if col.any() else None)


def build_chunk(blocks, method="greedy", backend="numpy", region_h=REGION_H) -> ChunkMesh:
    """Viewport data of one chunk from its (18, 18, 256) window (chunk + one-voxel ring)."""
    blocks = np.asarray(blocks)
    if blocks.shape != (18, 18, 256):
        raise VoxelError(f"build_chunk wants the chunk plus a one-voxel ring (18, 18, 256), "
                         f"got {blocks.shape}")
    _check_region(region_h)
    return build_chunks(blocks, method=method, backend=backend, region_h=region_h)[(0, 0)]
