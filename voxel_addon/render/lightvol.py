"""The light of the whole view in one camera-centred toroidal texture
(shaders/include/lightvol.glsl).

A 2D array of N x N layers of 256 x 256 texels: chunk (cx, cy) lives in layer
(cx mod N) + N (cy mod N), its voxel (x, y, z) at texel (x + 16 (z & 15), y + 16 (z >> 4)),
the packed uint16 in a 16-bit unorm. N = 2r + 1 slots per side, so every chunk within
r of the centre chunk has its own layer and moving the camera only uploads the chunks
that came into range; an edit uploads the layers of the chunks whose light changed.
One layer is the unit of upload because a device may not write part of a texture
(Blender's gpu module draws it in: blender/liveview/device.py).
"""
from __future__ import annotations

import numpy as np

from ..core import chunk

_OPEN = None  # a layer of open daylight (full daylight, no block light)


def window(area, radius: int):
    """The chunk box with exact light: `radius` chunks around the centre chunk of the
    area (cx0, cy0, cx1, cy1), clipped to it; bounds the volume at any view distance."""
    cx0, cy0, cx1, cy1 = area
    mx, my = (cx0 + cx1 - 1) // 2, (cy0 + cy1 - 1) // 2
    return (max(cx0, mx - radius), max(cy0, my - radius),
            min(cx1, mx + radius + 1), min(cy1, my + radius + 1))


def layer_of(light: np.ndarray) -> np.ndarray:
    """A chunk's (16, 16, 256) packed light as its (256, 256) layer (rows: y + 16 (z >> 4))."""
    a = np.asarray(light, np.uint16).reshape(16, 16, 16, 16, order="F")  # x, y, z & 15, z >> 4
    return np.ascontiguousarray(a.transpose(3, 1, 2, 0)).reshape(256, 256)


class LightVolume:
    def __init__(self, dev, n: int):
        """n chunk slots per side: 2r+1 for a view radius r."""
        self.dev = dev
        self.n = n
        self.tex = dev.texture((256, 256), "r16", layers=n * n)
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
                _OPEN = np.full((256, 256), 0xF000, np.uint16)
            data = _OPEN
        else:
            data = layer_of(light)
        self.dev.write_layer(self.tex, slot[0] + self.n * slot[1], data)
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

    def frame_values(self) -> dict:
        """The frame block's members of the volume (include/lightvol.glsl)."""
        return {"vol_n": self.n, "vol_lo": self.lo, "vol_hi": self.hi}

    def release(self):
        self.dev.release(self.tex)
