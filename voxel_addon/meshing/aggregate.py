"""Face aggregation on stacks of 2D face maps (thesis §5.3.3, fig. 5.9).

Input is a key array K of shape (S, V, U): S independent slices, V rows, U columns;
K == 0 means "no face", equal non-zero keys may merge. Output is rectangles as int
arrays (s, v, u, h, w) (h rows × w columns). The thesis's methods work inside aligned
8×8 tiles (its compute-shader work group); tiles are turned into extra slices so one
code path serves all (empty tiles are dropped first). `greedy` is unbounded: row by
row, a rectangle keeps growing down while every cell under it has its key; free cells
start new maximal runs (exactly Mikola's scan-order greedy; gpu/mesh_greedy.cl runs the
same per slice, this runs it on the compact list of non-empty cells of all slices).
"""
from __future__ import annotations

import numpy as np

TILE = 8


def _empty():
    z = np.zeros(0, np.int64)
    return z, z, z, z, z


def none(K):
    s, v, u = np.nonzero(K)
    one = np.ones_like(s)
    return s, v, u, one, one


def _tiles(K):
    """(S,V,U) -> (n, 8, 8) non-empty tiles, plus a function mapping tile rects back."""
    S, V, U = K.shape
    TV, TU = -(-V // TILE), -(-U // TILE)
    P = np.zeros((S, TV * TILE, TU * TILE), K.dtype)
    P[:, :V, :U] = K
    T = P.reshape(S, TV, TILE, TU, TILE).transpose(0, 1, 3, 2, 4).reshape(-1, TILE, TILE)
    live = np.flatnonzero(T.reshape(len(T), -1).any(1))    # most tiles have no face
    T = T[live]

    def back(s, v, u, h, w):
        ss, rest = np.divmod(live[s], TV * TU)
        tv, tu = np.divmod(rest, TU)
        return ss, tv * TILE + v, tu * TILE + u, h, w
    return T, back


def _label_unit(K):
    """Per-cell rectangle description for the all-1×1 partition."""
    S, V, U = K.shape
    u0 = np.broadcast_to(np.arange(U, dtype=np.int16), K.shape).copy()
    v0 = np.broadcast_to(np.arange(V, dtype=np.int16)[:, None], K.shape).copy()
    one = np.ones(K.shape, np.int16)
    return v0, u0, one, one.copy()


def _merge(K, v0, u0, h, w, axis):
    """Merge chains of neighbouring rectangles that share the full edge across `axis`
    (2 = along u: same v0 and h; 1 = along v: same u0 and w) and the same key."""
    n = K.shape[axis]
    pos = np.arange(n, dtype=np.int16).reshape((-1, 1) if axis == 1 else (1, -1))
    start, ext = (u0, w) if axis == 2 else (v0, h)
    o0, oext = (v0, h) if axis == 2 else (u0, w)

    def sl(a, lo, hi):
        return a[:, :, lo:hi] if axis == 2 else a[:, lo:hi, :]

    idx = np.broadcast_to(pos, K.shape)
    # Only a cell that starts its rectangle can join the one before it.
    join = ((sl(start, 1, None) == sl(idx, 1, None)) & (sl(K, 1, None) != 0)
            & (sl(K, 1, None) == sl(K, 0, -1)) & (sl(o0, 1, None) == sl(o0, 0, -1))
            & (sl(oext, 1, None) == sl(oext, 0, -1)))
    first = start == idx
    sl(first, 1, None)[...] &= ~join
    nstart = np.maximum.accumulate(np.where(first, idx, np.int16(0)), axis=axis)
    # End of the merged chain: the last cell before the next chain start.
    flip = (slice(None), slice(None), slice(None, None, -1)) if axis == 2 else \
        (slice(None), slice(None, None, -1), slice(None))
    nxt = np.minimum.accumulate(np.where(first, idx, np.int16(n))[flip], axis=axis)[flip]
    end = np.full(K.shape, n, np.int16)
    sl(end, 0, -1)[...] = sl(nxt, 1, None)
    if axis == 2:
        return v0, nstart, h, end - nstart
    return nstart, u0, end - nstart, w


def _emit(K, v0, u0, h, w):
    S, V, U = K.shape
    iv = np.arange(V)[:, None]
    iu = np.arange(U)[None, :]
    s, v, u = np.nonzero((K != 0) & (v0 == iv) & (u0 == iu))
    return s, v, u, h[s, v, u], w[s, v, u]


def _merged(T, lab):
    """Merge labelled cells along rows, then columns, and emit the quads."""
    lab = _merge(T, *lab, axis=2)
    return _emit(T, *_merge(T, *lab, axis=1))


def lines(K):
    T, back = _tiles(K)
    return back(*_merged(T, _label_unit(T)))


def _squares_labels(T):
    """Each cell -> the largest complete aligned block (1×1, 2×1, 2×2, …, 8×8) holding it.
    A block is complete when both halves are complete and carry the same key."""
    n = T.shape[0]
    v0, u0, h, w = _label_unit(T)
    key = T.copy()                      # key of complete blocks at the current level, else 0
    bh, bw = 1, 1
    while bh < TILE or bw < TILE:
        if bw <= bh:
            nbh, nbw = bh, 2 * bw
        else:
            nbh, nbw = 2 * bh, bw
        # key per block at the current level, shape (n, TILE/bh, TILE/bw)
        kb = key.reshape(n, TILE // bh, bh, TILE // bw, bw)[:, :, 0, :, 0]
        if nbw > bw:
            a, b = kb[:, :, 0::2], kb[:, :, 1::2]
        else:
            a, b = kb[:, 0::2, :], kb[:, 1::2, :]
        kn = np.where((a == b) & (a != 0), a, 0)
        full = np.repeat(np.repeat(kn, nbh, axis=1), nbw, axis=2)
        ok = full != 0
        iv = np.arange(TILE)[:, None] // nbh * nbh
        iu = np.arange(TILE)[None, :] // nbw * nbw
        v0 = np.where(ok, iv, v0)
        u0 = np.where(ok, iu, u0)
        h = np.where(ok, nbh, h)
        w = np.where(ok, nbw, w)
        key, bh, bw = full, nbh, nbw
    return v0, u0, h, w


def squares(K):
    T, back = _tiles(K)
    return back(*_emit(T, *_squares_labels(T)))


def squares_ext(K):
    T, back = _tiles(K)
    return back(*_merged(T, _squares_labels(T)))


def greedy(K):
    """Row by row on the compact list of non-empty cells (sorted by row, slice, column):
    an open rectangle continues while the cells under it are one same-key run segment;
    the cells no continuing rectangle covers start maximal new runs."""
    S, V, U = K.shape
    if K.size == 0:
        return _empty()
    v_all, s_all, u_all = np.nonzero(K.transpose(1, 0, 2))      # C order: by v, s, u
    key_all = K[s_all, v_all, u_all]
    pos_all = s_all * (U + 1) + u_all        # +1: no run crosses into the next slice
    bounds = np.searchsorted(v_all, np.arange(V + 1))
    o_pos = o_w = o_key = o_row = np.zeros(0, np.int64)   # open rectangles, by o_pos
    out = []
    for v in range(V + 1):
        if v < V:
            a, b = bounds[v], bounds[v + 1]
            p, k = pos_all[a:b], key_all[a:b]
        else:
            p = k = np.zeros(0, np.int64)
        n = len(p)
        # segments: maximal runs of consecutive cells with one key
        brk = np.ones(n, bool)
        brk[1:] = (p[1:] != p[:-1] + 1) | (k[1:] != k[:-1])
        seg = np.cumsum(brk)
        i0 = np.searchsorted(p, o_pos)
        i1 = i0 + o_w - 1
        ok = i1 < n
        j0, j1 = np.minimum(i0, n - 1), np.minimum(i1, n - 1)
        if n:
            ok &= (p[j0] == o_pos) & (k[j0] == o_key) & (seg[j0] == seg[j1]) & (p[j1] == o_pos + o_w - 1)
        else:
            ok[:] = False
        done = ~ok
        out.append((o_pos[done], o_row[done], v - o_row[done], o_w[done]))
        o_pos, o_w, o_key, o_row, i0 = o_pos[ok], o_w[ok], o_key[ok], o_row[ok], i0[ok]
        if v == V:
            break
        cov = np.zeros(n + 1, np.int64)
        np.add.at(cov, i0, 1)
        np.add.at(cov, i0 + o_w, -1)
        free = np.cumsum(cov[:-1]) == 0
        prev_free = np.zeros(n, bool)
        prev_free[1:] = free[:-1]
        start = free & (brk | ~prev_free)
        lab = np.cumsum(start) - 1
        ns = np.flatnonzero(start)
        w = np.bincount(lab[free], minlength=len(ns))
        o_pos = np.concatenate([o_pos, p[ns]])
        o_w = np.concatenate([o_w, w])
        o_key = np.concatenate([o_key, k[ns]])
        o_row = np.concatenate([o_row, np.full(len(ns), v)])
        order = np.argsort(o_pos, kind="stable")
        o_pos, o_w, o_key, o_row = o_pos[order], o_w[order], o_key[order], o_row[order]
    pos, row, h, w = (np.concatenate(c) for c in zip(*out))
    s, u = np.divmod(pos, U + 1)
    return s, row, u, h, w


METHODS = {"none": none, "lines": lines, "squares": squares, "squares_ext": squares_ext,
           "greedy": greedy}
