"""Render regions on the GPU (thesis §5.3.2, §5.3.4): per pass one big vertex buffer of
the meshing package's 4-byte vertices, a shared quad index pattern, CPU frustum
culling per region and one multi-draw per pass.

All passes share one region table (chunk x region, with its box and origin), so a
frame culls once per matrix (view, shadow) for every pass. Each pass keeps a static
table of its indirect commands, one per region that has faces in it, and where each
table row's command is; a frame gathers the commands of the visible rows only (work
by what is seen, not by the view distance) and uploads them when they changed since
the same slot's last draw.

GL 4.3+: glMultiDrawElementsIndirect, the region origin comes from baseInstance
through an instanced attribute. GL 4.1 (macOS): one draw per visible region with the
origin as a uniform.
"""
from __future__ import annotations

import numpy as np

from .. import meshing
from . import camera

PASSES = meshing.PASSES  # opaque, cutout (leaves), cutout2 (double-sided plants), blend


class Geometry:
    def __init__(self, ctx):
        self.ctx = ctx
        self.indirect_ok = ctx.version_code >= 430
        self.parts: dict[str, dict] = {}
        self.ibo = None
        self.obo = None
        self.quads = 0
        self.origin = np.zeros((0, 3), np.float32)
        self.boxes = np.zeros((6, 0), np.float32)

    def set_chunks(self, meshes: dict) -> None:
        """meshes: {(cx, cy): meshing.ChunkMesh}. Replaces what was shown."""
        self.release()
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
        keys = np.array(list(meshes), np.int64).reshape(-1, 2)
        self.origin = np.c_[keys[ci] * 16, ri * h].astype(np.float32)
        # 0.5 slack for waving: vertices move by < 0.1 blocks
        self.boxes = camera.boxes(self.origin - 0.5, self.origin + [16.5, 16.5, h + 0.5])
        max_quads = 1
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
            at = np.full(len(ci), -1, np.int64)  # table row -> its command here, or -1
            at[rows] = np.arange(len(rows))
            self.parts[name] = {
                "vbo": self.ctx.buffer(verts.astype(np.uint32, copy=False).tobytes()),
                "rows": rows, "at": at, "cmd": cmd, "tris": (count // 2).astype(np.int64),
                "vaos": {}, "bufs": {}}
        self.quads = sum(int(p["tris"].sum()) // 2 for p in self.parts.values())
        self.obo = self.ctx.buffer(self.origin.tobytes())
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

    def visible(self, name: str, rows: np.ndarray) -> np.ndarray:
        """Pass name's commands (indices into its table) among the table rows from cull."""
        part = self.parts.get(name)
        if part is None:
            return rows[:0]
        k = part["at"][rows]
        return k[k >= 0]

    def batch(self, name: str, rows: np.ndarray, slot: str = "view"):
        """Pass name's visible regions among the table rows from cull, with their
        commands uploaded when they changed since the slot's last batch; None if none.

        A frame batches every pass before it draws any: the heavy draws (llvmpipe runs
        vertex work in the calling thread) leave cold caches behind, which made the
        Python between them 2-3x slower. slot names the command buffer (one per matrix
        in a frame), so a frame never overwrites commands the GL may still be reading."""
        sel = self.visible(name, rows)
        if not len(sel):
            return None
        part = self.parts[name]
        buf = None
        if self.indirect_ok:
            buf = part["bufs"].get(slot)
            if buf is None or not np.array_equal(buf[1], sel):
                data = np.take(part["cmd"], sel, axis=0).tobytes()  # 2x a fancy index
                if buf is None or buf[0].size < len(data):
                    if buf is not None:
                        buf[0].release()
                    buf = [self.ctx.buffer(reserve=max(len(data), 4096) * 2), sel]
                else:
                    buf[0].orphan()  # fresh storage: no wait for draws still reading it
                buf[0].write(data)
                buf[1] = sel
                part["bufs"][slot] = buf
        return name, sel, buf, int(part["tris"][sel].sum())

    def draw(self, batch, prog, stats: dict | None = None) -> None:
        """Draw a batch; counts triangles and draw calls into stats."""
        if batch is None:
            return
        name, sel, buf, tris = batch
        vao = self.vao(name, prog)
        if buf is not None:
            vao.render_indirect(buf[0], mode=self.ctx.TRIANGLES, count=len(sel))
            calls = 1
        else:
            u = prog["region_origin"]  # a program built with UNIFORM_ORIGIN
            cmd = self.parts[name]["cmd"][sel]
            for c, first, row in zip(cmd[:, 0].tolist(), cmd[:, 2].tolist(), cmd[:, 4].tolist()):
                u.value = tuple(self.origin[row].tolist())
                vao.render(mode=self.ctx.TRIANGLES, vertices=c, first=first)
            calls = len(sel)
        if stats is not None:
            stats["triangles"] += tris
            stats["draw_calls"] += calls

    def release(self) -> None:
        for part in self.parts.values():
            for vao in part["vaos"].values():
                vao.release()
            part["vbo"].release()
            for buf in part["bufs"].values():
                buf[0].release()
        self.parts.clear()
        for b in (self.ibo, self.obo):
            if b is not None:
                b.release()
        self.ibo = self.obo = None
