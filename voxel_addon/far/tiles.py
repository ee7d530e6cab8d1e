"""Making a far tile's samples: from stored chunks where the file has them (their
column summaries, edits included), from the generator's 2D passes elsewhere, then
raised by the user's edits in each sample's cell (a tower between samples shows).

A tile's arrays ((N, N), indexed [kx, ky], grid.columns gives the block columns):
    height  int16   top ground block z (-1: none), core.surface
    top     uint16  that block's id
    water   int16   water surface z above the ground (-1: none)
    trees   uint8   canopy cover of the cell, 0..255
"""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from ..core import surface
from . import grid

NAMES = ("height", "top", "water", "trees")


def summary(blocks: np.ndarray) -> dict:
    """A chunk's column summary: core.surface.columns as a 16 x 16 far array set
    (trees: 255 where a crown is the column's top, else 0)."""
    col = surface.columns(blocks)
    return {"height": col["height"].astype(np.int16), "top": col["top"].astype(np.uint16),
            "water": col["water"].astype(np.int16),
            "trees": np.where(col["tree"], 255, 0).astype(np.uint8)}


def empty(n: int = grid.N) -> dict:
    return {"height": np.full((n, n), -1, np.int16), "top": np.zeros((n, n), np.uint16),
            "water": np.full((n, n), -1, np.int16), "trees": np.zeros((n, n), np.uint8)}


def build(key, store, generator, read_chunk) -> tuple[dict, int]:
    """The samples of tile `key` and how many came from stored chunks.
    store: storage.far.FarStore; read_chunk(key) -> blocks or None (a missing or
    damaged chunk: then the generator answers for it)."""
    return build_many([key], store, generator, read_chunk)[0]


def build_many(keys, store, generator, read_chunk) -> list[tuple[dict, int]]:
    """build() for several tiles, the generator asked once for the columns no stored
    chunk has in any of them: fewer, larger NumPy steps (a tile's ~1200 columns are
    small arrays for the 2D passes; far terrain's CPU, issue 28). Same values."""
    done = [_from_chunks(k, store, read_chunk) for k in keys]
    xy = np.concatenate([np.stack([X[~m], Y[~m]], -1) for _, m, X, Y in done])
    got = generator.surface(xy) if len(xy) else None
    i = 0
    for key, (out, m, X, Y) in zip(keys, done):
        rest = ~m
        n = int(rest.sum())
        if got is not None and n:
            part = {k: v[i:i + n] for k, v in got.items()}
            out["height"][rest] = part["height"]
            out["top"][rest] = part["top"]
            out["water"][rest] = part["water"]
            out["trees"][rest] = np.rint(np.clip(part["trees"], 0, 1) * 255).astype(np.uint8)
        i += n
        raise_edits(key, out, store)
    return [(out, int(m.sum())) for out, m, _, _ in done]


def _from_chunks(key, store, read_chunk):
    """(samples, mask of those from stored chunks, X, Y) of tile `key`."""
    level = key[0]
    s = grid.spacing(level)
    X, Y = grid.columns(key)
    out = empty()
    ck = np.stack([X >> 4, Y >> 4], -1)
    have = store.chunks_in(int(ck[..., 0].min()), int(ck[..., 1].min()),
                           int(ck[..., 0].max()), int(ck[..., 1].max()))
    from_chunks = np.zeros(X.size, bool)
    if have:
        cell = min(s, C.SIZE)  # the cover of a cell wider than a chunk: its first chunk's part
        keys, inv = np.unique(ck.reshape(-1, 2), axis=0, return_inverse=True)
        inv = inv.reshape(-1)
        order = np.argsort(inv, kind="stable")
        bounds = np.searchsorted(inv[order], np.arange(len(keys) + 1))
        xs, ys = X.reshape(-1) & 15, Y.reshape(-1) & 15
        flat = {n: out[n].reshape(-1) for n in NAMES}
        new = []
        for i, k in enumerate(map(tuple, keys.tolist())):
            if k not in have:
                continue
            col = store.columns(k)
            if col is None:
                blocks = read_chunk(k)
                if blocks is None:
                    continue
                col = summary(blocks)
                new.append((k, col))
            m = order[bounds[i]:bounds[i + 1]]
            lx, ly = xs[m], ys[m]
            for name in ("height", "top", "water"):
                flat[name][m] = col[name][lx, ly]
            cov = col["trees"].astype(np.float32).reshape(C.SIZE // cell, cell,
                                                          C.SIZE // cell, cell).mean(axis=(1, 3))
            flat["trees"][m] = np.rint(cov[lx // cell, ly // cell]).astype(np.uint8)
            from_chunks[m] = True
        store.put_columns(new)
    return out, from_chunks.reshape(X.shape), X, Y


def raise_edits(key, out: dict, store) -> None:
    """Ground blocks the user placed above a cell's sample raise the sample to the
    highest of them (its block on top): a one-block tower anywhere in the cell
    shows. Edits below the sample's ground (digging, ore) are not drawn from far."""
    s = grid.spacing(key[0])
    x0, y0 = grid.origin(key)
    bx0, by0 = x0 - s, y0 - s  # the cells of the border samples count too
    e = store.edits(bx0, by0, bx0 + grid.N * s, by0 + grid.N * s)
    e = e[surface.CLASS[e[:, 3]] == surface.GROUND] if len(e) else e
    if not len(e):
        return
    kx, ky, z = (e[:, 0] - bx0) // s, (e[:, 1] - by0) // s, e[:, 2]
    best = np.full((grid.N, grid.N), -1, np.int64)
    np.maximum.at(best, (kx, ky), z)
    blk = np.zeros((grid.N, grid.N), np.int64)
    on = z == best[kx, ky]
    blk[kx[on], ky[on]] = e[on, 3]
    up = best > out["height"]
    out["height"][up] = best[up]
    out["top"][up] = blk[up]
    out["water"][up & (out["water"] <= best)] = -1

