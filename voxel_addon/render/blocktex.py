"""The block textures on the device: an array of 32x16 layers, each the 16x16 texture
with its mip chain beside it (level l, 16 >> l wide, at x = 32 - (32 >> l)), sampled
by hand in shaders/block.frag (no device sampler state: nearest, clamped); the glow
masks (16x16), each times the strongest glow of a block that uses its layer (water's
layers all 1: its mark); and the world's colour palette (the `color` block's tint,
256 colours a row)."""
from __future__ import annotations

import numpy as np

from ..core.blocks import REGISTRY


class BlockTextures:
    def __init__(self, dev):
        from .. import textures
        rgba = textures.texture_array(origin="bottom")
        n = rgba.shape[0]
        atlas = np.zeros((n, 16, 32, 4), np.uint8)
        for lvl, a in enumerate(textures.mipmaps(rgba)):  # (alpha-weighted: no dark fringes)
            s, x = 16 >> lvl, 32 - (32 >> lvl)
            atlas[:, :s, x:x + s] = a
        scale = np.zeros(n, np.float32)
        for i, b in enumerate(REGISTRY.blocks):
            if b.shape != "none":
                for layer in set(REGISTRY.face_texture[i].tolist()):
                    scale[layer] = max(scale[layer], b.glow)
        if scale.max() > 1.0:
            raise ValueError("a block glows above 1: the glow texture is 8-bit unorm")
        glow = np.rint(textures.glow_array(origin="bottom") * scale[:, None, None])
        # water's layers are marked by glow 1 (block.frag: colour by depth; shade.glsl:
        # waves, reflections), every other glow stays below it
        glow = np.minimum(glow, 254).astype(np.uint8)
        glow[sorted(set(REGISTRY.face_texture[REGISTRY.id("water")].tolist()))] = 255
        self.dev = dev
        self.tex = dev.texture((32, 16), "rgba8", layers=n, data=atlas)
        self.glow = dev.texture((16, 16), "r8", layers=n, data=glow)
        self.palette = None
        self._rgb = None
        self.set_palette(np.array([[255, 255, 255]], np.uint8))

    def set_palette(self, rgb) -> bool:
        """The world's colours ((n, 3) uint8, core.colors); returns whether the texture
        changed (then the passes that bind it are made again)."""
        rgb = np.asarray(rgb, np.uint8).reshape(-1, 3)
        if self._rgb is not None and np.array_equal(rgb, self._rgb):
            return False
        rows = -(-len(rgb) // 256)
        data = np.full((rows * 256, 4), 255, np.uint8)
        data[:len(rgb), :3] = rgb
        old = self.palette
        self.palette = self.dev.texture((256, rows), "rgba8", data=data.reshape(rows, 256, 4))
        self.dev.release(old)
        self._rgb = rgb.copy()
        return True

    def bindings(self) -> dict:
        return {"tex": self.tex, "glow_tex": self.glow, "palette": self.palette}

    def release(self) -> None:
        self.dev.release(self.tex, self.glow, self.palette)
