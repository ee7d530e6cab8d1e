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

import threading
from bisect import bisect_right

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
_SHAPE_L = _SHAPE.tolist()
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
    olds: dict = {}     # per slice: its old quads from the first changed row on
    seeds: dict = {}
    if slices:
        # a quad's (direction, slice, region) as one index into a table of the
        # slices' first changed rows (+1; 0: not meshed again), built per call
        f = q["face"].astype(np.intp)
        s = np.choose(_AXC[f], (q["x"], q["y"], q["z"]))
        nr = 256 // rh
        code = (f * 256 + s) * nr + q["z"] // rh
        lut = np.zeros(12 * 256 * nr, np.int8)
        for c, (row, _) in slices.items():
            d, rest = divmod(c, 65536)
            sl, r = divmod(rest, 256)
            i = (d * 256 + sl) * nr
            if d < 4:
                lut[i + r] = row + 1
            else:   # a z slice: every region's code (its quads all lie in one)
                lut[i:i + nr] = row + 1
        first = lut[code]
        hit = np.flatnonzero(first)
        # rows above a slice's first changed row run as before: rects that end
        # above it stay, those open at it seed the greedy there
        # (gpu/mesh_greedy.cl's state); a few dozen quads: plain Python
        for j, (x, y, z, fh, wd, ht, b, _, _), fr in zip(hit.tolist(), q[hit].tolist(),
                                                       first[hit].tolist()):
            fr -= 1
            if fh < 2:
                v0, rows, u, cols, sc = y, wd, z % rh, ht, (fh * 256 + x) * 256 + z // rh
            elif fh < 4:
                v0, rows, u, cols, sc = x, wd, z % rh, ht, (fh * 256 + y) * 256 + z // rh
            else:   # its slice code as _affected makes it (a z slice: region 0)
                v0, rows, u, cols, sc = y, ht, x, wd, (fh * 256 + z) * 256
            if v0 + rows >= fr:     # open after the row above the first changed one
                olds.setdefault(sc, []).append((u, cols, b, v0, v0 + rows - 1, j))
                if v0 < fr:
                    seeds.setdefault(sc, []).append((u, cols, b, v0))
    new, stops = _quads(W, slices, seeds, olds, shapes, rh)
    if any(t[6] == _COLOR for t in new):
        return None
    # the old quads the greedy closed again: those closed before the row it stopped at
    gone = sorted(o[5] for c, os_ in olds.items() for o in os_ if o[4] < stops[c])
    if shapes:
        cell = (q["x"].astype(np.int64) * 16 + q["y"]) * 256 + q["z"]
        planes = np.flatnonzero((q["face"] >= 6) & np.isin(cell, list(shapes)))
        gone = sorted(set(gone).union(planes.tolist()))
    return _merge(old, q, gone, new, rh)


_COLOR = REGISTRY.id("color")


def _affected(W, cells, before, rh):
    """{code: (first, last) changed row} of the (direction, slice, region) sets to mesh again
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
    shape, T, nf = _SHAPE_L, _T_LIST, _NF   # face key of a toward b: T[(a + NF z) * NF + b]
    slices, shapes = {}, set()     # slice code -> its first and last changed rows
    item = W.item
    for v in cells:
        x, y, z = v
        around = [v, (x - 1, y, z), (x + 1, y, z), (x, y - 1, z), (x, y + 1, z),
                  (x, y, z - 1), (x, y, z + 1)]    # v, then per direction d: around[d + 1]
        new = [item(i + 1, j + 1, k) if -1 <= i <= 16 and -1 <= j <= 16 and 0 <= k < 256
               else 0 for i, j, k in around]
        old = new if was is None else [was.get(c, b) for c, b in zip(around, new)]
        inv = 0 <= x < 16 and 0 <= y < 16
        if inv and (was is None or shape[old[0]] or shape[new[0]]):
            shapes.add((x * 16 + y) * 256 + z)
        for d in range(6):
            a = d >> 1
            m, n = d + 1, (d ^ 1) + 1   # v's neighbour in direction d, and the other
            zf = nf if d >= 4 else 0
            for c, i, j in ((v, 0, m), (around[n], n, 0)):
                if 0 <= c[0] < 16 and 0 <= c[1] < 16 and 0 <= c[2] < 256 and (
                        was is None or T[(old[i] + zf) * nf + old[j]]
                        != T[(new[i] + zf) * nf + new[j]]):
                    code = (d * 256 + c[a]) * 256 + (c[2] // rh if a < 2 else 0)
                    row = c[0] if a == 1 else c[1]
                    lo, hi = slices.get(code, (row, row))
                    slices[code] = (min(lo, row), max(hi, row))
    return slices, shapes


def _quads(W, slices, seeds, olds, shapes, rh):
    """Quads (x, y, z, face, w, h, block) of the slices from their first changed row on
    (`seeds`: the rects open there) and of the shape cells, from the window W
    (18, 18, 256) of the new blocks, and per slice the row its greedy stopped at
    (`olds`: its old quads from the first changed row on, as patch keeps them). The
    x/y slices (rows of one region's rh layers) and z slices (16 x 16) go through one
    array of U = max(rh, 16) columns: a z slice's columns past 16 hold air (no key),
    and its keys come from the second half of the table (NumPy's fixed cost per call
    outweighs these tiny arrays)."""
    meta = []     # (d, s, region start, first row, seeds, last row, olds, code)
    for code in sorted(slices):
        d, rest = divmod(code, 65536)
        s, r = divmod(rest, 256)
        v1, v2 = slices[code]
        meta.append((d, s, r * rh, v1, sorted(seeds.get(code, ())), v2,
                     olds.get(code, ()), code))
    out: list = []
    stops: dict = {}
    if meta:
        U = max(rh, 16)
        # rows from each slice's first changed one (those above stay air: no keys);
        # column U stays air: its key 0 ends each row
        A, B, K = _rows(len(meta), U + 1)   # B: outside the world air
        for i, (d, s, z0, v, *_) in enumerate(meta):
            n = s + 1 + (1 if d & 1 else -1)
            if d < 2:
                A[i, v:, :rh] = W[s + 1, 1 + v:17, z0:z0 + rh]
                B[i, v:, :rh] = W[n, 1 + v:17, z0:z0 + rh]
            elif d < 4:
                A[i, v:, :rh] = W[1 + v:17, s + 1, z0:z0 + rh]
                B[i, v:, :rh] = W[1 + v:17, n, z0:z0 + rh]
            else:
                A[i, v:, :16] = W[1:17, 1 + v:17, s].T            # rows y, columns x
                if 0 <= n - 1 < 256:
                    B[i, v:, :16] = W[1:17, 1 + v:17, n - 1].T
        flat = sum(m[0] >= 4 for m in meta)     # z slices sort last
        if flat:
            A[len(meta) - flat:] += _NF
        A *= _NF
        A += B
        _rects(np.take(_T_ALL, A, out=K), meta, out, stops)
    for c in sorted(shapes):
        rest, z = divmod(c, 256)
        x, y = divmod(rest, 16)
        b = int(W[x + 1, y + 1, z])
        faces = (6, 7) if _X[b] else (8, 9, 10, 11) if _HASH[b] else ()
        out += [(x, y, z, f, 1, 1, b) for f in faces]
    return out, stops


_SCRATCH = threading.local()


def _rows(n, u):
    """(A, B, K) for n slices of 16 rows of u columns: A and B zeroed (intp: the
    key table's take needs no converted copy), K for the keys; views of this
    thread's scratch arrays. Fresh arrays here cost ~18 page faults a call in a
    big process (~45 us: more than their work)."""
    ab, k = getattr(_SCRATCH, "ab", None), getattr(_SCRATCH, "k", None)
    if ab is None or ab.shape[1] < n or ab.shape[3] != u:
        ab = _SCRATCH.ab = np.zeros((2, max(n, 16), 16, u), np.intp)
        k = _SCRATCH.k = np.empty((max(n, 16), 16, u), np.uint16)
    ab = ab[:, :n]
    ab[...] = 0
    return ab[0], ab[1], k[:n]


def _table(want):
    """(n, n) face key of block a toward block b, flat: key = T[a * n + b]."""
    a = np.arange(len(FLAGS))[:, None]
    b = np.arange(len(FLAGS))[None, :]
    hide = _OPAQUE[b] | (_SAME[a] & (a == b))
    return np.where(want[a] & ~hide, a, 0).astype(np.uint16).ravel()


_NF = len(FLAGS)
# side keys at a * NF + b, z keys at (NF + a) * NF + b (a z slice's A is offset by NF)
_T_ALL = np.concatenate([_table(_WANT_SIDE), _table(_WANT_Z)])
_T_LIST = _T_ALL.tolist()


def _rects(K, meta, out, stops):
    """Greedy rects of every slice of K (n, 16, U + 1; last column zero; rows above a
    slice's first changed row zero) appended to `out` as quads."""
    n, V, U1 = K.shape
    F = K.ravel()
    ch = np.flatnonzero(F[1:] != F[:-1]) + 1       # segments: runs of one key
    ch = np.concatenate([[0], ch])
    key = F[ch[:-1]]
    live = np.flatnonzero(key)
    a0, a1, key = ch[live], ch[live + 1], key[live]
    row, u0 = np.divmod(a0, U1)
    u1 = a1 - row * U1
    rows = [[[] for _ in range(V)] for _ in range(n)]
    for r, c, e, k in zip(row.tolist(), u0.tolist(), u1.tolist(), key.tolist()):
        rows[r // V][r % V].append((c, e, k))
    for (d, s, z0, v1, opn, v2, old, code), rs in zip(meta, rows):
        got, stops[code] = greedy_rows(rs, v1, opn, v2, old)
        if d < 2:
            out += [(s, v0, z0 + u, d, nr, nc, k) for v0, u, nr, nc, k in got]
        elif d < 4:
            out += [(v0, s, z0 + u, d, nr, nc, k) for v0, u, nr, nc, k in got]
        else:
            out += [(u, v0, s, d, nc, nr, k) for v0, u, nr, nc, k in got]


def greedy_rows(rows, start=0, opn=(), last=None, old=()):
    """Mikola's greedy row by row (as gpu/mesh_greedy.cl `span`) on one slice given as
    per row a list of segments (u0, u1, key): maximal runs of one non-zero key, by u0.
    An open rectangle continues while its whole width in the next row has its key (lies
    in one segment of that key); the cells no continuing rectangle covers start maximal
    runs. Returns (first row, first column, rows, columns, key) per rectangle. `start`,
    `opn`: go on from row `start` with these rectangles open (u, w, key, first row;
    by u), as the rows above left them.

    `last`, `old`: the rows after `last` are those the old rectangles `old` (u, w,
    key, first row, last row, ...) were made of: from there, once the open ones
    equal the old ones open at that row, everything after comes out as before, so
    stop. Then returns (rectangles, v): those closed before row v, the old ones
    closed before v to be replaced by them (v = len(rows): all)."""
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
        if last is not None and v >= last and \
                opn == sorted(o[:4] for o in old if o[3] <= v <= o[4]):
            return out, v
    return out if last is None else (out, V)


def _merge(old, q, gone, new, rh):
    """The old quads (q: old.quads, contiguous) and vertices but those at the sorted
    indices `gone`, with the `new` ones (x, y, z, face, w, h, block) put in their
    places in build_chunks' order: (region, pass) as `ranges` has them, then (face, z,
    y, x). A stroke's few quads: plain Python around two concatenations of runs
    (NumPy's calls on such tiny arrays cost more than their work)."""
    counts = (old.ranges[..., 1].ravel() // 4).tolist()  # quads per (region, pass) slot
    ends, e = [], 0
    for c in counts:
        e += c
        ends.append(e)
    # (face, z, y, x) is the little-endian value of a QUAD's first 7 bytes (x, y, z
    # u2, face u1): old quads are sorted by it within their slot; keys are unique
    po = _PASS_L
    new = sorted(((z // rh) * _NPASS + po[b], ((f << 16 | z) << 16 | y) << 16 | x, t)
                 for t in new for x, y, z, f, _, _, b in (t,))
    n_old = len(q)
    raw = np.ndarray((n_old,), "<u8", q, 0, (q.itemsize,)) if n_old else None
    # each new quad goes before the first old quad of its slot with a larger key
    pos = []
    i, nn = 0, len(new)
    while i < nn:
        s = new[i][0]
        j = i + 1
        while j < nn and new[j][0] == s:
            j += 1
        a0 = ends[s] - counts[s]
        if ends[s] > a0:
            keys = np.array([t[1] for t in new[i:j]], np.uint64)
            pos += (np.searchsorted(raw[a0:ends[s]] & _LOW7, keys) + a0).tolist()
        else:
            pos += [a0] * (j - i)
        i = j
    ft, sd = _FT_L, _SIDE_L
    recs, verts = [], []
    for s, _, (x, y, z, f, w, h, b) in new:
        layer = ft[b][sd[f]]
        recs.append((x, y, z, f, w, h, b, layer, 0))
        pq = x | y << 5 | (z - z // rh * rh) << 10 | f << 17 | layer << 21 | _BITS_L[b] \
            | (_INSET_L[b] if f >= 8 else 0)
        pa, pb, pc = _PA_L[f], _PB_L[f], _PC_L[f]
        verts += [(pq + pa[k] * w + pb[k] * h + pc[k]) & 0xFFFFFFFF for k in range(4)]
        counts[s] += 1
    for g in gone:
        counts[bisect_right(ends, g)] -= 1
    # runs of kept old quads and of new ones, in order
    n = q.dtype.itemsize
    Q = q.view(np.uint8).reshape(-1, n)
    V = old.vertices.reshape(-1, 4)
    NQ = np.array(recs, q.dtype).view(np.uint8).reshape(-1, n)
    NV = np.array(verts, np.uint32).reshape(-1, 4)
    qs, vs = [], []
    at, gi, ng, i = 0, 0, len(gone), 0
    while at < n_old or i < nn:
        # old quads from `at` up to the next new one's place or the next gone one
        stop = pos[i] if i < nn else n_old
        while at < stop:
            g = gone[gi] if gi < ng else n_old
            if g == at:
                at += 1
                gi += 1
                continue
            e = min(g, stop)
            qs.append(Q[at:e])
            vs.append(V[at:e])
            at = e
        if i < nn:
            j = i + 1
            while j < nn and pos[j] == pos[i]:
                j += 1
            qs.append(NQ[i:j])
            vs.append(NV[i:j])
            i = j
    quads = np.concatenate(qs).view(q.dtype).ravel() if qs else q[:0].copy()
    vertices = np.concatenate(vs).ravel() if vs else old.vertices[:0].copy()
    ranges, e = [], 0
    for c in counts:
        ranges.append((e * 4, c * 4))
        e += c
    return ChunkMesh(vertices, np.array(ranges, np.int32).reshape(256 // rh, _NPASS, 2), rh,
                     quads, None)


_PASS_L = PASS_OF.tolist()
_SIDE_L = SIDE.tolist()
_FT_L = REGISTRY.face_texture.tolist()
_LOW7 = np.uint64((1 << 56) - 1)
_BITS_L, _INSET_L = (t.tolist() for t in (_BLOCK_BITS, _INSET_BITS))
_PA_L, _PB_L, _PC_L = (t.tolist() for t in (_PA, _PB, _PC))
