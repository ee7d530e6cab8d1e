"""Block window -> quad list (the Blender-independent meshing result; see README.md).

Everything is batched: a window is cut into tiles (one tile = the whole window for
`quads`, 16×16 chunks for `vertex.build_chunks`) that are meshed apart in one go.
This is the NumPy reference; `cl.py` runs the same rules in OpenCL, `run.py` picks
one of them.
"""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY, SHAPES, RENDERS
from . import aggregate
from .mesh import SIDE

QUAD = np.dtype([("x", "u2"), ("y", "u2"), ("z", "u2"), ("face", "u1"), ("w", "u2"),
                 ("h", "u2"), ("block", "u2"), ("layer", "u2"), ("color", "u2")])
METHODS = tuple(aggregate.METHODS)
BORDERS = ("context", "air")
X_FACES = (6, 7)
HASH_FACES = (8, 9, 10, 11)
# Rect columns both backends produce: tile, tile-local x, y, z, face, w, h, block.
COLS = ("t", "x", "y", "z", "face", "w", "h", "block")


def tables(reg=REGISTRY):
    """Per-id uint8 flags the visibility rule needs (also uploaded to OpenCL).
    bit 0: cube; 1: opaque cube (hides the face of anything toward it); 2: hidden
    toward the same block (blend cubes, and # caps); 3: # block with top/bottom caps;
    4: X shape; 5: # shape."""
    shape = reg.shape
    cube = shape == SHAPES.index("cube")
    opaque = cube & (reg.render == RENDERS.index("opaque"))
    blend = cube & (reg.render == RENDERS.index("blend"))
    cap = np.array([b.shape == "hash" and ("top" in b.textures or "all" in b.textures)
                    for b in reg.blocks], bool)
    xs = shape == SHAPES.index("x")
    hs = shape == SHAPES.index("hash")
    return (cube * 1 | opaque * 2 | (blend | cap) * 4 | cap * 8 | xs * 16 | hs * 32).astype(np.uint8)


FLAGS = tables()
_OPAQUE = (FLAGS & 2) != 0
# Layer granularity of the pieces meshed: the tiled methods need whole 8×8 tiles.
STEP = {m: 1 if m in ("none", "greedy") else aggregate.TILE for m in METHODS}


def area(blocks, border):
    """(W+2, H+2, 256) uint16 Fortran array: the meshed window plus its one-voxel ring."""
    b = np.asarray(blocks)
    if border == "air":
        P = np.zeros((b.shape[0] + 2, b.shape[1] + 2, 256), np.uint16, order="F")
        P[1:-1, 1:-1] = b
        return P
    return np.asfortranarray(b, np.uint16)


def slab(P, za, zb):
    """(W+2, H+2, zb-za+2): layers za-1 .. zb of P, air outside the world."""
    S = np.zeros((P.shape[0], P.shape[1], zb - za + 2), np.uint16, order="F")
    lo, hi = max(za - 1, 0), min(zb + 1, 256)
    S[:, :, lo - (za - 1):hi - (za - 1)] = P[:, :, lo:hi]
    return S


def face_keys(S, flags=FLAGS):
    """Six (W, H, Z) uint16 arrays from a slab: block id where that cube face is emitted, else 0."""
    A = S[1:-1, 1:-1, 1:-1]
    fa = flags[A]
    same = (fa & 4).astype(bool)
    out = []
    for d in range(6):
        a, sign = divmod(d, 2)
        sl = [slice(1, -1)] * 3
        sl[a] = slice(2, None) if sign else slice(0, -2)
        B = S[tuple(sl)]
        hide = (flags[B] & 2).astype(bool) | (same & (A == B))
        want = (fa & (9 if a == 2 else 1)).astype(bool)
        out.append(np.where(want & ~hide, A, 0).astype(np.uint16))
    return out


def busy_layers(P, z0, z1):
    """(256,) bool: layer z of the area may have faces — some meshed cell is not air, and
    it is not sealed (it and both neighbour layers, ring included, all opaque cubes)."""
    opq = _OPAQUE[P].all(axis=(0, 1))
    busy = P[1:-1, 1:-1].any(axis=(0, 1))
    busy[1:-1] &= ~(opq[:-2] & opq[1:-1] & opq[2:])
    busy[:z0] = False
    busy[z1:] = False
    return busy


def regions(z0, z1, split):
    """Render regions [a, b) of [z0, z1): cut at multiples of `split` (0: one region)."""
    if not split:
        return [(z0, z1)]
    cuts = [z0] + list(range((z0 // split + 1) * split, z1, split)) + [z1]
    return list(zip(cuts, cuts[1:]))


def plan(P, z0, z1, split, step=aggregate.TILE):
    """Disjoint (za, zb) pieces to mesh: the runs of `step`-layer blocks (counted from
    each region start, so the tiled methods keep their 8×8 tile grid) that hold a busy
    layer. Skipped layers have no faces, so cutting there changes nothing."""
    busy = busy_layers(P, z0, z1)
    out = []
    for a, e in regions(z0, z1, split):
        piece = None
        for za in range(a, e, step):
            zb = min(za + step, e)
            if busy[za:zb].any():
                if piece and piece[1] == za:
                    piece[1] = zb
                else:
                    piece = [za, zb]
                    out.append(piece)
    return [tuple(p) for p in out]


# For each face axis: the (W, H, Z) key array seen as (slice, row, col) stacks of all
# tiles; (s, v, u) = (x, y, z) for axis x, (y, x, z) for y, (z, y, x) for z.
def _stack(K, a, TW, TH, nx, ny):
    Z = K.shape[2]
    K5 = K.reshape(nx, TW, ny, TH, Z)
    if a == 0:
        return np.ascontiguousarray(K5.transpose(2, 0, 1, 3, 4)).reshape(-1, TH, Z)
    if a == 1:
        return np.ascontiguousarray(K5.transpose(2, 0, 3, 1, 4)).reshape(-1, TW, Z)
    return np.ascontiguousarray(K5.transpose(2, 0, 4, 3, 1)).reshape(-1, TH, TW)


def aggregate_pieces(pieces, tile, nxy, method):
    """Rect columns (COLS) of several pieces [(za, six key arrays of layers za..)]: all
    their (slice, row, col) stacks are zero-padded to one shape and aggregated in one
    call (per-call NumPy overhead dominates otherwise); zero padding at the row and
    column ends changes nothing, not even the 8×8 tile grid."""
    TW, TH = tile
    nx, ny = nxy
    stacks, meta = [], []
    for za, keys in pieces:
        for d, K in enumerate(keys):
            a = d // 2
            stacks.append(_stack(K, a, TW, TH, nx, ny))
            meta.append((d, za, (TW, TH, K.shape[2])[a]))
    if not stacks:
        return []
    V = max(st.shape[1] for st in stacks)
    U = max(st.shape[2] for st in stacks)
    n = [st.shape[0] for st in stacks]
    big = np.zeros((sum(n), V, U), np.uint16)
    start = np.concatenate([[0], np.cumsum(n)])
    for st, s0 in zip(stacks, start):
        big[s0:s0 + st.shape[0], :st.shape[1], :st.shape[2]] = st
    live = np.flatnonzero(big.reshape(len(big), -1).any(1))   # most slices are empty
    big = big[live]
    s, v, u, rh, rw = aggregate.METHODS[method](big)
    block = big[s, v, u]
    s = live[s]
    seg = np.searchsorted(start, s, "right") - 1
    d, za, div = (np.array(c, np.int64)[seg] for c in zip(*meta))
    a = d // 2
    t, m = np.divmod(s - start[seg], div)
    side = a < 2
    x = np.where(a == 0, m, np.where(a == 1, v, u))
    y = np.where(a == 1, m, v)
    z = np.where(side, u, m) + za
    return [(t, x, y, z, d, np.where(side, rh, rw), np.where(side, rw, rh), block)]


def shape_rects(P, zk, zl, tile, nxy):
    """X planes (codes 6, 7) and # planes (8..11) of every X/# cell in layers [zk, zl)."""
    TW, TH = tile
    f = FLAGS[P[1:-1, 1:-1, zk:zl]]
    out = []
    for bit, faces in ((16, X_FACES), (32, HASH_FACES)):
        X, Y, Z = np.nonzero(f & bit)
        t = (Y // TH) * nxy[0] + X // TW
        blk = P[X + 1, Y + 1, Z + zk]
        one = np.ones(len(X), np.int64)
        for c in faces:
            out.append((t, X % TW, Y % TH, Z + zk, np.full(len(X), c), one, one, blk))
    return out


def rects(P, tile, nxy, method, z0, z1, split):
    """Rect columns (dict of COLS -> int arrays, unordered) of every tile of area P
    ((W+2, H+2, 256) with ring); tiles are TW x TH, nxy of them, numbered x fastest.
    The NumPy reference of cl.rects."""
    return mesh_pieces(P, plan(P, z0, z1, split, STEP[method]), tile, method,
                       lambda za, zb: face_keys(slab(P, za, zb)))


def mesh_pieces(P, pieces, tile, method, keys_of):
    nxy = ((P.shape[0] - 2) // tile[0], (P.shape[1] - 2) // tile[1])
    parts = aggregate_pieces([(za, keys_of(za, zb)) for za, zb in pieces], tile, nxy, method)
    for za, zb in pieces:
        parts += shape_rects(P, za, zb, tile, nxy)
    return join(parts)


def join(parts):
    if not parts:
        return {c: np.zeros(0, np.int64) for c in COLS}
    return {c: np.concatenate([p[i] for p in parts]).astype(np.int64) for i, c in enumerate(COLS)}


def to_quads(r):
    """Rect columns -> QUAD array (tile-local positions; texture layers filled in)."""
    q = np.empty(len(r["t"]), QUAD)
    for c in COLS[1:]:
        q[c] = r[c]
    q["layer"] = REGISTRY.face_texture[r["block"], SIDE[r["face"]]]
    q["color"] = r["color"] if "color" in r else 0  # the `color` block's palette index
    return q


def sort_key(r, *extra, xy_bits=16):
    """Unique uint64 order key (tile, *extra, face, z, y, x); extra = (value, bits) pairs."""
    k = r["t"].astype(np.uint64)
    for val, bits in list(extra) + [(r["face"], 4), (r["z"], 8), (r["y"], xy_bits),
                                    (r["x"], xy_bits)]:
        k = (k << np.uint64(bits)) | np.asarray(val).astype(np.uint64)
    return k
