"""The light of the whole view in one camera-centred toroidal 3D texture.

Chunk (cx, cy) lives at texels ((16cx) mod S, (16cy) mod S, 0..255), S = 16(2r+1),
so every chunk within r of the centre chunk has its own slot and moving the camera
only re-uploads the chunks that came into range (no bindless textures, GL 3.3+).
"""
from __future__ import annotations

import numpy as np

from ..core import chunk
from .programs import set_uniforms

_OPEN = None  # a chunk of open daylight (full daylight, no block light), as bytes


def window(area, radius: int):
    """The chunk box with exact light: `radius` chunks around the centre chunk of the
    area (cx0, cy0, cx1, cy1), clipped to it; bounds the volume at any view distance."""
    cx0, cy0, cx1, cy1 = area
    mx, my = (cx0 + cx1 - 1) // 2, (cy0 + cy1 - 1) // 2
    return (max(cx0, mx - radius), max(cy0, my - radius),
            min(cx1, mx + radius + 1), min(cy1, my + radius + 1))


class LightVolume:
    def __init__(self, ctx, n: int):
        """n chunk slots per side: 2r+1 for a view radius r."""
        self.ctx = ctx
        self.n = n
        self.size = chunk.SIZE * self.n
        self.tex = ctx.texture3d((self.size, self.size, chunk.HEIGHT), 1, dtype="u2")
        self.tex.filter = (0x2600, 0x2600)  # GL_NEAREST: integers, interpolated by hand
        self.slots: dict[tuple[int, int], tuple[int, int]] = {}  # slot -> resident key
        self.lo = (0, 0)
        self.hi = (0, 0)

    def upload(self, key, light) -> None:
        """Put one chunk's (16, 16, 256) light into its slot (None: open daylight, as
        outside the window; a tuple: core.chunk.pack_layers of it)."""
        global _OPEN
        slot = (key[0] % self.n, key[1] % self.n)
        if isinstance(light, tuple):
            light = chunk.unpack_layers(*light)
        if light is None:
            if _OPEN is None:
                _OPEN = np.full(16 * 16 * chunk.HEIGHT, 0xF000, np.uint16).tobytes()
            data = _OPEN
        else:
            arr = np.asarray(light, dtype=np.uint16)
            data = np.asfortranarray(arr).tobytes(order="F")
        self.tex.write(data, viewport=(slot[0] * 16, slot[1] * 16, 0, 16, 16, chunk.HEIGHT))
        self.slots[slot] = tuple(key)

    def resident(self, key) -> bool:
        return self.slots.get((key[0] % self.n, key[1] % self.n)) == key

    def forget(self, key) -> None:
        """The chunk's light changed: its slot no longer holds it (uploaded again when
        the window needs it)."""
        slot = (key[0] % self.n, key[1] % self.n)
        if self.slots.get(slot) == key:
            del self.slots[slot]

    def upload_area(self, light: np.ndarray, cx0: int, cy0: int) -> None:
        """A (16w, 16h, 256) light array whose first chunk is (cx0, cy0)."""
        for key, a in chunk.cut(light, cx0, cy0).items():
            self.upload(key, a)

    def set_window(self, cx0: int, cy0: int, cx1: int, cy1: int) -> None:
        """The chunk box whose light is resident (outside it: open daylight)."""
        if cx1 - cx0 > self.n or cy1 - cy0 > self.n:
            raise ValueError("light window is larger than the volume")
        for cx in range(cx0, cx1):
            for cy in range(cy0, cy1):
                if self.slots.get((cx % self.n, cy % self.n)) != (cx, cy):
                    raise ValueError(f"chunk {(cx, cy)} is not resident")
        self.lo, self.hi = (cx0 * 16, cy0 * 16), (cx1 * 16, cy1 * 16)

    def bind(self, prog, unit: int) -> None:
        self.tex.use(unit)
        set_uniforms(prog, light_vol=unit)
        self.uniforms(prog)

    def uniforms(self, prog) -> None:
        """The window's uniforms (the texture itself is bound by the caller's scope)."""
        set_uniforms(prog, vol_size=self.size, vol_lo=self.lo, vol_hi=self.hi)

    def release(self):
        self.tex.release()
