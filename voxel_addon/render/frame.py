"""The per-frame uniform block (shaders/include/frame.glsl): one std140 buffer that
every program reads, written once per frame instead of dozens of uniform writes
spread over the passes. frame.glsl's `//@ frame` lines are the only place its members
are written; render/glsl.py lays them out (mat4s, then vec4 rows; ints and bools
stored as floats, vec4 arrays as their rows) and this packs the values the same way.
"""
from __future__ import annotations

import struct

import numpy as np

from . import glsl

BINDING = 0  # the uniform-buffer binding point of the block (moderngl)


def layout() -> tuple[dict, int]:
    """{member: (first float index, floats, kind)} and the block's size in bytes."""
    members, size, _ = glsl.frame_layout()
    return members, size


class FrameBlock:
    """The block's values by member name; pack() packs them in one struct call (a
    frame sets ~30 members: one NumPy write each cost more than the whole pack)."""

    def __init__(self):
        self.members, size = layout()
        self.order = sorted(self.members, key=lambda k: self.members[k][0])
        fmt, at = "<", 0
        for k in self.order:
            o, n, _ = self.members[k]
            fmt += f"{4 * (o - at)}x" if o > at else ""
            fmt += "f" * n
            at = o + n
        fmt += f"{size - 4 * at}x" if 4 * at < size else ""
        self.fmt = fmt
        self.data = bytearray(size)
        self.values = {k: 0 if self.members[k][1] == 1 else (0,) * self.members[k][1]
                       for k in self.order}
        self._seen: dict = {}  # member -> (the value object last packed, its floats)

    def set(self, **values) -> None:
        """Scalars, sequences, row-major 4x4 NumPy matrices (GL gets columns), or
        (N, 4) arrays for vec4 arrays."""
        self.values.update(values)

    def pack(self) -> bytes:
        """The block's bytes (a device uploads them: Device.frame). A member set again
        as the same object keeps its converted floats (the sky's tables and colours
        of an hour, a still view's matrices: issue 29, a redraw's Python); so values
        are never changed in place once set."""
        flat, seen = [], self._seen
        for k in self.order:
            v, (_, n, kind) = self.values[k], self.members[k]
            if n == 1:
                flat.append(float(v))
                continue
            c = seen.get(k)
            if c is not None and c[0] is v:
                flat.extend(c[1])
                continue
            if kind == "a":  # (N, 4) rows
                f = np.asarray(v, float).ravel().tolist()
            elif n == 16:
                f = np.asarray(v, float).T.ravel().tolist()
            elif isinstance(v, tuple):  # (a new tuple each frame: the eye, the sun's pixel)
                f = [float(x) for x in v]
            else:
                f = np.asarray(v, float).tolist()
            seen[k] = (v, f)
            flat.extend(f)
        struct.pack_into(self.fmt, self.data, 0, *flat)
        return bytes(self.data)
