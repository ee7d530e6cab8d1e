"""The block textures on the device: an array of 32x16 layers, each the 16x16 texture
with its mip chain beside it (level l, 16 >> l wide, at x = 32 - (32 >> l)), sampled
by hand in shaders/block.frag (no device sampler state: nearest, clamped); and the
glow masks (16x16), each times the strongest glow of a block that uses its layer."""
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
        glow = np.rint(textures.glow_array(origin="bottom") * scale[:, None, None]).astype(np.uint8)
        self.dev = dev
        self.tex = dev.texture((32, 16), "rgba8", layers=n, data=atlas)
        self.glow = dev.texture((16, 16), "r8", layers=n, data=glow)

    def bindings(self) -> dict:
        return {"tex": self.tex, "glow_tex": self.glow}

    def release(self) -> None:
        self.dev.release(self.tex, self.glow)
