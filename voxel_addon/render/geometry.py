"""Render regions on the GPU (thesis §5.3.2, §5.3.4) with what every device has: no
multi-draw, no indirect draws, no storage buffers, no partial buffer updates (Blender's
gpu module offers none of them).

Chunks are grouped into batches of BATCH x BATCH chunks. Per batch and pass one vertex
buffer holds the quads of its chunks ordered region by region (chunks within a
region), each vertex with a word saying where its region lies in the batch
(shaders/block.vert). A changed chunk marks its batch; the batch is built again (its
chunks' vertices gathered, one upload per pass) when the next frame is prepared, so
many changes in one frame cost one build.

Culling is on the CPU, as fine as the thesis's: one NumPy product tests every
(chunk, region) box against the clip planes (camera.visible_boxes); the visible rows
of a batch that follow each other in its vertex order are one range and one draw.
At distance 16 (~81 batches) a frame draws a few hundred ranges over all passes
instead of thousands of per-chunk draws.
"""
from __future__ import annotations

from collections.abc import MutableMapping

import numpy as np

from .. import meshing
from . import camera

PASSES = meshing.PASSES  # opaque, cutout (leaves), cutout2 (double-sided plants), blend
BATCH = 4                # chunks per side of a batch (the origin word has 2 bits per axis)


class _Batch:
    __slots__ = ("key", "meshes", "rows", "origin")

    def __init__(self, key):
        self.key = key
        self.meshes = [None] * len(PASSES)  # per pass: the device's vertex buffer
        self.rows = [[] for _ in PASSES]    # per pass: (first quad, quads, chunk, region)
        self.origin = (0.0, 0.0, 0.0, 0.0)  # in vertex order


class Geometry:
    def __init__(self, dev):
        self.dev = dev
        self.chunks: dict = {}     # (cx, cy) -> meshing.ChunkMesh
        self.region_h = meshing.REGION_H
        self.nreg = 256 // self.region_h
        self._batches: dict = {}   # (bx, by) -> _Batch
        self._dirty: set = set()
        self.gen = 0               # changes of the shown chunks
        self._table()

    @property
    def keys(self):
        """The shown chunks."""
        return self.chunks.keys()

    # ------------------------------------------------------------------ chunks
    def set_chunks(self, meshes: dict) -> None:
        """meshes: {(cx, cy): meshing.ChunkMesh}. Replaces what was shown."""
        self.remove([k for k in self.chunks if k not in meshes])
        self.update(meshes)

    def update(self, meshes: dict) -> None:
        """Show or replace these chunks ({(cx, cy): ChunkMesh}); their batches are
        built again when the next frame is prepared."""
        meshes = {(int(k[0]), int(k[1])): m for k, m in meshes.items()}
        if not meshes:
            return
        hs = {m.region_h for m in meshes.values()}
        if len(hs) > 1 or (self.chunks and hs != {self.region_h}):
            raise ValueError("all shown chunks must share one region height")
        if not self.chunks:  # empty: start over at this height
            self.region_h = hs.pop()
            self.nreg = 256 // self.region_h
        self.chunks.update(meshes)
        self._dirty.update(_batch_of(k) for k in meshes)
        self.gen += 1

    def remove(self, keys) -> None:
        """Stop showing these chunks (unknown keys are ignored)."""
        keys = [k for k in ((int(k[0]), int(k[1])) for k in keys) if k in self.chunks]
        for k in keys:
            del self.chunks[k]
            self._dirty.add(_batch_of(k))
        if keys:
            self.gen += 1

    def bounds(self):
        """(cx0, cy0, cx1, cy1): the box of the shown chunks, or None."""
        if not self.chunks:
            return None
        k = np.array(list(self.chunks))
        lo, hi = k.min(0), k.max(0) + 1
        return int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])

    # ------------------------------------------------------------------ batches
    def commit(self) -> None:
        """Build the batches that changed (before a frame culls)."""
        if not self._dirty:
            return
        for key in self._dirty:
            self._build(key)
        self._dirty.clear()
        self._table()

    def _build(self, key) -> None:
        b = self._batches.pop(key, None)
        if b is not None:
            self.dev.release(*b.meshes)
        bx, by = key
        inside = sorted(k for k in ((bx * BATCH + i, by * BATCH + j)
                                    for j in range(BATCH) for i in range(BATCH))
                        if k in self.chunks)
        if not inside:
            return
        b = _Batch(key)
        nreg, npass = self.nreg, len(PASSES)
        ms = [self.chunks[k] for k in inside]
        ranges = np.stack([m.ranges for m in ms])        # (chunks, regions, passes, 2)
        code = np.array([(k[0] - bx * BATCH) | (k[1] - by * BATCH) << 2 for k in inside], np.uint32)
        for p in range(npass):
            counts = ranges[:, :, p, 1]                   # (chunks, regions) vertices
            if not counts.any():
                continue
            parts, words, tints, q = [], [], [], 0
            for r in range(nreg):  # region by region (visible neighbours: one range)
                for c in np.flatnonzero(counts[:, r]):
                    f, n = ranges[c, r, p]
                    parts.append(ms[c].vertices[f:f + n])
                    words.append((n, code[c] | np.uint32(r << 4)))
                    b.rows[p].append((q, int(n) // 4, inside[c], r))
                    q += int(n) // 4
                    cols = getattr(ms[c], "colors", None)  # `color` blocks' palette index
                    if cols is not None:
                        tints.append((len(parts) - 1, cols[f:f + n]))
            w = np.empty((int(counts.sum()), 2), np.uint32)
            w[:, 0] = np.concatenate(parts)
            w[:, 1] = np.repeat([c for _, c in words], [n for n, _ in words])
            if tints:
                at = np.cumsum([0] + [len(x) for x in parts])
                for i, cols in tints:
                    w[at[i]:at[i + 1], 1] |= cols.astype(np.uint32) << 16
            b.meshes[p] = self.dev.mesh(w)
        b.origin = (float(bx * BATCH * 16), float(by * BATCH * 16), 0.0, float(self.region_h))
        if any(b.rows):
            self._batches[key] = b

    def _table(self) -> None:
        """The arrays a frame culls and draws with: the (chunk, region) boxes, and per
        pass every batch's rows in vertex order (batch, first quad, quads, box)."""
        self._list = list(self._batches.values())
        nreg, h = self.nreg, self.region_h
        keys = sorted({row[2] for b in self._list for rows in b.rows for row in rows})
        index = {k: i for i, k in enumerate(keys)}
        lo = np.zeros((len(keys), nreg, 3))
        lo[:, :, :2] = (np.array(keys, np.float64).reshape(-1, 1, 2) * 16) if keys else 0.0
        lo[..., 2] = np.arange(nreg) * h
        hi = lo + [16.0, 16.0, h]
        self._rows = []
        for p in range(len(PASSES)):
            t = [(i, q, n, index[k] * nreg + r) for i, b in enumerate(self._list)
                 for q, n, k, r in b.rows[p]]
            self._rows.append(np.array(t, np.int64).reshape(-1, 4).T if t else None)
        # only the boxes of regions with quads (a half or less of all: the air above
        # the ground, issue 29: culling reads a half as much), numbered anew
        used = np.unique(np.concatenate([t[3] for t in self._rows if t is not None] or
                                        [np.zeros(0, np.int64)]))
        new = np.zeros(len(keys) * nreg, np.int64)
        new[used] = np.arange(len(used))
        for t in self._rows:
            if t is not None:
                t[3] = new[t[3]]
        # 0.5 slack for waving: vertices move by < 0.1 blocks
        self._boxes = camera.boxes(lo.reshape(-1, 3)[used] - 0.5, hi.reshape(-1, 3)[used] + 0.5)
        # every pass's rows in one table, so a frame's draw lists are one set of NumPy
        # calls (issue 29): per row its batch among all passes' (pass * batches +
        # batch), first quad, quads, box, whether the row before / after it is the
        # same batch's (a run of visible rows within a batch is one draw), its pass
        nl = len(self._list)
        tabs = [np.vstack([t[:1] + p * nl, t[1:], np.full((1, t.shape[1]), p)])
                for p, t in enumerate(self._rows) if t is not None]
        gb, q, n, box, pi = np.concatenate(tabs, 1) if tabs else np.zeros((5, 0), np.int64)
        nb = np.ones(len(gb) + 1, bool)
        nb[1:-1] = gb[1:] != gb[:-1]
        # per row its box's centre and, as a fourth coordinate far beyond any distance
        # in blocks, its pass: a row's squared distance from (eye, 0) sorts by pass first
        mid = np.empty((len(gb), 4))
        mid[:, :3] = self._boxes[:3, box].T
        mid[:, 3] = pi * 1e6
        self._all = (gb, q, n, box, ~nb[:-1], ~nb[1:], mid)
        self._bq, self._end = np.vstack([gb, q]), q + n  # (a range's batch, first quad; its end)
        self._join = np.zeros(len(gb) + 1, bool)  # batches' scratch: J[i], row i joins i - 1
        self._cut = np.cumsum([0] + [0 if t is None else t.shape[1] for t in self._rows])
        self._meshes = [b.meshes[p] for p in range(len(PASSES)) for b in self._list]
        self._origins = [b.origin for _ in PASSES for b in self._list]
        self._last: dict = {}
        self._culled: dict = {}
        self._rects: dict = {}

    # ------------------------------------------------------------------ frames
    def cull(self, mvp: np.ndarray, keep: bool = False) -> np.ndarray:
        """(chunk, region) boxes: whether each may intersect the clip volume (read
        only). keep: the answers of the last few matrices are kept until the shown
        chunks change (a still view's redraws, the shadow map's light while the sun
        rests)."""
        if not keep:
            return camera.visible_boxes(mvp, self._boxes)
        k = np.asarray(mvp, np.float64).tobytes()
        c = self._culled
        v = c.get(k)
        if v is None:
            if len(c) >= 4:
                c.clear()
            v = c[k] = camera.visible_boxes(mvp, self._boxes)
        return v

    def _rect(self, p: int):
        """The horizontal extent of pass p's rows' boxes as (x0, -x1, y0, -y1) rows of
        one (4, n) array (kept)."""
        r = self._rects.get(p)
        if r is None:
            c = self._boxes[:, self._all[3][self._cut[p]:self._cut[p + 1]]]
            r = self._rects[p] = np.array((c[0] - c[3], -(c[0] + c[3]), c[1] - c[4], -(c[1] + c[4])))
        return r

    def seen(self, name: str, vis: np.ndarray) -> bool:
        """Whether pass name has quads in a visible region."""
        t = self._rows[PASSES.index(name)]
        return t is not None and bool(vis[t[3]].any())

    def batches(self, vis: np.ndarray, names, slot: str = "view", eye=None,
                reach: dict | None = None) -> dict:
        """{pass name: [(mesh, first quad, quads, origin)] or None} for the culling of
        cull(): a batch's visible rows that follow each other in its vertex order are
        one range. eye: each pass's ranges nearest first (by the box of their first
        row), so hidden surfaces fail the depth test before they are shaded (software
        GL's early depth test: caves and the ground behind a hill); else in vertex
        order (regions bottom up, caves first). reach: {pass name: blocks}: that
        pass's rows only where their box comes within so far of the eye
        (horizontally)."""
        key = (tuple(names), tuple(reach.items()) if reach else None)
        if reach:
            eye = tuple(map(float, eye))
        last = self._last.get(slot)
        if last is not None and last[0] == key and np.array_equal(last[1], vis) and \
                (not reach or last[3] == eye):
            return last[2]
        _, _, _, box, same_prev, _, mid = self._all
        v = vis[box]
        for name, r in (reach or {}).items():
            p = PASSES.index(name)
            a, b = self._cut[p], self._cut[p + 1]
            if a < b:
                # (x0 - x, x - x1, y0 - y, y - y1), at least 0: of each pair one is 0, so
                # their sums are the distances along x and y (in fewer NumPy calls)
                d = self._rect(p) - np.array((eye[0], -eye[0], eye[1], -eye[1]))[:, None]
                np.maximum(d, 0.0, out=d)
                d = d.reshape(2, 2, -1).sum(1)
                v[a:b] &= (d * d).sum(0) <= r * r
        # J[i]: row i continues row i - 1's range (both visible, one batch's); J[0] and
        # J[-1] stay False. A range starts at a visible row that continues none, ends at
        # one that the next does not continue (few NumPy calls: issue 29)
        J = self._join
        np.logical_and(v[1:], v[:-1], out=J[1:-1])
        J[1:-1] &= same_prev[1:]
        starts = np.flatnonzero(v > J[:-1])
        ends = np.flatnonzero(v > J[1:])
        cut = np.searchsorted(starts, self._cut).tolist()  # each pass's first range
        if eye is not None and len(starts) > 1:
            d = mid[starts] - (*eye, 0.0)
            order = np.argsort(np.einsum("ij,ij->i", d, d))  # (within each pass)
            starts, ends = starts[order], ends[order]
        bs, fs = self._bq[:, starts].tolist()
        M, O = self._meshes, self._origins
        items = [(M[i], f, e - f, O[i]) for i, f, e in zip(bs, fs, self._end[ends].tolist())]
        out = {}
        for name in names:
            p = PASSES.index(name)
            out[name] = None if self._rows[p] is None else (items[cut[p]:cut[p + 1]] or None)
        self._last[slot] = (key, vis.copy(), out, eye)
        return out

    @property
    def quads(self) -> int:
        return int(sum(t[2].sum() for t in self._rows if t is not None))

    @property
    def nbytes(self) -> int:
        """GPU bytes of the vertex buffers (8 per vertex)."""
        return 32 * self.quads

    def release(self) -> None:
        for b in self._batches.values():
            self.dev.release(*b.meshes)
        self._batches.clear()
        self._dirty = set(_batch_of(k) for k in self.chunks)
        self._table()


def _batch_of(key):
    return key[0] // BATCH, key[1] // BATCH


def draw(dev, batches, stats: "Stats | None" = None, shadow: bool = False) -> None:
    """Draw one pass's batch list with the program in use (dev.use)."""
    if not batches:
        return
    tris = 0
    for mesh, first, n, origin in batches:
        dev.push({"batch_origin": origin})
        if first < 0:             # a triangle mesh of model quads (models.py): n triangles
            dev.draw_tris(mesh)
            tris += n
            continue
        dev.draw(mesh, first, n)
        tris += 2 * n
    if stats is not None:
        stats.add(tris, len(batches), shadow)


class Stats(MutableMapping):
    """A frame's counters: triangles, shadow_triangles, draw_calls (and what the
    renderer adds)."""

    def __init__(self):
        self._d = {"triangles": 0, "shadow_triangles": 0, "draw_calls": 0}

    def add(self, tris: int, calls: int, shadow: bool) -> None:
        d = self._d
        d["draw_calls"] += calls
        d["triangles"] += tris
        if shadow:
            d["shadow_triangles"] += tris

    def snapshot(self) -> dict:
        return dict(self._d)

    def __getitem__(self, key):
        return self._d[key]

    def __setitem__(self, key, value):
        self._d[key] = value

    def __delitem__(self, key):
        del self._d[key]

    def __iter__(self):
        return iter(self._d)

    def __len__(self):
        return len(self._d)

    def __repr__(self):
        return f"Stats({self._d!r})"
