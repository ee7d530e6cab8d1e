"""One Minecraft chunk's sections -> a world chunk's blocks and data: palette entries
mapped once per palette (by its bytes), 4-bit sections through lookup tables of
byte pairs, the rest by index (formats/minecraft.py's import and the cluster's
workers)."""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from . import anvil

PAIRS = 1024   # 4-bit sections' lookup tables (1 KiB each) convert keeps


def convert(ch: anvil.Chunk, y_min: int, pal, blank=C.empty):
    """(blocks, data or None, dropped voxels) of one chunk in world axes; PAL (the
    import's minecraft._Palettes, or a cluster worker's twin): `pal.settle`
    sees every palette entry's (block id, data, voxels) before data is written and
    gives the data stored as 0 per block id (its default state, mcstate.States).
    `blank()`: a zeroed chunk array (C.empty, or one of arrays used before)."""
    blocks, data, dropped = blank(), None, 0
    counts = pal.report.blocks
    keyed = pal.keyed   # a palette's bytes -> its entries' ids, values and report rows
    ids_l, vals_l, n_l, secs, four, packed = [], [], [], [], [], []
    for s in ch.sections:
        start = len(ids_l)
        got = keyed.get(s.key) if s.key is not None else None
        if got is None:
            got = [pal.of(name, p) for name, p in zip(s.palette, s.props or [None] * len(s.palette))]
            got = ([g[0] for g in got], [g[1] for g in got], [counts[n] for n in s.palette])
            if s.key is not None:
                keyed[s.key] = got
        ids, vals, rows = got
        if s.indices is None and s.nib is None and len(s.palette) == 1:   # often all air
            rows[0][2] += 4096
            ids_l.append(ids[0])
            vals_l.append(vals[0])
            n_l.append(4096)
            secs.append((s, start, start + 1, None))
            continue
        ids_l += ids
        vals_l += vals
        if s.nib is not None:
            packed.append((s, start, len(ids_l)))
        if s.counts is not None:
            n = s.counts
        elif s.indices is not None:
            n = np.bincount(s.indices, minlength=len(s.palette))
        else:
            n = np.array([4096] + [0] * (len(s.palette) - 1))
        nl = n.tolist()
        for row, k in zip(rows, nl):
            row[2] += k
        n_l += nl
        secs.append((s, start, len(ids_l), n))
    if not secs:
        return blocks, data, dropped
    ids_a, vals_a = np.array(ids_l, np.uint16), np.array(vals_l, np.uint16)
    dflt = pal.settle(ids_a, vals_a, np.array(n_l))
    vals_a[vals_a == dflt[ids_a]] = 0                   # a block's default state: 0
    idl, vall = ids_l, vals_a.tolist()   # Python ints: no NumPy scalars per section
    for s, i, j, n in secs:
        z0 = 16 * s.y - y_min
        lo, hi = max(z0, 0), min(z0 + 16, C.HEIGHT)
        if lo >= hi:
            dropped += (4096 if idl[i] else 0) if n is None else int(n[ids_a[i:j] != 0].sum())
            continue
        if s.indices is None and s.nib is None:
            if idl[i]:
                blocks[:, :, lo:hi] = idl[i]
            if vall[i]:
                if data is None:
                    data = blank()
                data[:, :, lo:hi] = vall[i]
            continue
        ids = ids_a[i:j]
        if s.nib is not None and hi - lo == 16:
            four.append((s, i, j))
            continue
        idx = s.indices if s.indices is not None else anvil.nibbles(s.nib)
        # indices are [y][15 - z][x] (anvil): blocks is x-fastest, so its .T is
        # [y][15 - z][x] in C order and take writes it in place (no gather, no temporary)
        sec = idx.reshape(16, 16, 16)[lo - z0:hi - z0]
        ids.take(sec, out=blocks.T[lo:hi], mode="clip")   # indices checked by anvil
        if any(vall[i:j]):
            if data is None:
                data = blank()
            vals_a[i:j].take(sec, out=data.T[lo:hi], mode="clip")
        if hi - lo < 16:
            outside = np.ones(16, bool)
            outside[lo - z0:hi - z0] = False
            cut = idx.reshape(16, 4096 // 16)[outside].ravel()
            dropped += int((ids != 0)[cut].sum())
    if four:
        data = _four(four, packed, ch.nibs, y_min, blocks, data, ids_a, vals_a, vall, keyed, blank)
    return blocks, data, dropped


def _four(four, packed, nibs, y_min, blocks, data, ids_a, vals_a, vall, keyed, blank=C.empty):
    """The packed 4-bit sections (`packed`; `four`: those whole inside the world's
    height) of a chunk: two voxels a byte, so each byte looks up its two block ids
    (data values) as one 32-bit word, in a table of 256 per section (the ids' kept
    by palette) at 256 * the section's place (Section.nib): all sections in one take,
    written into the layers (x fastest, z-flipped rows, as anvil._flip)."""
    n = len(four)
    at = nibs if n == len(packed) else np.stack([s.nib for s, _, _ in four])
    memo = keyed.get(None)   # (palette bytes, values) -> their table; bounded
    if memo is None or len(memo) > PAIRS:
        memo = keyed[None] = {}
    tabs = [_table(memo, s.key, ids_a[i:j]) for s, i, j in packed]
    ys = [s.y for s, _, _ in four]
    run = ys == list(range(ys[0], ys[0] + n))   # consecutive: straight into the layers
    z0 = 16 * ys[0] - y_min
    out = blocks.T[z0:z0 + 16 * n].view(np.uint32).reshape(n, 16, 16, 8) if run else None
    got = (tabs[0] if len(tabs) == 1 else np.concatenate(tabs)).take(at, out=out, mode="clip")
    if not run:
        _place(got, ys, y_min, blocks)
    if any(any(vall[i:j]) for _, i, j in four):
        if data is None:
            data = blank()
        tab = np.concatenate([_table(memo, s.key, vals_a[i:j], vall[i:j]) for s, i, j in packed])
        out = data.T[z0:z0 + 16 * n].view(np.uint32).reshape(n, 16, 16, 8) if run else None
        got = tab.take(at, out=out, mode="clip")
        if not run:
            _place(got, ys, y_min, data)
    return data


def _place(words, ys, y_min, arr):
    for w, y in zip(words, ys):
        z0 = 16 * y - y_min
        arr.T[z0:z0 + 16].view(np.uint32)[...] = w.reshape(16, 16, 8)


def _table(memo, key, vals, vl=None):
    """_pairs(vals), remembered by the palette's bytes (and the values, for data)."""
    if key is None:
        return _pairs(vals)
    k = key if vl is None else (key, tuple(vl))
    got = memo.get(k)
    if got is None:
        got = memo[k] = _pairs(vals)
    return got


def _pairs(vals: np.ndarray) -> np.ndarray:
    """(256,) words: byte b's two uint16 values vals[b & 15], vals[b >> 4] in memory
    order (the byte's low index is the lower x)."""
    v = np.zeros(16, np.uint16)
    v[:len(vals)] = vals
    out = np.empty((16, 16, 2), np.uint16)
    out[:, :, 0] = v[None, :]
    out[:, :, 1] = v[:, None]
    return out.view(np.uint32).reshape(256)
