"""The per-frame uniform block (shaders/include/frame.glsl): one std140 buffer that
every program reads, written once per frame instead of dozens of uniform writes
spread over the passes. The GLSL declaration is the only place its layout is written;
the offsets come from it by the std140 rules of the member types it may use.
"""
from __future__ import annotations

import re

import numpy as np

from .. import resources

BINDING = 0  # the uniform-buffer binding point of the block
# std140 (size, alignment) in bytes, and the 4-byte kind stored
_TYPES = {"float": (4, 4, "f"), "int": (4, 4, "i"), "bool": (4, 4, "i"),
          "vec2": (8, 8, "f"), "ivec2": (8, 8, "i"), "vec3": (12, 16, "f"),
          "vec4": (16, 16, "f"), "mat4": (64, 16, "f")}


def layout(text: str | None = None) -> tuple[dict, int]:
    """{member: (first float index, floats, kind)} and the block's size in bytes."""
    text = resources.shader("include/frame.glsl") if text is None else text
    body = re.sub(r"//[^\n]*", "", re.search(r"uniform\s+Frame\s*\{(.*?)\}", text, re.S)[1])
    members, off = {}, 0
    for typ, name in re.findall(r"(\w+)\s+(\w+)\s*;", body):
        if typ not in _TYPES:
            raise ValueError(f"frame.glsl: member type {typ} has no std140 rule here")
        size, align, kind = _TYPES[typ]
        off = -(-off // align) * align
        members[name] = (off // 4, size // 4, kind)
        off += size
    return members, -(-off // 16) * 16


class FrameBlock:
    def __init__(self, ctx):
        self.members, size = layout()
        self.f = np.zeros(size // 4, np.float32)
        self.i = self.f.view(np.int32)
        self.buf = ctx.buffer(reserve=size)

    def set(self, **values) -> None:
        for k, v in values.items():
            o, n, kind = self.members[k]
            if kind == "i":
                self.i[o:o + n] = v
            elif n == 16:  # matrices are row-major NumPy; GL wants columns
                self.f[o:o + 16] = np.asarray(v).T.ravel()
            else:
                self.f[o:o + n] = v

    def upload(self) -> None:
        self.buf.orphan()  # fresh storage: no wait for the previous frame's draws
        self.buf.write(self.f)

    def release(self) -> None:
        self.buf.release()
