"""Render regions on the GPU (thesis §5.3.2, §5.3.4): per pass one big vertex buffer of
the meshing package's 4-byte vertices, a shared quad index pattern, CPU frustum
culling per region and one multi-draw per pass.

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
        self.quads = 0

    def set_chunks(self, meshes: dict) -> None:
        """meshes: {(cx, cy): meshing.ChunkMesh}. Replaces what was shown."""
        self.release()
        max_quads = 1
        for p, name in enumerate(PASSES):
            verts, first, count, origin = [], [], [], []
            n = 0
            for (cx, cy), m in meshes.items():
                for r in range(m.ranges.shape[0]):
                    f, c = (int(x) for x in m.ranges[r, p])
                    if c == 0:
                        continue
                    verts.append(m.vertices[f:f + c])
                    first.append(n)
                    count.append(c)
                    origin.append((cx * 16, cy * 16, r * m.region_h))
                    n += c
            if not n:
                continue
            h = next(iter(meshes.values())).region_h
            origin = np.array(origin, np.float32)
            max_quads = max(max_quads, n // 4)
            self.parts[name] = {
                "vbo": self.ctx.buffer(np.concatenate(verts).astype(np.uint32).tobytes()),
                "obo": self.ctx.buffer(origin.tobytes()),
                "first": np.array(first, np.int64), "count": np.array(count, np.int64),
                "origin": origin, "lo": origin - 0.5,  # slack for waving
                "hi": origin + np.array([16.5, 16.5, h + 0.5], np.float32),
                "vaos": {}, "cmd": None, "cmd_cap": 0}
        self.quads = sum(int(p["count"].sum()) // 4 for p in self.parts.values())
        self.ibo = self.ctx.buffer(meshing.quad_indices(max_quads).tobytes())

    def vao(self, name: str, prog):
        part = self.parts[name]
        vao = part["vaos"].get(prog.glo)
        if vao is None:
            content = [(part["vbo"], "u4", "in_v")]
            if self.indirect_ok:
                content.append((part["obo"], "3f4/i", "in_origin"))
            vao = self.ctx.vertex_array(prog, content, index_buffer=self.ibo,
                                        index_element_size=4)
            part["vaos"][prog.glo] = vao
        return vao

    def visible(self, name: str, mvp: np.ndarray) -> np.ndarray:
        part = self.parts.get(name)
        if part is None:
            return np.zeros(0, np.int64)
        return np.flatnonzero(camera.visible(mvp, part["lo"], part["hi"]))

    def draw(self, name: str, prog, idx, stats: dict | None = None) -> None:
        """Draw regions idx of pass name; counts triangles and draw calls."""
        if name not in self.parts or not len(idx):
            return
        part = self.parts[name]
        vao = self.vao(name, prog)
        first, count = part["first"][idx], part["count"][idx]
        if stats is not None:
            stats["triangles"] += int(count.sum()) // 2
        if self.indirect_ok:
            prog["use_uniform_origin"].value = False
            # DrawElementsIndirectCommand: count, instances, first index, base vertex, base instance
            cmd = np.zeros((len(idx), 5), np.uint32)
            cmd[:, 0], cmd[:, 1], cmd[:, 2], cmd[:, 4] = count // 4 * 6, 1, first // 4 * 6, idx
            if part["cmd_cap"] < cmd.nbytes:
                if part["cmd"] is not None:
                    part["cmd"].release()
                part["cmd_cap"] = max(cmd.nbytes, 4096) * 2
                part["cmd"] = self.ctx.buffer(reserve=part["cmd_cap"])
            part["cmd"].write(cmd.tobytes())
            vao.render_indirect(part["cmd"], mode=self.ctx.TRIANGLES, count=len(idx))
            calls = 1
        else:
            prog["use_uniform_origin"].value = True
            for i, f, c in zip(idx, first, count):
                prog["region_origin"].value = tuple(part["origin"][i])
                vao.render(mode=self.ctx.TRIANGLES, vertices=int(c // 4 * 6), first=int(f // 4 * 6))
            calls = len(idx)
        if stats is not None:
            stats["draw_calls"] += calls

    def release(self) -> None:
        for part in self.parts.values():
            for vao in part["vaos"].values():
                vao.release()
            part["vbo"].release()
            part["obo"].release()
            if part["cmd"] is not None:
                part["cmd"].release()
        self.parts.clear()
        if self.ibo is not None:
            self.ibo.release()
            self.ibo = None
