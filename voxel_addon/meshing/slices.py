"""One chunk's greedy mesh again after a few voxels changed, on the CPU (an edit's
remesh): no kernel launch, no copies to a device. The greedy merges only within one
(direction, slice, render region), and a face depends only on its cell and the cell
it faces, so a changed voxel can change only the slices through it and through its
face neighbours (per direction: its own slice and the one its neighbour's face toward
it lies in) and its own X/# planes. Those quads leave the old mesh, those slices are
meshed here again (row by row, as gpu/mesh_greedy.cl does) and the new quads are
merged into the old order. Equals build_chunks on the new blocks when `old` equals it
on the old ones (tested against both backends).
"""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY
from .faces import FLAGS
from .mesh import AXIS, SIDE
from .vertex import _BLOCK_BITS, _INSET_BITS, _PA, _PB, _PC, PASS_OF, PASSES, ChunkMesh

_WANT_SIDE = (FLAGS & 1) != 0     # cube: side faces
_WANT_Z = (FLAGS & 9) != 0        # cube or # caps: -z/+z faces
_OPAQUE = (FLAGS & 2) != 0
_SAME = (FLAGS & 4) != 0          # hidden toward the same block
_X = (FLAGS & 16) != 0
_HASH = (FLAGS & 32) != 0
_SHAPE = _X | _HASH
_L = {k: v.tolist() for k, v in (("side", _WANT_SIDE), ("z", _WANT_Z), ("opaque", _OPAQUE),
                                       ("same", _SAME), ("shape", _SHAPE))}
_NPASS = len(PASSES)
_AX = AXIS.astype(np.int64)
_AX[6:] = 3                          # X/# planes: no slice axis
_AXC = np.minimum(_AX, 2).astype(np.intp)   # the coordinate a face's slice is at


def patch(old: ChunkMesh, P, cells, before=None, origin=(0, 0)) -> ChunkMesh | None:
    """The mesh of the chunk whose window (chunk + one-voxel ring, 18 x 18 x 256) is
    P[ox:ox + 18, oy:oy + 18] (`origin` = (ox, oy)) after the voxels `cells` changed
    ((x, y, z) chunk-local; x, y may be -1 or 16: a neighbour's voxel). `old`: its
    mesh before (as build_chunks made it). `before`: the old block id of each cell
    (optional: slices whose faces stay the same are then kept as they are). None
    where this does not apply: coloured voxels (tint: their colour is data this does
    not see) — mesh those in full."""
    q = np.ascontiguousarray(old.quads)
    if old.colors is not None or (q["block"] == _COLOR).any():
        return None
    ox, oy = origin
    W = P[ox:ox + 18, oy:oy + 18]
    rh = old.region_h
    slices, shapes = _affected(W, cells, before, rh)
    if not slices and not shapes:
        return old
    n = len(q)
    keep = np.ones(n, bool)
    seeds: dict = {}
    if slices:
        # a quad's (direction, slice, region) as one index into a table of the
        # slices' first changed rows (+1; 0: not meshed again), built per call
        f = q["face"].astype(np.intp)
        s = np.choose(_AXC[f], (q["x"], q["y"], q["z"]))
        reg = q["z"] // rh
        nr = 256 // rh
        code = (f * 256 + s) * nr + reg
        lut = np.zeros(12 * 256 * nr, np.int8)
        for c, row in slices.items():
            d, rest = divmod(c, 65536)
            sl, r = divmod(rest, 256)
            i = (d * 256 + sl) * nr
            if d < 4:
                lut[i + r] = row + 1
            else:   # a z slice: every region's code (its quads all lie in one)
                lut[i:i + nr] = row + 1
        first = lut[code]
        hit = np.flatnonzero(first)
        if hit.size:
            # rows above a slice's first changed row run as before: rects that end
            # above it stay, those open at it seed the greedy there
            # (gpu/mesh_greedy.cl's state)
            h = q[hit]
            fh = h["face"].astype(np.intp)
            a = _AX[fh]
            x, y = h["x"].astype(np.int64), h["y"].astype(np.int64)
            wd, ht = h["w"].astype(np.int64), h["h"].astype(np.int64)
            v0 = np.where(a == 1, x, y)
            rows = np.where(a == 2, ht, wd)
            fr = first[hit].astype(np.int64) - 1
            gone = v0 + rows >= fr
            keep[hit[gone]] = False
            # their slice codes as _affected makes them (a z slice: region 0)
            ch = (fh * 256 + s[hit]) * 256 + np.where(a < 2, reg[hit], 0)
            for j in np.flatnonzero(gone & (v0 < fr)).tolist():
                u, cols_ = (int(x[j]), int(wd[j])) if a[j] == 2 else \
                    (int(h["z"][j]) % rh, int(ht[j]))
                seeds.setdefault(int(ch[j]), []).append((u, cols_, int(h["block"][j]),
                                                         int(v0[j])))
    if shapes:
        cell = (q["x"].astype(np.int64) * 16 + q["y"]) * 256 + q["z"]
        keep &= (q["face"] < 6) | ~np.isin(cell, list(shapes))
    new = _quads(W, slices, seeds, shapes, rh)
    if any(t[6] == _COLOR for t in new):
        return None
    return _merge(old, q, keep, new, rh)


_COLOR = REGISTRY.id("color")


def _affected(W, cells, before, rh):
    """{code: first changed row} of the (direction, slice, region) sets to mesh again
    (code = (direction * 256 + slice) * 256 + region, 0 for z slices) and the cells
    (as patch's `cell`) whose X/# planes to redo. With `before` (the old block of
    each cell) a slice whose face keys stay the same is left as it is. A face of c
    in direction d depends on c and its neighbour there: for a changed v, v's own
    faces and those of each neighbour toward v; all read v and its 6 neighbours."""
    cells = [(int(x), int(y), int(z)) for x, y, z in cells]
    was = None
    if before is not None:
        was = {}
        for c, b in zip(cells, before):
            was.setdefault(c, int(b))       # the first old value of a cell counts
    ws, wz, opq, same, shape = (_L[k] for k in ("side", "z", "opaque", "same", "shape"))

    def key(a, b, d):
        return a if (wz if d >= 4 else ws)[a] and not opq[b] and not (same[a] and a == b) \
            else 0

    slices, shapes = {}, set()     # slice code -> its first changed row
    for v in cells:
        x, y, z = v
        around = [v, (x - 1, y, z), (x + 1, y, z), (x, y - 1, z), (x, y + 1, z),
                  (x, y, z - 1), (x, y, z + 1)]    # v, then per direction d: around[d + 1]
        new = [int(W[i + 1, j + 1, k]) if -1 <= i <= 16 and -1 <= j <= 16 and 0 <= k < 256
               else 0 for i, j, k in around]
        old = new if was is None else [was.get(c, b) for c, b in zip(around, new)]
        inv = 0 <= x < 16 and 0 <= y < 16
        if inv and (was is None or shape[old[0]] or shape[new[0]]):
            shapes.add((x * 16 + y) * 256 + z)
        for d in range(6):
            a = d >> 1
            m, n = d + 1, (d ^ 1) + 1   # v's neighbour in direction d, and the other
            for c, i, j in ((v, 0, m), (around[n], n, 0)):
                if 0 <= c[0] < 16 and 0 <= c[1] < 16 and 0 <= c[2] < 256 and (
                        was is None or key(old[i], old[j], d) != key(new[i], new[j], d)):
                    code = (d * 256 + c[a]) * 256 + (c[2] // rh if a < 2 else 0)
                    row = c[0] if a == 1 else c[1]
                    slices[code] = min(row, slices.get(code, row))
    return slices, shapes


def _quads(W, slices, seeds, shapes, rh):
    """Quads (x, y, z, face, w, h, block) of the slices from their first changed row on
    (`seeds`: the rects open there) and of the shape cells, from the window W
    (18, 18, 256) of the new blocks."""
    side, flat = [], []     # (d, s, region start, first row, seeds): x/y and z slices
    for code in sorted(slices):
        d, rest = divmod(code, 65536)
        s, r = divmod(rest, 256)
        (side if d < 4 else flat).append((d, s, r * rh, slices[code],
                                          sorted(seeds.get(code, ()))))
    out: list = []
    if side:
        A = np.empty((len(side), 16, rh), W.dtype)
        B = np.empty_like(A)
        for i, (d, s, z0, _, _) in enumerate(side):
            n = s + 1 + (1 if d & 1 else -1)
            if d < 2:
                A[i], B[i] = W[s + 1, 1:17, z0:z0 + rh], W[n, 1:17, z0:z0 + rh]
            else:
                A[i], B[i] = W[1:17, s + 1, z0:z0 + rh], W[1:17, n, z0:z0 + rh]
        _rects(_keys(A, B, _T_SIDE), side, out)
    if flat:
        A = np.empty((len(flat), 16, 16), W.dtype)
        B = np.zeros_like(A)                    # outside the world: air
        for i, (d, z, *_) in enumerate(flat):
            A[i] = W[1:17, 1:17, z].T            # rows y, columns x
            n = z + (1 if d & 1 else -1)
            if 0 <= n < 256:
                B[i] = W[1:17, 1:17, n].T
        _rects(_keys(A, B, _T_Z), flat, out)
    for c in sorted(shapes):
        rest, z = divmod(c, 256)
        x, y = divmod(rest, 16)
        b = int(W[x + 1, y + 1, z])
        faces = (6, 7) if _X[b] else (8, 9, 10, 11) if _HASH[b] else ()
        out += [(x, y, z, f, 1, 1, b) for f in faces]
    return out


def _table(want):
    """(n, n) face key of block a toward block b, flat: key = T[a * n + b]."""
    a = np.arange(len(FLAGS))[:, None]
    b = np.arange(len(FLAGS))[None, :]
    hide = _OPAQUE[b] | (_SAME[a] & (a == b))
    return np.where(want[a] & ~hide, a, 0).astype(np.uint16).ravel()


_T_SIDE, _T_Z = _table(_WANT_SIDE), _table(_WANT_Z)


def _keys(A, B, table):
    """Face keys (block id where the face of A toward B is drawn, else 0), with a
    zero column after each row (segments end there)."""
    n, V, U = A.shape
    K = np.zeros((n, V, U + 1), np.uint16)
    K[:, :, :U] = table[A.astype(np.intp) * len(FLAGS) + B]
    return K


def _rects(K, meta, out):
    """Greedy rects of every slice of K (n, 16, U + 1; last column zero) appended to
    `out` as quads."""
    n, V, U1 = K.shape
    F = K.ravel()
    ch = np.flatnonzero(F[1:] != F[:-1]) + 1       # segments: runs of one key
    ch = np.concatenate([[0], ch])
    key = F[ch[:-1]]
    live = np.flatnonzero(key)
    a0, a1, key = ch[live], ch[live + 1], key[live]
    row, u0 = np.divmod(a0, U1)
    late = row % V >= np.array([m[3] for m in meta])[row // V]   # rows from the first changed
    row, u0, a1, key = row[late], u0[late], a1[late], key[late]
    u1 = a1 - row * U1
    rows = [[[] for _ in range(V)] for _ in range(n)]
    for r, c, e, k in zip(row.tolist(), u0.tolist(), u1.tolist(), key.tolist()):
        rows[r // V][r % V].append((c, e, k))
    for (d, s, z0, v1, opn), rs in zip(meta, rows):
        got = greedy_rows(rs, v1, opn)
        if d < 2:
            out += [(s, v0, z0 + u, d, nr, nc, k) for v0, u, nr, nc, k in got]
        elif d < 4:
            out += [(v0, s, z0 + u, d, nr, nc, k) for v0, u, nr, nc, k in got]
        else:
            out += [(u, v0, s, d, nc, nr, k) for v0, u, nr, nc, k in got]


def greedy_rows(rows, start=0, opn=()):
    """Mikola's greedy row by row (as gpu/mesh_greedy.cl `span`) on one slice given as
    per row a list of segments (u0, u1, key): maximal runs of one non-zero key, by u0.
    An open rectangle continues while its whole width in the next row has its key (lies
    in one segment of that key); the cells no continuing rectangle covers start maximal
    runs. Returns (first row, first column, rows, columns, key) per rectangle. `start`,
    `opn`: go on from row `start` with these rectangles open (u, w, key, first row;
    by u), as the rows above left them."""
    out = []
    V = len(rows)
    for v in range(start, V + 1):
        segs = rows[v] if v < V else ()
        kept = []
        j, n = 0, len(segs)
        for o in opn:
            u, w, k, v0 = o
            while j < n and segs[j][1] <= u:
                j += 1
            if j < n and segs[j][0] <= u and u + w <= segs[j][1] and segs[j][2] == k:
                kept.append(o)
            else:
                out.append((v0, u, v - v0, w, k))
        if v == V:
            break
        opn = []
        i, nk = 0, len(kept)
        for a, b, k in segs:
            cur = a
            while i < nk and kept[i][0] < b:
                o = kept[i]
                if o[0] > cur:
                    opn.append((cur, o[0] - cur, k, v))
                opn.append(o)
                cur = o[0] + o[1]
                i += 1
            if cur < b:
                opn.append((cur, b - cur, k, v))
    return out


def _merge(old, q, keep, new, rh):
    """The kept old quads (q: old.quads, contiguous) and vertices with the `new` ones
    (x, y, z, face, w, h, block) put in their places in build_chunks' order: (region,
    pass) as `ranges` has them, then (face, z, y, x)."""
    n_old, nn = len(q), len(new)
    counts = old.ranges[..., 1].ravel() // 4        # quads per (region, pass) slot
    ends = np.cumsum(counts)
    c = np.array(new, np.int64).reshape(nn, 7).T
    x, y, z, f, w, h, b = c
    reg = z // rh
    slot = reg * _NPASS + PASS_OF[b]
    # (face, z, y, x) is the little-endian value of a QUAD's first 7 bytes (x, y, z
    # u2, face u1): old quads are sorted by it within their slot
    low = (((f << 16 | z) << 16 | y) << 16 | x).astype(np.uint64)
    o = np.lexsort((low, slot))
    x, y, z, f, w, h, b, reg, slot, low = (v[o] for v in (x, y, z, f, w, h, b, reg, slot, low))
    raw = np.ndarray((n_old,), "<u8", q, 0, (q.itemsize,)) if n_old else \
        np.zeros(0, np.uint64)
    # each new quad goes before the first old quad of its slot with a larger key
    # (keys are unique), and so after the kept ones before that
    pos = np.empty(nn, np.int64)
    sl = slot.tolist()
    i = 0
    while i < nn:
        j, s = i + 1, sl[i]
        while j < nn and sl[j] == s:
            j += 1
        a0 = int(ends[s] - counts[s])
        pos[i:j] = a0 + np.searchsorted(raw[a0:ends[s]] & _LOW7, low[i:j])
        i = j
    gone = np.flatnonzero(~keep)
    at = pos - np.searchsorted(gone, pos) + np.arange(nn)
    idx = np.empty(n_old - len(gone) + nn, np.intp)
    mask = np.ones(len(idx), bool)
    mask[at] = False
    idx[mask] = np.flatnonzero(keep)
    idx[at] = np.arange(n_old, n_old + nn)
    nq = np.zeros(nn, q.dtype)
    for name, v in zip(("x", "y", "z", "face", "w", "h", "block"), (x, y, z, f, w, h, b)):
        nq[name] = v
    nq["layer"] = layer = REGISTRY.face_texture[b, SIDE[f]]
    quads = _take_records(q, nq, idx)
    verts = _verts(f, x, y, z - reg * rh, w, h, b, layer)
    vertices = np.take(np.concatenate([old.vertices.reshape(-1, 4), verts]), idx, 0).ravel()
    n = len(counts)
    counts = counts + np.bincount(slot, minlength=n) - \
        np.bincount(np.searchsorted(ends, gone, "right"), minlength=n)
    ranges = np.empty((n, 2), np.int32)
    ranges[:, 1] = counts * 4
    ranges[:, 0] = (np.cumsum(counts) - counts) * 4
    return ChunkMesh(vertices, ranges.reshape(256 // rh, _NPASS, 2), rh, quads, None)


def _verts(f, x, y, z, w, h, b, layer):
    """_pack for a few quads (int64 columns already inside their region): fewer,
    two-dimensional table lookups."""
    pq = x | y << 5 | z << 10 | f << 17 | layer.astype(np.int64) << 21 | _BITS[b] \
        | (f >= 8) * _INSET[b]
    return (pq[:, None] + _PA64[f] * w[:, None] + _PB64[f] * h[:, None] + _PC64[f]) \
        .astype(np.uint32)


_LOW7 = np.uint64((1 << 56) - 1)
_BITS, _INSET = (t.astype(np.int64) for t in (_BLOCK_BITS, _INSET_BITS))
_PA64, _PB64, _PC64 = (t.astype(np.int64) for t in (_PA, _PB, _PC))


def _take_records(q, nq, idx):
    """concatenate([q, nq])[idx] for record arrays, done on their bytes (record copies
    and fancy indexing of records are several times slower)."""
    n = q.dtype.itemsize
    raw = np.concatenate([q.view(np.uint8).reshape(-1, n), nq.view(np.uint8).reshape(-1, n)])
    return np.take(raw, idx, 0).view(q.dtype).ravel()
