"""Render regions on the GPU (thesis §5.3.2, §5.3.4): one vertex buffer of the meshing
package's 4-byte vertices for every shown chunk, a shared quad index pattern, frustum
culling per region and one multi-draw per pass.

Chunks come and go one at a time (`update`, `remove`): each has a slot, which owns
its rows of the region table (slot x region, with box and origin) and one block of
the vertex buffer (first fit in a free list; the buffer grows by copying on the GPU,
so the other chunks are never uploaded again). Every (region, pass) with faces has
one indirect command in its pass's command table; a removed chunk's commands become
empty holes that the next chunk reuses. `at` says where each table row's command of
each pass is. Commands reach their chunk's block through the base vertex, so the
shared index pattern only spans the largest chunk.

All passes share the region table, so a frame culls once per matrix (view, shadow)
for every pass; per matrix it gathers the commands of the visible rows only (work by
what is seen, not by the view distance) into one buffer, uploaded when it changed
since the same slot's last frame, and each pass draws its slice of it.

GL 4.3+: glMultiDrawElementsIndirect, the region origin comes from baseInstance
through an instanced attribute, and the culling runs on the GPU (`gpu_cull`,
shaders/cull.comp, the twin of camera.visible_boxes): a slot's buffer holds every
command and a compute pass sets each one's instance count to 1 or 0, so the CPU
neither culls nor gathers. GL 4.1 (macOS): CPU culling and one draw per visible
region with the origin as a uniform (moderngl draws those without a base vertex, so
there the index pattern spans the whole vertex buffer).
"""
from __future__ import annotations

from collections.abc import MutableMapping

import numpy as np

from .. import meshing
from . import camera

PASSES = meshing.PASSES  # opaque, cutout (leaves), cutout2 (double-sided plants), blend
_QUAD = 4 * meshing.BYTES_PER_VERTEX  # bytes of one quad's vertices


class _Free:
    """First-fit allocation of [start, start + n) ranges (in quads) with merging."""

    def __init__(self):
        self.holes: list[list[int]] = []  # sorted [start, size]
        self.end = 0                      # high-water mark

    def take(self, n: int) -> int:
        for i, h in enumerate(self.holes):
            if h[1] >= n:
                start = h[0]
                if h[1] == n:
                    del self.holes[i]
                else:
                    h[0] += n
                    h[1] -= n
                return start
        start, self.end = self.end, self.end + n
        return start

    def give(self, start: int, n: int) -> None:
        hs = self.holes
        i = 0
        while i < len(hs) and hs[i][0] < start:
            i += 1
        hs.insert(i, [start, n])
        if i + 1 < len(hs) and start + n == hs[i + 1][0]:  # merge with the next
            hs[i][1] += hs.pop(i + 1)[1]
        if i > 0 and hs[i - 1][0] + hs[i - 1][1] == start:  # and the previous
            hs[i - 1][1] += hs.pop(i)[1]
            i -= 1
        if hs[i][0] + hs[i][1] == self.end:  # the tail is free: lower the mark
            self.end = hs.pop(i)[0]


class Geometry:
    def __init__(self, ctx):
        self.ctx = ctx
        self.indirect_ok = ctx.version_code >= 430
        self.gpu_cull = True  # with indirect_ok (4.3 brings compute shaders); tests switch it
        self.frames = 0  # gpu_batches calls and changes: the command buffers' generation
        self.gen = 0     # changes of the shown chunks: cached batches are void
        self._cs = None
        self._reset()

    def _reset(self) -> None:
        self.region_h = meshing.REGION_H
        self.nreg = 256 // self.region_h
        self.slot_of: dict[tuple[int, int], int] = {}
        self._slots: list = []         # slot -> (key, vertex start, quads, [(pass, cmd)])
        self._free_slots: list[int] = []
        self._verts = _Free()
        self.vbo = self.ibo = self.obo = self._boxes = None
        self._vbo_q = self._ibo_q = 0  # capacities in quads
        self._most_q = 0               # quads of the largest chunk shown since the reset
        self._kxy = np.zeros((0, 2), np.int64)  # slot -> its key
        self._used = np.zeros(0, bool)
        self._rows_cap = 0             # rows in obo / _boxes
        self.origin = np.zeros((0, 3), np.float32)
        self.boxes = np.zeros((7, 0), np.float32)
        self._cmd = [np.zeros((0, 5), np.uint32) for _ in PASSES]  # per pass, local
        self._cused = [0] * len(PASSES)                             # high-water marks
        self._cfree: list[list[int]] = [[] for _ in PASSES]
        self._at = np.full((len(PASSES), 0), -1, np.int32)         # pass, row -> local
        self._vaos: dict = {}
        self.bufs: dict = {}  # slot -> [buffer, its commands, key, batches]
        self._commit()

    @property
    def keys(self):
        """The shown chunks."""
        return self.slot_of.keys()

    # ------------------------------------------------------------------ chunks
    def set_chunks(self, meshes: dict) -> None:
        """meshes: {(cx, cy): meshing.ChunkMesh}. Replaces what was shown."""
        self._free()
        self._reset()
        self.update(meshes)

    def update(self, meshes: dict) -> None:
        """Show or replace these chunks ({(cx, cy): ChunkMesh}); the others stay as
        they are on the GPU."""
        meshes = {(int(k[0]), int(k[1])): m for k, m in meshes.items()}
        if not meshes:
            return
        hs = {m.region_h for m in meshes.values()}
        if len(hs) > 1 or (self.slot_of and hs != {self.region_h}):
            raise ValueError("all shown chunks must share one region height")
        if not self.slot_of and hs != {self.region_h}:  # empty: start over at this height
            self._free()
            self._reset()
            self.region_h = hs.pop()
            self.nreg = 256 // self.region_h
        self._drop([k for k in meshes if k in self.slot_of])
        new = []
        for key, m in meshes.items():
            s = self._free_slots.pop() if self._free_slots else len(self._slots)
            if s == len(self._slots):
                self._slots.append(None)
            nq = len(m.vertices) // 4
            start = self._verts.take(nq) if nq else 0
            self._slots[s] = [key, start, nq, []]
            self.slot_of[key] = s
            new.append((s, m, start))
            self._most_q = max(self._most_q, nq)
        self._grow()
        nreg, h = self.nreg, self.region_h
        slots = np.array([s for s, _, _ in new])
        self._kxy[slots] = list(meshes)
        self._used[slots] = True
        rows = (slots[:, None] * nreg + np.arange(nreg)).ravel()
        o = self.origin
        o[rows, 0] = np.repeat(self._kxy[slots, 0] * 16, nreg)
        o[rows, 1] = np.repeat(self._kxy[slots, 1] * 16, nreg)
        o[rows, 2] = np.tile(np.arange(nreg) * h, len(slots))
        # 0.5 slack for waving: vertices move by < 0.1 blocks
        self.boxes[:, rows] = camera.boxes(o[rows] - 0.5, o[rows] + [16.5, 16.5, h + 0.5])
        for s, m, start in new:
            if len(m.vertices):
                self.vbo.write(np.ascontiguousarray(m.vertices, np.uint32), offset=start * _QUAD)
            rng = np.asarray(m.ranges)
            reg, ps = np.nonzero(rng[..., 1])
            cmds = self._slots[s][3]
            for r, p, first, count in zip(reg.tolist(), ps.tolist(),
                                          rng[reg, ps, 0].tolist(), rng[reg, ps, 1].tolist()):
                c = self._cfree[p].pop() if self._cfree[p] else self._new_cmd(p)
                # DrawElementsIndirectCommand: count, instances, first index (in the
                # chunk), base vertex (its block), base instance (= the region table
                # row: its origin and box)
                self._cmd[p][c] = (count // 4 * 6, 1, first // 4 * 6, 4 * start, s * nreg + r)
                self._at[p, s * nreg + r] = c
                cmds.append((p, c))
        self._write_rows(rows.min(), rows.max() + 1)
        self._commit()

    def remove(self, keys) -> None:
        """Stop showing these chunks (unknown keys are ignored)."""
        keys = [k for k in ((int(k[0]), int(k[1])) for k in keys) if k in self.slot_of]
        if keys:
            self._drop(keys)
            self._commit()

    def _drop(self, keys) -> None:
        for key in keys:
            s = self.slot_of.pop(key)
            _, start, nq, cmds = self._slots[s]
            if nq:
                self._verts.give(start, nq)
            for p, c in cmds:  # an empty hole until reused (count 0 draws nothing)
                self._cmd[p][c] = 0
                self._cfree[p].append(c)
            self._at[:, s * self.nreg:(s + 1) * self.nreg] = -1
            self._slots[s] = None
            self._used[s] = False
            self._free_slots.append(s)
        self._free_slots.sort(reverse=True)  # lowest slot first: full rebuilds stay in order

    def _new_cmd(self, p: int) -> int:
        c = self._cused[p]
        if c == len(self._cmd[p]):
            grown = np.zeros((max(64, 2 * c), 5), np.uint32)
            grown[:c] = self._cmd[p]
            self._cmd[p] = grown
        self._cused[p] += 1
        return c

    def _grow(self) -> None:
        """Room for the slots and vertices taken: bigger buffers, the old contents
        copied on the GPU (no chunk is uploaded again)."""
        c = self.ctx
        rows = len(self._slots) * self.nreg
        if rows > self.origin.shape[0]:
            n = max(rows, 2 * self.origin.shape[0], 16 * self.nreg)
            o = np.zeros((n, 3), np.float32)
            o[:len(self.origin)] = self.origin
            b = np.zeros((7, n), np.float32)
            b[:, :self.boxes.shape[1]] = self.boxes
            at = np.full((len(PASSES), n), -1, np.int32)
            at[:, :self._at.shape[1]] = self._at
            self.origin, self.boxes, self._at = o, b, at
            k = np.zeros((n // self.nreg, 2), np.int64)
            k[:len(self._kxy)] = self._kxy
            u = np.zeros(n // self.nreg, bool)
            u[:len(self._used)] = self._used
            self._kxy, self._used = k, u
        if self.origin.shape[0] > self._rows_cap:
            for buf in (self.obo, self._boxes):
                if buf is not None:
                    buf.release()
            self._rows_cap = self.origin.shape[0]
            self.obo = c.buffer(reserve=12 * self._rows_cap)
            if self.indirect_ok:
                self._boxes = c.buffer(reserve=32 * self._rows_cap)
            self._write_rows(0, len(self._slots) * self.nreg)
            self._vaos_void()
        need = self._verts.end
        if need > self._vbo_q or self.vbo is None:
            n = max(need, 2 * self._vbo_q, 1 << 15)
            vbo = c.buffer(reserve=n * _QUAD)
            if self.vbo is not None:
                if self._vbo_q:
                    c.copy_buffer(vbo, self.vbo, self._vbo_q * _QUAD)
                self.vbo.release()
            self.vbo, self._vbo_q = vbo, n
            self._vaos_void()
        self._index(self._most_q)

    def _index(self, quads: int) -> None:
        """The shared index pattern for at least `quads` quads: commands index their
        chunk's block through their base vertex, so the largest chunk is enough; one
        draw per region without base vertices (GL 4.1) needs the whole buffer."""
        if quads > self._ibo_q or self.ibo is None:
            n = max(quads, 2 * self._ibo_q, 1 << 14)
            if self.ibo is not None:
                self.ibo.release()
            self.ibo = self.ctx.buffer(meshing.quad_indices(n).tobytes())
            self._ibo_q = n
            self._vaos_void()

    def _write_rows(self, a: int, b: int) -> None:
        """Upload origins and boxes of table rows [a, b)."""
        if b <= a:
            return
        self.obo.write(self.origin[a:b].tobytes(), offset=12 * a)
        if self._boxes is not None:  # centre and half extent per region, vec4-aligned
            x = np.zeros((b - a, 2, 4), np.float32)
            x[:, 0, :3], x[:, 1, :3] = self.boxes[0:3, a:b].T, self.boxes[3:6, a:b].T
            self._boxes.write(x.tobytes(), offset=32 * a)

    def _vaos_void(self) -> None:
        for vao in self._vaos.values():
            vao.release()
        self._vaos.clear()

    def _commit(self) -> None:
        """The global command table (pass by pass) and each pass's part, after a change."""
        self.frames += 1
        self.gen += 1
        off = np.cumsum([0] + self._cused[:-1])
        self.cmd = np.concatenate([c[:n] for c, n in zip(self._cmd, self._cused)])
        self.at = np.where(self._at >= 0, self._at + off[:, None].astype(np.int32), -1)
        # rows with faces in some pass, and their boxes: what CPU culling tests
        self.live = np.flatnonzero((self._at >= 0).any(0))
        self._live_boxes = np.ascontiguousarray(self.boxes[:, self.live])
        self.parts: dict[str, dict] = {}
        for p, name in enumerate(PASSES):
            rows = np.flatnonzero(self._at[p] >= 0)
            if len(rows):
                self.parts[name] = {"rows": rows, "first": int(off[p]), "n": self._cused[p],
                                    "boxes": self.boxes[:, rows]}

    def bounds(self):
        """(cx0, cy0, cx1, cy1): the box of the shown chunks, or None."""
        k = self._kxy[self._used]
        if not len(k):
            return None
        lo, hi = k.min(0), k.max(0) + 1
        return int(lo[0]), int(lo[1]), int(hi[0]), int(hi[1])

    @property
    def quads(self) -> int:
        return int(self.cmd[:, 0].sum()) // 6  # 6 indices a quad

    # ------------------------------------------------------------------ frames
    def vao(self, name: str, prog):
        vao = self._vaos.get(prog.glo)
        if vao is None:
            content = [(self.vbo, "u4", "in_v")]
            if "in_origin" in prog:  # else UNIFORM_ORIGIN: one draw per region
                content.append((self.obo, "3f4/i", "in_origin"))
            vao = self.ctx.vertex_array(prog, content, index_buffer=self.ibo,
                                        index_element_size=4)
            self._vaos[prog.glo] = vao
        return vao

    def cull(self, mvp: np.ndarray) -> np.ndarray:
        """Region table rows with faces (ascending) whose box may intersect the clip
        volume."""
        return self.live[camera.visible_boxes(mvp, self._live_boxes)]

    def batches(self, rows: np.ndarray, names, slot: str = "view") -> dict:
        """{pass name: its batch, or None} of the visible regions among the table rows
        from cull, for the passes named: their commands gathered into the slot's one
        buffer, uploaded when it changed since the slot's last frame.

        A frame batches before it draws anything: the heavy draws (llvmpipe runs vertex
        work in the calling thread) leave cold caches behind, which made the Python
        between them 2-3x slower. One slot per matrix in a frame (view, shadow), so a
        frame never overwrites commands the GL may still be reading."""
        names = [n for n in names if n in self.parts]
        self.frames += 1  # the slot's buffer may change: older GPU stats are void
        cols = [PASSES.index(n) for n in names]
        # leading passes (view: all, shadow: all but blend) are a slice, not a copy
        at = self.at[:len(cols)] if cols == list(range(len(cols))) else self.at[cols]
        k = np.take(at, rows, axis=1)  # 2x a fancy index, as below
        has = k >= 0
        every = k[has]  # pass by pass, each pass's commands in table order
        last = self.bufs.get(slot)
        key = (names, self.indirect_ok, self.gen)
        if last is not None and last[2] == key and np.array_equal(last[1], every):
            return last[3]  # the same regions as the slot's last frame: nothing to do
        n_of = [int(np.count_nonzero(h)) for h in has]
        cmd = np.take(self.cmd, every, axis=0)
        buf = last[0] if last is not None else None
        if self.indirect_ok and len(every):
            data = cmd.tobytes()
            if buf is None or buf.size < len(data):
                if buf is not None:
                    buf.release()
                buf = self.ctx.buffer(reserve=max(len(data), 4096) * 2)
            else:
                buf.orphan()  # fresh storage: no wait for draws still reading it
            buf.write(data)
        starts = np.cumsum([0] + n_of[:-1]).tolist()
        full = [s for s, n in zip(starts, n_of) if n]
        # 3 indices a triangle
        tris = iter((np.add.reduceat(cmd[:, 0], full) // 3).tolist() if full else ())
        out = {name: (name, every[s:s + n], buf if self.indirect_ok else None, s, n, next(tris))
               if n else None for name, s, n in zip(names, starts, n_of)}
        self.bufs[slot] = [buf, every, key, out]
        return out

    def gpu_batches(self, mvp: np.ndarray, names, slot: str = "view") -> dict:
        """batches() with the culling on the GPU: the slot's buffer holds every command
        of every pass (uploaded when the shown chunks changed) and cull.comp sets their
        instance counts for mvp. Call barrier() after the last one and before drawing.
        Triangles are counted from the buffer when Stats are read."""
        names = [n for n in names if n in self.parts]
        self.frames += 1
        if not names:  # nothing shown (or none of these passes): nothing to cull
            return {}
        last = self.bufs.get(slot)
        if last is None or last[2] != ("gpu", self.gen):
            data = self.cmd.tobytes()
            buf = last[0] if last is not None else None
            if buf is None or buf.size < len(data):
                if buf is not None:
                    buf.release()
                buf = self.ctx.buffer(reserve=max(len(data), 4096) * 2)
            else:
                buf.orphan()
            buf.write(data)
            last = self.bufs[slot] = [buf, None, ("gpu", self.gen), None]
        buf, n = last[0], len(self.cmd)
        if self._cs is None:
            from .. import resources
            self._cs = self.ctx.compute_shader("#version 430 core\n" + resources.shader("cull.comp"))
        self._cs["planes"].write(camera.planes(mvp).astype(np.float32).tobytes())
        self._cs["n"].value = n
        buf.bind_to_storage_buffer(0)
        self._boxes.bind_to_storage_buffer(1)
        self._cs.run((n + 63) // 64)
        return {name: (name, None, buf, self.parts[name]["first"], self.parts[name]["n"], None)
                for name in names}

    @property
    def gpu(self) -> bool:
        """Whether frames cull on the GPU (gpu_batches) rather than the CPU (batches)."""
        return self.gpu_cull and self.indirect_ok

    def seen(self, name: str, mvp: np.ndarray) -> bool:
        """Whether any region of pass name may be in view (CPU, that pass's boxes only:
        with GPU culling the frame still needs to know if there is water to peel)."""
        part = self.parts.get(name)
        return part is not None and bool(camera.visible_boxes(mvp, part["boxes"]).any())

    def barrier(self) -> None:
        """The GPU culling's instance counts are visible to the draws that follow (and
        to a Stats readback)."""
        self.ctx.memory_barrier(0x40 | 0x200)  # GL_COMMAND_ and GL_BUFFER_UPDATE_BARRIER_BIT

    def draw(self, batch, prog, stats: "Stats | None" = None, shadow: bool = False) -> None:
        """Draw a batch; counts triangles (also as shadow_triangles) and draw calls."""
        if batch is None:
            return
        name, sel, buf, off, n, tris = batch
        vao = self.vao(name, prog)
        if buf is not None:
            vao.render_indirect(buf, mode=self.ctx.TRIANGLES, count=n, first=off)
            calls = 1
        else:
            u = prog["region_origin"]  # a program built with UNIFORM_ORIGIN
            cmd = self.cmd[sel]
            self._index(self._verts.end)  # no base vertex: indices into the whole buffer
            vao = self.vao(name, prog)
            first = cmd[:, 2] + cmd[:, 3] // 4 * 6
            for c, f, row in zip(cmd[:, 0].tolist(), first.tolist(), cmd[:, 4].tolist()):
                u.value = tuple(self.origin[row].tolist())
                vao.render(mode=self.ctx.TRIANGLES, vertices=c, first=f)
            calls = len(sel)
        if stats is not None:
            stats.add(tris, calls, shadow, (buf, off, n))

    def release(self) -> None:
        self._free()
        if self._cs is not None:
            self._cs.release()
            self._cs = None

    def _free(self) -> None:
        """Everything of the shown chunks (the culling program stays)."""
        self.frames += 1
        self._vaos_void()
        for b in self.bufs.values():
            if b[0] is not None:
                b[0].release()
        self.bufs.clear()
        for b in (self.vbo, self.ibo, self.obo, self._boxes):
            if b is not None:
                b.release()
        self.vbo = self.ibo = self.obo = self._boxes = None
        self._vbo_q = self._ibo_q = self._rows_cap = 0


class Stats(MutableMapping):
    """A frame's counters: triangles, shadow_triangles, draw_calls (and what the
    renderer adds). Draws culled on the GPU count their triangles from their command
    buffers when first read, in any way (a readback, so only when someone asks): read
    them before the next frame culls or the shown chunks change."""

    def __init__(self, geo: "Geometry"):
        self._d = {"triangles": 0, "shadow_triangles": 0, "draw_calls": 0}
        self.pending = []
        self.geo, self.frame = geo, geo.frames

    def add(self, tris, calls: int, shadow: bool, cmds) -> None:
        d = self._d  # no readback while drawing
        d["draw_calls"] += calls
        if tris is None:
            self.pending.append((*cmds, shadow))
            return
        d["triangles"] += tris
        if shadow:
            d["shadow_triangles"] += tris

    def _counted(self) -> dict:
        if self.pending:
            if self.geo.frames != self.frame:
                raise RuntimeError("these are an earlier frame's stats: the command buffers "
                                   "have changed since; read Renderer.stats before the next "
                                   "frame")
            pending, self.pending, read = self.pending, [], {}
            for buf, first, n, shadow in pending:
                c = read.get(id(buf))
                if c is None:
                    c = np.frombuffer(buf.read(), np.uint32)  # reserved with room to spare
                    c = read[id(buf)] = c[:len(c) // 5 * 5].reshape(-1, 5)
                c = c[first:first + n]
                self.add(int((c[:, 0].astype(np.int64) * c[:, 1]).sum()) // 3, 0, shadow, None)
        return self._d

    def snapshot(self) -> dict:
        """The counters as a plain dict (counted now)."""
        return dict(self._counted())

    def __getitem__(self, key):
        return self._counted()[key]

    def __setitem__(self, key, value):
        self._d[key] = value

    def __delitem__(self, key):
        del self._d[key]

    def __iter__(self):
        return iter(self._counted())

    def __len__(self):
        return len(self._d)

    def __repr__(self):
        return f"Stats({self._counted()!r})"
