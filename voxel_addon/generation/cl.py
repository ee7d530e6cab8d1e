"""Runs a lang.Program's OpenCL kernels (clsource.py writes them) on batches of
chunks: the OpenCL twin of execute.Runner, with the same calls."""
from __future__ import annotations

import threading
import time

import numpy as np

from .. import opencl
from ..core import chunk as C
from .clscalar import LAYER, LOCAL2D, OPTIONS, VLANES, VLOCAL, _Gen, _pad, g3_row
from .clsource import source
from .clvector import vectorizable
from .lower import lattice_dims, levels, shape

SMALL_GRID = 65535  # work items: pocl's small-grid work-group variant (Runner._launch)
_SHARED: dict = {}  # lower.shape(units) -> Runner (shared)
_SHARED_LOCK = threading.Lock()
SHARED_MAX = 2  # programs kept (each holds its device buffers: ~20 MB at 64 chunks)


def shared(units) -> "Runner":
    """The process's Runner of a chunk program: a new world's generator has its own
    units (fresh node ids) of the same program, and writing their OpenCL source again
    cost ~40 ms of CPU in a new world's first batch (~4 % of a view-12 stream)."""
    key = shape(units)
    with _SHARED_LOCK:
        r = _SHARED.get(key)
        if r is None:
            if len(_SHARED) >= SHARED_MAX:
                _SHARED.clear()
            r = _SHARED[key] = Runner(units)
        return r


class Runner:
    """A compiled program; the OpenCL twin of execute.Runner (the same calls)."""

    def __init__(self, units, size=C.SIZE):
        import pyopencl as cl
        self.units, self.size = units, int(size)
        # chunks' programs call their big noise functions (a fresh install builds them
        # on the way to its first picture); the far surface's (1-column domains, built
        # in the background, run on 16384-column batches) inlines them: clsource.called
        self.src = source(units, self.size, inline=self.size != C.SIZE)
        self.ctx, self.queue, _ = opencl.context()
        # the far surface's builds alone (world.build.warm starts it as a world opens)
        prog = opencl.build(self.src, OPTIONS, alone=self.size != C.SIZE)
        self.kernels = [cl.Kernel(prog, f"unit{i}") for i in range(len(units))]
        self.gen = _Gen(units, self.size)
        # fields each unit reads: walking the expression graph per batch cost ~5 % of
        # a batch's time in Python (the GIL the stream's light solve wants)
        self._reads = [self.gen.reads(u) for u in units]
        self._vec = [vectorizable(u, self.size) for u in units]
        self._perm = {}
        self._bufs = {}
        self.timings = None  # set to a dict to collect seconds per unit (serialises the queue)
        self._lock = threading.Lock()  # kernels' arguments and buffers: one batch at a time

    def _perm_buf(self, seed32, perm):
        import pyopencl as cl
        b = self._perm.get(seed32)
        if b is None:
            if len(self._perm) > 8:
                self._perm.clear()
            b = self._perm[seed32] = cl.Buffer(self.ctx, cl.mem_flags.READ_ONLY |
                                               cl.mem_flags.COPY_HOST_PTR, hostbuf=perm)
        return b

    def _buf(self, key, nbytes):
        """A device buffer reused across batches (grown when a batch needs more)."""
        import pyopencl as cl
        b = self._bufs.get(key)
        if b is None or b.size < nbytes:
            b = self._bufs[key] = cl.Buffer(self.ctx, cl.mem_flags.READ_WRITE, max(nbytes, 4))
        return b

    def _zmax(self, u, fields, n, tops=None):
        """Each chunk's highest z a unit computes (its top's maximum), (n,)."""
        if u.top is None:
            return np.full(n, C.HEIGHT - 1)
        if tops is None or u.top not in tops:
            top = self._read_field(u.top, fields, n)
            zmax = np.clip(top.reshape(n, -1).max(axis=1), -1, C.HEIGHT - 1)
            if tops is None:
                return zmax
            tops[u.top] = zmax
        return tops[u.top]

    def _launch(self, i, k, args, size, local, lay, at):
        """Kernel K over SIZE work items; a layer-indexed unit (LAY: one entry per
        work-group, its buffer at args[AT]) in pieces of at most SMALL_GRID items:
        pocl compiles another work-group variant for a wider grid (~0.4-0.5 s of the
        first 30-chunk batch's CPU, issue 28), and the warm-up's 3 x 3 chunks compile
        only this one. A group reads only its own layers entry: same values."""
        import pyopencl as cl
        q = self.queue
        if lay is None:
            k.set_args(*args)
            cl.enqueue_nd_range_kernel(q, k, (size,), (local,))
            return
        b = self._buf(f"layers{i}", lay.nbytes)
        cl.enqueue_copy(q, b, lay)
        # pieces as sub-buffers of one upload (one blocking write per unit, as before);
        # a sub-buffer starts at a multiple of the device's base address alignment
        step = max(1, opencl.context()[2].mem_base_addr_align // 8 // lay.itemsize)
        per = max(step, SMALL_GRID // local // step * step)
        for j in range(0, len(lay), per):
            m = min(per, len(lay) - j)
            args[at] = b if m == len(lay) else b.get_sub_region(j * lay.itemsize,
                                                                 m * lay.itemsize)
            k.set_args(*args)
            cl.enqueue_nd_range_kernel(q, k, (m * local,), (local,))

    def _levels(self, u, fields, n, tops):
        """(chunk, level) pairs of a lattice unit: the levels below each chunk's top."""
        k = np.array([levels(u.cell, t) for t in self._zmax(u, fields, n, tops)], np.int64)
        cs = np.repeat(np.arange(n), k)
        ks = np.concatenate([np.arange(m) for m in k]) if n else cs
        return (cs * 256 + ks).astype(np.int32)

    def _layers(self, u, fields, n, tops=None):
        """(chunk, z) pairs to compute for a 3D unit: z up to the chunk's highest top."""
        zmax = self._zmax(u, fields, n, tops)
        cs = np.repeat(np.arange(n), zmax + 1)
        zs = np.concatenate([np.arange(m + 1) for m in zmax]) if n else cs
        return (cs * 256 + zs).astype(np.int32)

    def _read_field(self, name, fields, n):
        import pyopencl as cl
        buf, h = fields[name]
        w, s = self.size + 2 * h, self.size
        t = np.float32 if self.gen.fields[name][0] == "f" else np.int32
        a = np.empty((n, w, w), t)
        cl.enqueue_copy(self.queue, a, buf)  # blocking
        return a.transpose(0, 2, 1)[:, h:h + s, h:h + s]

    def at(self, org, seed32, perm, want=()):
        """execute.Runner.at: 2D fields over the domains whose first column is org."""
        if any(u.kind != "2d" for u in self.units):
            raise ValueError("Runner.at evaluates 2D units only (lower.prune)")
        org = np.asarray(org, np.int64).reshape(-1, 2)
        with self._lock:
            _, got = self._go(org.T.astype(np.int32).copy(), seed32, perm, want, chunks=False)
        return {k: np.ascontiguousarray(v) for k, v in got.items()}

    def run(self, keys, seed32, perm, want=()):
        if self.size != C.SIZE:
            raise ValueError("Runner.run makes chunks: size must be 16")
        org = (np.array(keys, np.int64).reshape(-1, 2).T * C.SIZE).astype(np.int32).copy()
        with self._lock:  # (a shared runner: generators of several worlds)
            return self._go(org, seed32, perm, want)

    def _go(self, org, seed32, perm, want, chunks=True):
        import pyopencl as cl
        q, n = self.queue, org.shape[1]
        borg = self._buf("org", org.nbytes)
        cl.enqueue_copy(q, borg, org)
        bperm = self._perm_buf(seed32, perm)
        fields, blocks, prev = {}, None, None
        tops: dict = {}  # top field -> its values, read back once per batch
        nb = 0  # which of the two block buffers is next
        for i, u in enumerate(self.units):
            k = self.kernels[i]
            args = [borg, bperm, np.uint32(seed32), np.int32(n)]
            if u.kind in ("g3", "gc"):
                ni, nj, nk = lattice_dims(u.cell)
                lay = self._levels(u, fields, n, tops)
                pts = LAYER if u.kind == "gc" else g3_row(u.cell)
                local = pts if u.kind == "gc" or not self._vec[i] else pts // VLANES
                size = len(lay) * local
                at = len(args)  # the layers' buffer: _launch fills it per piece
                args.append(None)
                for name in u.outs:
                    fields[name] = (self._buf(f"f_{name}", 4 * n * nk * pts), None)
                    args.append(fields[name][0])
            elif u.kind == "2d":
                w = self.size + 2 * u.halo
                size = _pad(n * w * w, LOCAL2D)
                for name in u.outs:
                    fields[name] = (self._buf(f"f_{name}", 4 * size), u.halo)
                    args.append(fields[name][0])
                if self._vec[i]:  # _GenV.kernel_2d: 8 items per work-item
                    size = _pad(n * (_pad(w * w, VLANES) // VLANES), LOCAL2D)
                local, lay, at = LOCAL2D, None, None
            else:
                lay = self._layers(u, fields, n, tops)
                prev = blocks
                blocks = self._buf(f"blocks{nb}", 2 * n * C.VOLUME)
                nb ^= 1
                cl.enqueue_fill_buffer(q, blocks, np.uint16(0), 0, 2 * n * C.VOLUME)
                at = len(args)
                args += [None, blocks, prev if prev is not None else self._buf("dummy", 2)]
                local = VLOCAL if self._vec[i] else LAYER
                size = len(lay) * local
            args += [fields[name][0] for name in self._reads[i]]
            if size == 0:
                continue
            t0 = time.perf_counter()
            self._launch(i, k, args, size, local, lay, at)
            if self.timings is not None:
                q.finish()
                key = f"unit{i} {u.kind} {'+'.join(u.outs) or 'blocks'}"
                self.timings[key] = self.timings.get(key, 0.0) + time.perf_counter() - t0
        # Runner.at wants no blocks: a zeroed (n, VOLUME) array here was 2 GiB per
        # 16384-column surface batch, free in a venv (calloc's untouched pages) but ~1 s
        # of page zeroing per batch under Blender's allocator (issue 28)
        out = np.zeros((n, C.VOLUME) if chunks else (n, 0), np.uint16)
        if blocks is not None and chunks:
            cl.enqueue_copy(q, out, blocks)
        got = {name: self._read_field(name, fields, n) for name in want}
        q.finish()
        return out, got
