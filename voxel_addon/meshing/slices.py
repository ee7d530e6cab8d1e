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
from .vertex import PASS_OF, PASSES, ChunkMesh, _pack

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
_AX = AXIS[:6].astype(np.int64)


def patch(old: ChunkMesh, P, cells, before=None, origin=(0, 0)) -> ChunkMesh | None:
    """The mesh of the chunk whose window (chunk + one-voxel ring, 18 x 18 x 256) is
    P[ox:ox + 18, oy:oy + 18] (`origin` = (ox, oy)) after the voxels `cells` changed
    ((x, y, z) chunk-local; x, y may be -1 or 16: a neighbour's voxel). `old`: its
    mesh before (as build_chunks made it). `before`: the old block id of each cell
    (optional: slices whose faces stay the same are then kept as they are). None
    where this does not apply: coloured voxels (tint: their colour is data this does
    not see) — mesh those in full."""
    if old.colors is not None or (old.quads["block"] == _COLOR).any():
        return None
    ox, oy = origin
    W = P[ox:ox + 18, oy:oy + 18]
    rh = old.region_h
    slices, shapes = _affected(W, cells, before, rh)
    if not slices and not shapes:
        return old
    q = old.quads
    f, x, y, z, b = (q[c].astype(np.int64) for c in ("face", "x", "y", "z", "block"))
    codes = _codes(f, x, y, z, rh)
    keep = np.ones(len(q), bool)
    seeds: dict = {}
    if slices:
        # rows above a slice's first changed row run as before: rects that end above
        # it stay, those open at it seed the greedy there (gpu/mesh_greedy.cl's state)
        sc = np.array(sorted(slices), np.int64)
        i = np.minimum(np.searchsorted(sc, codes), len(sc) - 1)
        hit = sc[i] == codes
        a = _AX[np.minimum(f, 5)]
        v0 = np.where(a == 1, x, y)
        rows = np.where(a == 2, q["h"], q["w"])
        first = np.array([slices[c] for c in sc.tolist()], np.int64)[i]
        keep = ~hit | (v0 + rows < first)
        for j in np.flatnonzero(hit & (v0 < first) & (v0 + rows >= first)).tolist():
            u, cols_ = (int(x[j]), int(q["w"][j])) if a[j] == 2 else \
                (int(z[j]) % rh, int(q["h"][j]))
            seeds.setdefault(int(codes[j]), []).append((u, cols_, int(b[j]), int(v0[j])))
    if shapes:
        cell = (x * 16 + y) * 256 + z
        keep &= (f < 6) | ~np.isin(cell, list(shapes))
    new = _quads(W, slices, seeds, shapes, rh)
    if any(k == _COLOR for k in new[6]):
        return None
    return _merge(old, keep, _order(f, x, y, z, b, rh), (z // rh) * _NPASS + PASS_OF[b], new, rh)


_COLOR = REGISTRY.id("color")


def _affected(W, cells, before, rh):
    """{code: first changed row} of the (direction, slice, region) sets to mesh again
    (codes as _codes makes them) and the codes of the cells whose X/# planes to redo.
    With `before` (the old block of each cell) a slice whose face keys stay the same
    is left as it is."""
    cells = [(int(x), int(y), int(z)) for x, y, z in cells]
    was = None
    if before is not None:
        was = {}
        for c, b in zip(cells, before):
            was.setdefault(c, int(b))       # the first old value of a cell counts

    def inside(c):
        return 0 <= c[0] < 16 and 0 <= c[1] < 16 and 0 <= c[2] < 256

    def at(c, old):
        if not 0 <= c[2] < 256:
            return 0
        if old and c in was:
            return was[c]
        return int(W[c[0] + 1, c[1] + 1, c[2]])

    def key(c, d, old):
        a = at(c, old)
        if not (wz if d >= 4 else ws)[a]:
            return 0
        n = list(c)
        n[d >> 1] += 1 if d & 1 else -1
        b = at(tuple(n), old)
        return 0 if opq[b] or (same[a] and a == b) else a

    ws, wz, opq, same, shape = (_L[k] for k in ("side", "z", "opaque", "same", "shape"))
    slices, shapes = {}, set()     # slice code -> its first changed row
    for v in cells:
        if inside(v) and (was is None or shape[at(v, True)] or shape[at(v, False)]):
            shapes.add((v[0] * 16 + v[1]) * 256 + v[2])   # as patch's `cell`
        for d in range(6):
            a, sign = d >> 1, 1 if d & 1 else -1
            n = list(v)
            n[a] -= sign     # the neighbour whose face toward v lies in direction d
            for c in (v, tuple(n)):
                if inside(c) and (was is None or key(c, d, True) != key(c, d, False)):
                    code = (d * 256 + c[a]) * 256 + (c[2] // rh if a < 2 else 0)
                    row = c[0] if a == 1 else c[1]
                    slices[code] = min(row, slices.get(code, row))
    return slices, shapes


def _codes(f, x, y, z, rh):
    """Per quad: its (direction, slice, region) code (cube faces; -1 for X/# planes)."""
    cube = f < 6
    a = _AX[np.minimum(f, 5)]
    s = np.where(a == 0, x, np.where(a == 1, y, z))
    r = np.where(a < 2, z // rh, 0)
    return np.where(cube, (f * 256 + s) * 256 + r, -1)


def _quads(W, slices, seeds, shapes, rh):
    """Quad columns (x, y, z, face, w, h, block) of the slices from their first changed
    row on (`seeds`: the rects open there) and of the shape cells, from the window W
    (18, 18, 256) of the new blocks."""
    side, flat = [], []     # (d, s, region start, first row, seeds): x/y and z slices
    for code in sorted(slices):
        d, rest = divmod(code, 65536)
        s, r = divmod(rest, 256)
        (side if d < 4 else flat).append((d, s, r * rh, slices[code],
                                          sorted(seeds.get(code, ()))))
    cols = [[] for _ in range(7)]
    if side:
        A = np.empty((len(side), 16, rh), W.dtype)
        B = np.empty_like(A)
        for i, (d, s, z0, _, _) in enumerate(side):
            n = s + 1 + (1 if d & 1 else -1)
            if d < 2:
                A[i], B[i] = W[s + 1, 1:17, z0:z0 + rh], W[n, 1:17, z0:z0 + rh]
            else:
                A[i], B[i] = W[1:17, s + 1, z0:z0 + rh], W[1:17, n, z0:z0 + rh]
        _rects(_keys(A, B, _T_SIDE), side, cols)
    if flat:
        A = np.empty((len(flat), 16, 16), W.dtype)
        B = np.zeros_like(A)                    # outside the world: air
        for i, (d, z, *_) in enumerate(flat):
            A[i] = W[1:17, 1:17, z].T            # rows y, columns x
            n = z + (1 if d & 1 else -1)
            if 0 <= n < 256:
                B[i] = W[1:17, 1:17, n].T
        _rects(_keys(A, B, _T_Z), flat, cols)
    for c in sorted(shapes):
        rest, z = divmod(c, 256)
        x, y = divmod(rest, 16)
        b = int(W[x + 1, y + 1, z])
        faces = (6, 7) if _X[b] else (8, 9, 10, 11) if _HASH[b] else ()
        for f in faces:
            for col, v in zip(cols, (x, y, z, f, 1, 1, b)):
                col.append(v)
    return cols


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


def _rects(K, meta, cols):
    """Greedy rects of every slice of K (n, 16, U + 1; last column zero) appended to
    the quad columns."""
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
    X, Y, Z, F, Wc, Hc, Bk = cols
    for (d, s, z0, v1, opn), rs in zip(meta, rows):
        a = d >> 1
        for v0, u, nr, nc, k in greedy_rows(rs, v1, opn):
            if a == 0:
                X.append(s), Y.append(v0), Z.append(z0 + u), Wc.append(nr), Hc.append(nc)
            elif a == 1:
                X.append(v0), Y.append(s), Z.append(z0 + u), Wc.append(nr), Hc.append(nc)
            else:
                X.append(u), Y.append(v0), Z.append(s), Wc.append(nc), Hc.append(nr)
            F.append(d)
            Bk.append(k)


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


def _take_records(q, nq, idx):
    """concatenate([q, nq])[idx] for record arrays, done on their bytes (record copies
    and fancy indexing of records are several times slower)."""
    n = q.dtype.itemsize
    raw = np.concatenate([np.ascontiguousarray(q).view(np.uint8).reshape(-1, n),
                          nq.view(np.uint8).reshape(-1, n)])
    return np.take(raw, idx, 0).view(q.dtype).ravel()


def _order(face, x, y, z, block, rh):
    """build_chunks' vertex order key: (region, pass, face, z, y, x)."""
    reg = z // rh
    ps = PASS_OF[block].astype(np.int64)
    return ((((reg * _NPASS + ps) * 16 + face) * 256 + z) * 32 + y) * 32 + x


def _merge(old, keep, old_key, old_slot, cols, rh):
    """The kept old quads and vertices with the new ones (cols) put in their places
    (old_key: the old quads' order keys; old_slot: their (region, pass) index)."""
    q = old.quads
    x, y, z, f, w, h, b = (np.array(c, np.int64) for c in cols)
    key = _order(f, x, y, z, b, rh)
    o = np.argsort(key)
    x, y, z, f, w, h, b, key = x[o], y[o], z[o], f[o], w[o], h[o], b[o], key[o]
    nq = np.zeros(len(x), q.dtype)
    for c, v in zip(("x", "y", "z", "face", "w", "h", "block"), (x, y, z, f, w, h, b)):
        nq[c] = v
    nq["layer"] = REGISTRY.face_texture[b, SIDE[f]]
    reg = z // rh
    verts = _pack(f, x, y, z - reg * rh, w, h, b, nq["layer"]).reshape(-1, 4)
    # final order: kept old quads in their order, each new one before the first old
    # quad with a larger key (keys are unique)
    n_old, nn = len(q), len(x)
    kept = np.flatnonzero(keep)
    before = np.searchsorted(kept, np.searchsorted(old_key, key))  # kept ones before it
    at = before + np.arange(nn)
    idx = np.empty(len(kept) + nn, np.intp)
    mask = np.ones(len(idx), bool)
    mask[at] = False
    idx[mask] = kept
    idx[at] = n_old + np.arange(nn)
    quads = _take_records(q, nq, idx)
    vertices = np.take(np.concatenate([old.vertices.reshape(-1, 4), verts]), idx, 0).ravel()
    npass = _NPASS
    counts = old.ranges[..., 1].ravel().copy()
    gone = ~keep
    if gone.any():
        counts -= 4 * np.bincount(old_slot[gone], minlength=len(counts))
    counts += 4 * np.bincount(reg * npass + PASS_OF[b], minlength=len(counts))
    first = np.cumsum(counts) - counts
    ranges = np.stack([first, counts], -1).reshape(256 // rh, npass, 2).astype(np.int32)
    return ChunkMesh(vertices, ranges, rh, quads, None)

