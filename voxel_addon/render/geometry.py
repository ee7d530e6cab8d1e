"""Render regions on the GPU (thesis §5.3.2, §5.3.4): per pass one big vertex buffer of
the meshing package's 4-byte vertices, a shared quad index pattern, CPU frustum
culling per region and one multi-draw per pass.

All passes share one region table (chunk x region, with its box and origin), so a
frame culls once per matrix (view, shadow) for every pass. Each pass keeps a static
table of its indirect commands, one per region that has faces in it; a frame only
gathers the rows of the visible regions (one NumPy mask index) and uploads them when
the visible set changed since the same slot's last draw.

GL 4.3+: glMultiDrawElementsIndirect, the region origin comes from baseInstance
through an instanced attribute. GL 4.1 (macOS): one draw per visible region with the
origin as a uniform.
"""
from __future__ import annotations

import numpy as np

from .. import meshing
from . import camera
from .programs import set_uniforms

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
            self.parts[name] = {
                "vbo": self.ctx.buffer(verts.astype(np.uint32, copy=False).tobytes()),
                "rows": rows, "cmd": cmd, "tris": (count // 2).astype(np.int64),
                "vaos": {}, "bufs": {}}
        self.quads = sum(int(p["tris"].sum()) // 2 for p in self.parts.values())
        self.obo = self.ctx.buffer(self.origin.tobytes())
        self.ibo = self.ctx.buffer(meshing.quad_indices(max_quads).tobytes())

    def vao(self, name: str, prog):
        part = self.parts[name]
        vao = part["vaos"].get(prog.glo)
        if vao is None:
            content = [(part["vbo"], "u4", "in_v")]
            if self.indirect_ok:
                content.append((self.obo, "3f4/i", "in_origin"))
            vao = self.ctx.vertex_array(prog, content, index_buffer=self.ibo,
                                        index_element_size=4)
            part["vaos"][prog.glo] = vao
        return vao

    def cull(self, mvp: np.ndarray) -> np.ndarray:
        """Mask over the region table: regions whose box may intersect the clip volume."""
        return camera.visible_boxes(mvp, self.boxes)

    def visible(self, name: str, mvp: np.ndarray) -> np.ndarray:
        """Indices into the region table of pass name's visible regions."""
        part = self.parts.get(name)
        if part is None:
            return np.zeros(0, np.int64)
        return part["rows"][self.cull(mvp)[part["rows"]]]

    def draw(self, name: str, prog, mask: np.ndarray, stats: dict | None = None,
             slot: str = "view") -> None:
        """Draw pass name's regions where mask (from cull) is set; counts triangles
        and draw calls. slot names the command buffer (one per matrix in a frame), so
        a frame never overwrites commands the GL may still be reading."""
        part = self.parts.get(name)
        if part is None:
            return
        sel = mask[part["rows"]]
        n = int(np.count_nonzero(sel))
        if not n:
            return
        vao = self.vao(name, prog)
        if stats is not None:
            stats["triangles"] += int(part["tris"][sel].sum())
        if self.indirect_ok:
            set_uniforms(prog, use_uniform_origin=False)
            buf = part["bufs"].get(slot)
            if buf is None or buf[1] is None or not np.array_equal(buf[1], sel):
                data = part["cmd"][sel].tobytes()
                if buf is None or buf[0].size < len(data):
                    if buf is not None:
                        buf[0].release()
                    buf = [self.ctx.buffer(reserve=max(len(data), 4096) * 2), None]
                else:
                    buf[0].orphan()  # fresh storage: no wait for draws still reading it
                buf[0].write(data)
                buf[1] = sel
                part["bufs"][slot] = buf
            vao.render_indirect(buf[0], mode=self.ctx.TRIANGLES, count=n)
            calls = 1
        else:
            set_uniforms(prog, use_uniform_origin=True)
            u = prog["region_origin"]
            cmd = part["cmd"][sel]
            for c, first, row in zip(cmd[:, 0].tolist(), cmd[:, 2].tolist(), cmd[:, 4].tolist()):
                u.value = tuple(self.origin[row].tolist())
                vao.render(mode=self.ctx.TRIANGLES, vertices=c, first=first)
            calls = n
        if stats is not None:
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
