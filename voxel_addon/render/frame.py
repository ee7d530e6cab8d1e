"""The per-frame uniform block (shaders/include/frame.glsl): one std140 buffer that
every program reads, written once per frame instead of dozens of uniform writes
spread over the passes. frame.glsl's `//@ frame` lines are the only place its members
are written; render/glsl.py lays them out (mat4s, then vec4 rows; ints and bools
stored as floats, vec4 arrays as their rows) and this packs the values the same way.
"""
from __future__ import annotations

import numpy as np

from . import glsl

BINDING = 0  # the uniform-buffer binding point of the block (moderngl)


def layout() -> tuple[dict, int]:
    """{member: (first float index, floats, kind)} and the block's size in bytes."""
    members, size, _ = glsl.frame_layout()
    return members, size


class FrameBlock:
    """The block's values by member name, packed into one float32 array that stays:
    pack() writes only the members set to another object or scalar value since the
    last pack (a redraw while orbiting changes a dozen of ~60: issue 29)."""

    def __init__(self):
        self.members, size = layout()
        self.order = sorted(self.members, key=lambda k: self.members[k][0])
        self.arr = np.zeros(size // 4, np.float32)  # (the paddings stay 0)
        self.values = {k: 0 if self.members[k][1] == 1 else (0,) * self.members[k][1]
                       for k in self.order}
        # per member: how pack writes it (an index, or a view of arr in the value's
        # shape: a row-major 4x4 into a column-major one, (N, 4) rows, a vector), and
        # the value object last written
        self._at: dict = {}
        for k in self.order:
            o, n, kind = self.members[k]
            a = self.arr[o:o + n]
            self._at[k] = o if n == 1 else a.reshape(4, 4).T if n == 16 and kind != "a" \
                else a.reshape(-1, 4) if kind == "a" else a
        self._seen = dict(self.values)

    def set(self, **values) -> None:
        """Scalars, sequences, row-major 4x4 NumPy matrices (GL gets columns), or
        (N, 4) arrays for vec4 arrays."""
        self.values.update(values)

    def pack(self) -> bytes:
        """The block's bytes (a device uploads them: Device.frame). A member set again
        as the same object is not written again (the sky's tables and colours of an
        hour, a still view's matrices: issue 29, a redraw's Python); so values are
        never changed in place once set."""
        seen, at, arr = self._seen, self._at, self.arr
        for k, v in self.values.items():
            w = seen[k]
            if w is v:
                continue
            a = at[k]
            if a.__class__ is int:
                arr[a] = float(v)
            else:
                a[...] = v
            seen[k] = v
        return arr.tobytes()
