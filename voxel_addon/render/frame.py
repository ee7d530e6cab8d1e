"""The per-frame uniform block (shaders/include/frame.glsl): one std140 buffer that
every program reads, written once per frame instead of dozens of uniform writes
spread over the passes. The GLSL declaration is the only place its layout is written;
the offsets come from it by the std140 rules of the member types it may use
(and vec4 arrays, `vec4 name[N];`: N × 16 bytes, set as an (N, 4) array).
"""
from __future__ import annotations

import re
import struct

import numpy as np

from .. import resources

BINDING = 0  # the uniform-buffer binding point of the block
# std140 (size, alignment) in bytes, and the 4-byte kind stored
_TYPES = {"float": (4, 4, "f"), "int": (4, 4, "i"), "bool": (4, 4, "i"),
          "vec2": (8, 8, "f"), "ivec2": (8, 8, "i"), "vec3": (12, 16, "f"),
          "vec4": (16, 16, "f"), "mat4": (64, 16, "f")}


_MEMBER = re.compile(r"(\w+)\s+(\w+)\s*(?:\[\s*(\d+)\s*\])?\s*;")


def layout(text: str | None = None) -> tuple[dict, int]:
    """{member: (first float index, floats, kind)} and the block's size in bytes."""
    text = resources.shader("include/frame.glsl") if text is None else text
    body = re.sub(r"//[^\n]*", "", re.search(r"uniform\s+Frame\s*\{(.*?)\}", text, re.S)[1])
    left = _MEMBER.sub("", body).strip()
    if left:  # e.g. "float a, b;" would shift every later offset
        raise ValueError(f"frame.glsl: cannot lay out {left.split(';')[0]!r}")
    members, off = {}, 0
    for typ, name, count in _MEMBER.findall(body):
        if typ not in _TYPES or (count and typ != "vec4"):
            raise ValueError(f"frame.glsl: member type {typ}{'[]' if count else ''} "
                             "has no std140 rule here")
        size, align, kind = _TYPES[typ]
        size *= int(count or 1)  # vec4 arrays: stride 16, no padding
        off = -(-off // align) * align
        members[name] = (off // 4, size // 4, kind)
        off += size
    return members, -(-off // 16) * 16


def arrays(text: str | None = None) -> dict:
    """{member: element count} of the block's array members."""
    text = resources.shader("include/frame.glsl") if text is None else text
    return {name: int(n) for _, name, n in _MEMBER.findall(text) if n}


class FrameBlock:
    """The block's values by member name; upload() packs them in one struct call (a
    frame sets ~30 members: one NumPy write each cost more than the whole pack)."""

    def __init__(self, ctx):
        self.members, size = layout()
        self.arrays = arrays()
        self.order = sorted(self.members, key=lambda k: self.members[k][0])
        fmt, at = "<", 0
        for k in self.order:
            o, n, kind = self.members[k]
            fmt += f"{4 * (o - at)}x" if o > at else ""
            fmt += ("i" if kind == "i" else "f") * n
            at = o + n
        self.fmt = fmt
        self.data = bytearray(size)
        self.values = {k: 0 if self.members[k][1] == 1 else (0,) * self.members[k][1]
                       for k in self.order}
        for k, n in self.arrays.items():
            self.values[k] = np.zeros((n, 4))
        self.buf = ctx.buffer(reserve=size)

    def set(self, **values) -> None:
        """Scalars, sequences, or row-major 4x4 NumPy matrices (GL gets columns)."""
        self.values.update(values)

    def upload(self) -> None:
        flat = []
        for k in self.order:
            v, (_, n, kind) = self.values[k], self.members[k]
            if n == 1:
                flat.append(int(v) if kind == "i" else float(v))
            elif k in self.arrays:
                flat.extend(np.asarray(v, float).ravel().tolist())
            elif n == 16:
                flat.extend(np.asarray(v, float).T.ravel().tolist())
            else:
                flat.extend(map(int if kind == "i" else float, v))
        struct.pack_into(self.fmt, self.data, 0, *flat)
        self.buf.orphan()  # fresh storage: no wait for the previous frame's draws
        self.buf.write(self.data)

    def release(self) -> None:
        self.buf.release()
