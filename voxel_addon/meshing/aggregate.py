"""Face aggregation on stacks of 2D face maps (thesis §5.3.3, fig. 5.9).

Input is a key array K of shape (S, V, U): S independent slices, V rows, U columns;
K == 0 means "no face", equal non-zero keys may merge. Output is rectangles as int
arrays (s, v, u, h, w) (h rows × w columns). The thesis's methods work inside aligned
8×8 tiles (its compute-shader work group); tiles are turned into extra slices so one
code path serves all. `greedy` is unbounded: row-by-row, a rectangle keeps growing
down while every cell under it has its key; free cells start new maximal runs (this is
exactly Mikola's scan-order greedy, which the OpenCL kernel runs sequentially).
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
    """(S,V,U) -> (S*TV*TU, 8, 8) tiles, plus a function mapping tile rects back."""
    S, V, U = K.shape
    TV, TU = -(-V // TILE), -(-U // TILE)
    P = np.zeros((S, TV * TILE, TU * TILE), K.dtype)
    P[:, :V, :U] = K
    T = P.reshape(S, TV, TILE, TU, TILE).transpose(0, 1, 3, 2, 4).reshape(-1, TILE, TILE)

    def back(s, v, u, h, w):
        ss, rest = np.divmod(s, TV * TU)
        tv, tu = np.divmod(rest, TU)
        return ss, tv * TILE + v, tu * TILE + u, h, w
    return T, back


def _label_unit(K):
    """Per-cell rectangle description for the all-1×1 partition."""
    S, V, U = K.shape
    u0 = np.broadcast_to(np.arange(U), K.shape).copy()
    v0 = np.broadcast_to(np.arange(V)[:, None], K.shape).copy()
    one = np.ones(K.shape, np.int64)
    return v0, u0, one, one.copy()


def _merge(K, v0, u0, h, w, axis):
    """Merge chains of neighbouring rectangles that share the full edge across `axis`
    (2 = along u: same v0 and h; 1 = along v: same u0 and w) and the same key."""
    pos = np.arange(K.shape[axis]).reshape((-1, 1) if axis == 1 else (1, -1))
    start, ext = (u0, w) if axis == 2 else (v0, h)
    o0, oext = (v0, h) if axis == 2 else (u0, w)

    def prev(a):
        return np.take(a, range(0, a.shape[axis] - 1), axis=axis)

    def cur(a):
        return np.take(a, range(1, a.shape[axis]), axis=axis)
    idx = np.broadcast_to(pos, K.shape)
    # Only a cell that starts its rectangle can join the one before it.
    join = ((cur(start) == cur(idx)) & (cur(K) != 0) & (cur(K) == prev(K))
            & (cur(o0) == prev(o0)) & (cur(oext) == prev(oext)))
    first = start == idx
    if axis == 2:
        first[:, :, 1:] &= ~join
    else:
        first[:, 1:, :] &= ~join
    nstart = np.maximum.accumulate(np.where(first, idx, 0), axis=axis)
    # End of the merged chain: the last cell before the next chain start.
    n = K.shape[axis]
    nxt = np.flip(np.minimum.accumulate(np.flip(np.where(first, idx, n), axis=axis), axis=axis),
                  axis=axis)
    nxt = np.concatenate([np.take(nxt, range(1, n), axis=axis),
                          np.full(np.take(nxt, [0], axis=axis).shape, n)], axis=axis)
    if axis == 2:
        return v0, nstart, h, nxt - nstart
    return nstart, u0, nxt - nstart, w


def _emit(K, v0, u0, h, w):
    S, V, U = K.shape
    iv = np.arange(V)[:, None]
    iu = np.arange(U)[None, :]
    s, v, u = np.nonzero((K != 0) & (v0 == iv) & (u0 == iu))
    return s, v, u, h[s, v, u], w[s, v, u]


def lines(K):
    T, back = _tiles(K)
    lab = _label_unit(T)
    lab = _merge(T, *lab, axis=2)
    lab = _merge(T, *lab, axis=1)
    return back(*_emit(T, *lab))


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
    lab = _squares_labels(T)
    lab = _merge(T, *lab, axis=2)
    lab = _merge(T, *lab, axis=1)
    return back(*_emit(T, *lab))


def greedy(K):
    S, V, U = K.shape
    if K.size == 0:
        return _empty()
    K = K.astype(np.int64)
    iu = np.arange(U)
    ostart = np.full((S, U), -1)       # open rectangle covering the cell: start column
    olen = np.zeros((S, U), np.int64)
    orow = np.zeros((S, U), np.int64)
    okey = np.zeros((S, U), np.int64)
    out = []

    def emit(mask, r):
        s, u = np.nonzero(mask & (ostart == iu))
        out.append((s, orow[s, u], u, r - orow[s, u], olen[s, u]))

    for r in range(V):
        k = K[:, r, :]
        isopen = ostart >= 0
        bad = isopen & (k != okey)
        c = np.zeros((S, U + 1), np.int64)
        np.cumsum(bad, axis=1, out=c[:, 1:])
        st = np.where(isopen, ostart, 0)
        rows = np.arange(S)[:, None]
        cont = isopen & (c[rows, st + olen] == c[rows, st])
        emit(isopen & ~cont, r)
        ostart[~cont] = -1
        free = ~cont & (k != 0)
        pf = np.zeros((S, U), bool)
        pf[:, 1:] = free[:, :-1] & free[:, 1:] & (k[:, :-1] == k[:, 1:])
        first = free & ~pf
        start = np.maximum.accumulate(np.where(first, iu, 0), axis=1)
        nf = np.zeros((S, U), bool)
        nf[:, :-1] = pf[:, 1:]
        last = free & ~nf
        end = np.flip(np.minimum.accumulate(np.flip(np.where(last, iu, U), axis=1), axis=1), axis=1)
        ostart = np.where(free, start, ostart)
        olen = np.where(free, end - start + 1, olen)
        orow = np.where(free, r, orow)
        okey = np.where(free, k, okey)
    emit(ostart >= 0, V)
    return tuple(np.concatenate(a) for a in zip(*out))


METHODS = {"none": none, "lines": lines, "squares": squares, "squares_ext": squares_ext,
           "greedy": greedy}
