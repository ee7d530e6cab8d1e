"""A "superflat" world: the same stack of layers everywhere (a test bed and a canvas)."""
from __future__ import annotations

import numpy as np

from ..core import chunk, surface
from ..core.blocks import REGISTRY
from ..core.errors import VoxelError
from .base import Generator


class FlatGenerator(Generator):
    name = "flat"
    version = 1
    # Bottom-up (block name, thickness) pairs.
    defaults = {"layers": [["stone", 60], ["dirt", 3], ["grass", 1]]}

    def __init__(self, seed, params=None, backend=None, version=None):
        super().__init__(seed, params, backend, version)
        column = np.zeros(chunk.HEIGHT, np.uint16)
        z = 0
        for name, thickness in self.params["layers"]:
            if z + int(thickness) > chunk.HEIGHT:
                raise VoxelError("flat layers are taller than the world (256)")
            column[z:z + int(thickness)] = REGISTRY.id(name)
            z += int(thickness)
        self._column = column

    def generate(self, keys):
        out = []
        for _ in keys:
            a = chunk.empty()
            a[:, :, :] = self._column
            out.append(a)
        return out

    def surface(self, xy):
        n = len(xy)
        col = surface.columns(self._column)
        return {"height": np.full(n, col["height"], np.int32),
                "top": np.full(n, col["top"], np.int32),
                "water": np.full(n, col["water"], np.int32),
                "trees": np.full(n, float(col["tree"]), np.float32)}
