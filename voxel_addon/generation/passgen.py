"""Generators written in the pass language: backend choice, batching, results.

A subclass implements `program()` -> lang.Program (built from self.params); this
class runs it with NumPy or OpenCL, in batches, and cuts the result into chunks.
"""
from __future__ import annotations

import numpy as np

from .. import opencl
from ..core import chunk as C
from . import noise
from .base import Generator

BACKENDS = opencl.BACKENDS


class PassGenerator(Generator):
    batch_cl = 64   # chunks per kernel launch
    batch_np = 4    # chunks per NumPy evaluation (bounds temporary memory)

    def __init__(self, seed, params=None, backend=None):
        super().__init__(seed, params, backend)
        self.backend_used = opencl.pick(backend, "generation")
        self.backend = self.backend_used
        self.seed32 = noise.seed32(self.seed)
        self.perm = noise.perm_table(self.seed32)
        self.units = self.program().units()
        self._runner = None

    def program(self):
        raise NotImplementedError

    def _run(self, keys, want=()):
        if self.backend_used == "opencl":
            if self._runner is None:
                from .cl import Runner
                self._runner = Runner(self.units)
            return self._runner.run(keys, self.seed32, self.perm, want)
        from .execute import Runner
        return Runner(self.units).run(keys, self.seed32, self.perm, want)

    def _batches(self, keys, want=()):
        keys = [(int(a), int(b)) for a, b in keys]
        step = self.batch_cl if self.backend_used == "opencl" else self.batch_np
        for i in range(0, len(keys), step):
            yield self._run(keys[i:i + step], want)

    def generate(self, keys):
        out = []
        for flat, _ in self._batches(keys):
            out += [np.asarray(f).reshape(C.SHAPE, order="F") for f in flat]
        return out

    def columns(self, keys, names):
        """2D values (e.g. groundZ, biome factors) per key: {name: [(16, 16) arrays]}."""
        res = {n: [] for n in names}
        for _, got in self._batches(keys, names):
            for n in names:
                res[n] += list(np.ascontiguousarray(got[n]))
        return res
