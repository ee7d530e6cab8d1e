"""Render regions on the GPU (thesis §5.3.2, §5.3.4): per pass one big vertex buffer of
the meshing package's 4-byte vertices, a shared quad index pattern, frustum culling
per region and one multi-draw per pass.

All passes share one region table (chunk x region, with its box and origin), so a
frame culls once per matrix (view, shadow) for every pass. One static table holds the
indirect commands of every pass (one per region with faces in that pass), and `at`
says where each table row's command of each pass is; per matrix a frame gathers the
commands of the visible rows only (work by what is seen, not by the view distance)
into one buffer, uploaded when it changed since the same slot's last frame, and each
pass draws its slice of it.

GL 4.3+: glMultiDrawElementsIndirect, the region origin comes from baseInstance
through an instanced attribute, and the culling runs on the GPU (`gpu_cull`,
shaders/cull.comp, the twin of camera.visible_boxes): a slot's buffer holds every
command and a compute pass sets each one's instance count to 1 or 0, so the CPU
neither culls nor gathers. GL 4.1 (macOS): CPU culling and one draw per visible
region with the origin as a uniform.
"""
from __future__ import annotations

from collections.abc import MutableMapping

import numpy as np

from .. import meshing
from . import camera
from .programs import source

PASSES = meshing.PASSES  # opaque, cutout (leaves), cutout2 (double-sided plants), blend


class Geometry:
    def __init__(self, ctx):
        self.ctx = ctx
        self.indirect_ok = ctx.version_code >= 430
        self.gpu_cull = True  # with indirect_ok (4.3 brings compute shaders); tests switch it
        self.frames = 0  # gpu_batches calls: the command buffers' generation
        self._cs = None
        self._boxes = None  # the region boxes for cull.comp
        self.parts: dict[str, dict] = {}
        self.ibo = None
        self.obo = None
        self.quads = 0
        self.origin = np.zeros((0, 3), np.float32)
        self.boxes = np.zeros((7, 0), np.float32)
        self._clear_tables(0)

    def _clear_tables(self, n_rows: int) -> None:
        self.at = np.full((len(PASSES), n_rows), -1, np.int32)  # pass, row -> command
        self.cmd = np.zeros((0, 5), np.uint32)
        self.bufs: dict = {}  # slot -> [buffer, its commands, pass names, batches]

    def set_chunks(self, meshes: dict) -> None:
        """meshes: {(cx, cy): meshing.ChunkMesh}. Replaces what was shown."""
        self._free()
        if not meshes:
            self.ibo = self.ctx.buffer(meshing.quad_indices(1).tobytes())
            return
        ms = list(meshes.values())
        h = ms[0].region_h
        nr = max(m.ranges.shape[0] for m in ms)
        # (chunk, region, pass) -> (first, count) of that chunk's own vertex array
        rng = np.zeros((len(ms), nr, len(PASSES), 2), np.int64)
        for i, m in enumerate(ms):
            rng[i, :m.ranges.shape[0]] = m.ranges
        cnt = rng[..., 1]
        keep = cnt.sum(2) > 0                       # regions with any face
        ci, ri = np.nonzero(keep)                   # region table rows, chunk-major
        if not len(ci):  # all air: nothing to draw
            self.ibo = self.ctx.buffer(meshing.quad_indices(1).tobytes())
            return
        keys = np.array(list(meshes), np.int64).reshape(-1, 2)
        self.origin = np.c_[keys[ci] * 16, ri * h].astype(np.float32)
        # 0.5 slack for waving: vertices move by < 0.1 blocks
        self.boxes = camera.boxes(self.origin - 0.5, self.origin + [16.5, 16.5, h + 0.5])
        max_quads = 1
        self._clear_tables(len(ci))
        cmds = []
        for p, name in enumerate(PASSES):
            c = cnt[ci, ri, p]
            rows = np.flatnonzero(c)
            if not len(rows):
                continue
            f = rng[ci[rows], ri[rows], p, 0]
            verts = np.concatenate([ms[ci[k]].vertices[a:a + n]
                                    for k, a, n in zip(rows.tolist(), f.tolist(), c[rows].tolist())])
            count = c[rows]
            first = np.r_[0, np.cumsum(count)[:-1]]
            max_quads = max(max_quads, len(verts) // 4)
            # DrawElementsIndirectCommand: count, instances, first index, base vertex, base instance
            cmd = np.zeros((len(rows), 5), np.uint32)
            cmd[:, 0], cmd[:, 1], cmd[:, 2], cmd[:, 4] = count // 4 * 6, 1, first // 4 * 6, rows
            self.at[p, rows] = sum(map(len, cmds)) + np.arange(len(rows))
            cmds.append(cmd)
            self.parts[name] = {
                "vbo": self.ctx.buffer(verts.astype(np.uint32, copy=False).tobytes()),
                "rows": rows, "vaos": {}, "first": sum(map(len, cmds)) - len(rows),
                "boxes": self.boxes[:, rows]}
        if cmds:
            self.cmd = np.concatenate(cmds)
        self.quads = int(self.cmd[:, 0].sum()) // 6  # 6 indices a quad
        self.obo = self.ctx.buffer(self.origin.tobytes())
        if self.indirect_ok:  # centre and half extent per region, vec4-aligned
            b = np.zeros((len(ci), 2, 4), np.float32)
            b[:, 0, :3], b[:, 1, :3] = self.boxes[0:3].T, self.boxes[3:6].T
            self._boxes = self.ctx.buffer(b.tobytes() or b"\0" * 32)
        self.ibo = self.ctx.buffer(meshing.quad_indices(max_quads).tobytes())

    def vao(self, name: str, prog):
        part = self.parts[name]
        vao = part["vaos"].get(prog.glo)
        if vao is None:
            content = [(part["vbo"], "u4", "in_v")]
            if "in_origin" in prog:  # else UNIFORM_ORIGIN: one draw per region
                content.append((self.obo, "3f4/i", "in_origin"))
            vao = self.ctx.vertex_array(prog, content, index_buffer=self.ibo,
                                        index_element_size=4)
            part["vaos"][prog.glo] = vao
        return vao

    def cull(self, mvp: np.ndarray) -> np.ndarray:
        """Region table rows (ascending) whose box may intersect the clip volume."""
        return np.flatnonzero(camera.visible_boxes(mvp, self.boxes))

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
        key = (names, self.indirect_ok)
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
        of every pass (uploaded once) and cull.comp sets their instance counts for mvp.
        Call barrier() after the last one and before drawing. Triangles are counted
        from the buffer when Stats are read."""
        names = [n for n in names if n in self.parts]
        self.frames += 1
        if not names:  # nothing shown (or none of these passes): nothing to cull
            return {}
        last = self.bufs.get(slot)
        if last is None or last[2] != "gpu":
            if last is not None and last[0] is not None:
                last[0].release()
            last = self.bufs[slot] = [self.ctx.buffer(self.cmd.tobytes() or b"\0" * 20),
                                      None, "gpu", None]
        buf, n = last[0], len(self.cmd)
        if self._cs is None:
            self._cs = self.ctx.compute_shader(source("cull.comp", None, 430))
        self._cs["planes"].write(camera.planes(mvp).astype(np.float32).tobytes())
        self._cs["n"].value = n
        buf.bind_to_storage_buffer(0)
        self._boxes.bind_to_storage_buffer(1)
        self._cs.run((n + 63) // 64)
        return {name: (name, None, buf, self.parts[name]["first"],
                       len(self.parts[name]["rows"]), None) for name in names}

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
            for c, first, row in zip(cmd[:, 0].tolist(), cmd[:, 2].tolist(), cmd[:, 4].tolist()):
                u.value = tuple(self.origin[row].tolist())
                vao.render(mode=self.ctx.TRIANGLES, vertices=c, first=first)
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
        for part in self.parts.values():
            for vao in part["vaos"].values():
                vao.release()
            part["vbo"].release()
        for b in self.bufs.values():
            if b[0] is not None:
                b[0].release()
        self.bufs.clear()
        if self._boxes is not None:
            self._boxes.release()
            self._boxes = None
        self.parts.clear()
        for b in (self.ibo, self.obo):
            if b is not None:
                b.release()
        self.ibo = self.obo = None


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
                    c = read[id(buf)] = np.frombuffer(buf.read(), np.uint32).reshape(-1, 5)
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
