"""Generators written in the pass language: backend choice, batching, results.

A subclass implements `program()` -> lang.Program (built from self.params); this
class runs it with NumPy or OpenCL, in batches, and cuts the result into chunks.
"""
from __future__ import annotations

import threading

import numpy as np

from .. import opencl
from ..core import chunk as C
from ..core.blocks import REGISTRY
from . import noise
from .base import Generator
from .lower import lower, prune

BACKENDS = opencl.BACKENDS


class PassGenerator(Generator):
    batch_cl = 64   # chunks per kernel launch
    batch_np = 4    # chunks per NumPy evaluation (bounds temporary memory)
    # far terrain (surface): the 2D fields with the ground height and its block; a
    # program without the first has no far surface, without the second it is grass
    surface_fields = ("groundZ", "top")
    # columns per evaluation (NumPy's single-column passes: ~2 k columns spent more in
    # Python's per-node steps than 16 k, in ~30 MiB of temporaries)
    surface_batch = {"opencl": 16384, "numpy": 16384}

    def __init__(self, seed, params=None, backend=None, version=None):
        self._asked = backend
        super().__init__(seed, params, backend, version)
        opencl.pick(backend, "generation")  # an unknown or unusable one: refused now
        self.seed32 = noise.seed32(self.seed)
        self.perm = noise.perm_table(self.seed32)
        self.units = lower(self.program())
        self._runner = None
        self._surf = None
        self._surf_lock = threading.Lock()
        # prebuild_surface: its build runs (_surf_building), and until warm_surface
        # launched the kernels once (_surf_held) surface() runs NumPy's twin: pocl's one
        # in-order queue would put the far batches and their first launch's
        # work-group build in front of (or behind) the near view's kernels
        self._surf_building = self._surf_held = False
        self._surf_built = threading.Condition(self._surf_lock)
        self._surf_run: dict = {}  # backend -> the lock its runner runs under

    def program(self):
        raise NotImplementedError

    # Asked for no backend: OpenCL where present, decided per batch, so a generator
    # made before a warm-up (opencl.warm) runs NumPy until the kernels are built.
    @property
    def backend_used(self) -> str:
        return opencl.pick(self._asked, "generation")

    @property
    def backend(self) -> str:
        return self.backend_used

    @backend.setter
    def backend(self, value) -> None:  # Generator.__init__'s; the choice is _asked
        pass

    def _run(self, keys, want=(), backend="numpy"):
        from ..core import trace
        with trace.span("generate", backend=backend, n=len(keys)):  # (VOXEL_TRACE)
            return self._run_on(keys, want, backend)

    def _run_on(self, keys, want, backend):
        if backend == "opencl":
            if self._runner is None:
                from .cl import shared
                self._runner = shared(self.units)
            return self._runner.run(keys, self.seed32, self.perm, want)
        from .execute import Runner
        return Runner(self.units).run(keys, self.seed32, self.perm, want)

    def _batches(self, keys, want=()):
        keys = [(int(a), int(b)) for a, b in keys]
        i = 0
        while i < len(keys):
            be = self.backend_used
            step = self.batch_cl if be == "opencl" else self.batch_np
            yield self._run(keys[i:i + step], want, be)
            i += step

    def warm_opencl(self, keys) -> list:
        """generate(keys) on OpenCL whatever the default (world.build.warm). Another
        generator of the same program shares the build (clsource.source writes the same
        text; the ~5 s recompiles once blamed on new kernel objects were new sources)."""
        flat, _ = self._run([(int(a), int(b)) for a, b in keys], (), "opencl")
        return [np.asarray(f).reshape(C.SHAPE, order="F") for f in flat]

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

    # ---- far terrain ----------------------------------------------------------
    def surface_wants(self) -> list[str]:
        """The 2D fields `surface_from` reads (present in the program)."""
        have = {n for u in self.units if u.kind == "2d" for n in u.outs}
        return [n for n in self.surface_fields if n in have]

    def surface_from(self, f: dict) -> dict:
        """Generator.surface's values from the fields of surface_wants at the columns.
        Water: up to `sea_level` (when the generator has one) above lower ground."""
        h = f[self.surface_fields[0]].astype(np.int32)
        top = f.get(self.surface_fields[1])
        top = np.full(h.shape, REGISTRY.id("grass"), np.int32) if top is None \
            else top.astype(np.int32)
        sea = self.params.get("sea_level")
        water = np.full(h.shape, -1, np.int32) if sea is None \
            else np.where(h < int(sea), np.int32(sea), np.int32(-1))
        return {"height": h, "top": top, "water": water,
                "trees": np.zeros(h.shape, np.float32)}

    def surface(self, xy):
        """Generator.surface from the 2D passes alone (lower.prune: no 3D pass, only
        the halos the wanted fields need), evaluated on 1-column domains, so the
        height and block are exactly those of the generated chunk's column."""
        return self._surface(xy, None)

    def warm_surface(self) -> bool:
        """surface() once on OpenCL whatever the default, building the program and the
        kernel objects that surface() keeps for later calls (world.build.warm: the far
        ring's first tiles need not wait ~1.5-5 s for pocl); False when this generator
        has no far surface."""
        # a whole batch: pocl's work-group code for a small grid was not reused for a
        # batch's (the first far batch after a 64-column warm-up still took ~1.1 s)
        n = self.surface_batch["opencl"]
        try:
            return self._surface(np.stack([np.arange(n), np.zeros(n, np.int64)], 1),
                                 "opencl") is not None
        finally:
            self._surf_held = False  # launched (or failed: surface() then raises it)

    def prebuild_surface(self, before=None) -> bool:
        """Build surface()'s OpenCL program and kernel objects now, launching nothing
        (world.build.warm, as a world opens: the build takes no queue and no build
        lock); surface() calls asked for no backend run NumPy (the same values) from
        this call until warm_surface has launched it once (world.build.warm's later
        part, when the streams have all they want). BEFORE() (if given) runs between
        that claim and the build (world.build waits there for the near view's kernels:
        pocl compiles one thing at a time). False when there is nothing to build (no
        far surface, no device, built already)."""
        want = self.surface_wants()
        if self.surface_fields[0] not in want or not opencl.available():
            return False
        with self._surf_lock:
            if self._surf_building or (self._surf or {}).get("opencl") is not None:
                return False
            self._surf_building = self._surf_held = True
        try:
            from ..core import trace
            from .cl import Runner
            if before is not None:
                before()
            with trace.span("far.prebuild"):
                run = Runner(prune(self.units, want), 1)
            with self._surf_lock:
                self._surf = {**(self._surf or {}), "opencl": run}
        finally:
            with self._surf_lock:
                self._surf_building = False
                self._surf_built.notify_all()
        return True

    def _surface(self, xy, backend):
        want = self.surface_wants()
        if self.surface_fields[0] not in want:
            return None
        xy = np.asarray(xy, np.int64).reshape(-1, 2)
        with self._surf_lock:
            be = backend or self.backend_used
            if self._surf is None:
                self._surf = {}
            run = self._surf.get(be)
            if be == "opencl" and backend is None and self._surf_held:
                be = "numpy"  # built in the background, not launched yet: NumPy's twin
                run = self._surf.get(be)
            elif run is None and be == "opencl" and self._surf_building:
                # asked for OpenCL by name (warm_surface): that build, not another
                self._surf_built.wait_for(lambda: not self._surf_building)
                run = self._surf.get(be)
            if run is None:
                units = prune(self.units, want)
                if be == "opencl":
                    from .cl import Runner
                else:
                    from .execute import Runner
                run = self._surf[be] = Runner(units, 1)
            # each runner alone (its kernel objects and buffers are not re-entrant),
            # but a NumPy far tile need not wait for warm_surface's first OpenCL launch
            lock = self._surf_run.setdefault(be, threading.Lock())
        with lock:
            step = self.surface_batch[be]
            parts = [run.at(xy[i:i + step], self.seed32, self.perm, want)
                     for i in range(0, len(xy), step)]
        f = {n: np.concatenate([p[n].reshape(-1) for p in parts]) if parts
             else np.zeros(0, np.int32) for n in want}
        return self.surface_from(f)

