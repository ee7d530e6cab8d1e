"""Compiles a lang.Program to OpenCL C (one kernel per unit, appended to gpu/gen.cl)
and runs it on batches of chunks.

Every node becomes one C statement doing exactly the float32 operation NumPy does
(np_exec); constants are written as hex floats so no decimal rounding sneaks in.
"""
from __future__ import annotations

import numpy as np

from .. import opencl, resources
from ..core import chunk as C
from .lang import Unit, nodes

# No fast-math, no mad: IEEE results identical to NumPy's (see gpu/noise.h).
OPTIONS = ("-cl-fp32-correctly-rounded-divide-sqrt",)
CT = {"f": "float", "i": "int", "b": "int", "f3": "float3"}
LOCAL2D, LOCAL3D = 64, 256


def _lit(e):
    if e.t == "f":
        v = float(np.float32(e.k))
        if v != v or v in (float("inf"), float("-inf")):
            raise ValueError("non-finite constant")
        return f"({v.hex()}f)"
    if e.t == "b":
        return "1" if e.k else "0"
    return f"({int(e.k)})"


_BIN = {"add": "+", "sub": "-", "mul": "*", "div": "/", "lt": "<", "le": "<=", "gt": ">",
        "ge": ">=", "eq": "==", "ne": "!=", "and": "&&", "or": "||"}


class _Gen:
    def __init__(self, units):
        self.units = units
        self.fields = {}  # name -> (type, halo)
        for u in units:
            if u.kind == "2d":
                for n, e in u.outs.items():
                    self.fields[n] = (e.t, u.halo)

    def expr(self, e, a, unit):
        op, k = e.op, e.k
        if op == "const":
            return _lit(e)
        if op in ("x", "y", "z"):
            return op
        if op in _BIN:
            return f"({a[0]} {_BIN[op]} {a[1]})"
        if op == "neg":
            return f"(-{a[0]})"
        if op == "not":
            return f"(!{a[0]})"
        if op in ("min", "max"):
            return f"{'f' if e.t == 'f' else ''}{op}({a[0]}, {a[1]})"
        if op == "abs":
            return f"fabs({a[0]})" if e.t == "f" else f"vx_iabs({a[0]})"
        if op in ("floor", "sqrt"):
            return f"{op}({a[0]})"
        if op == "int":
            return f"((int){a[0]})"
        if op == "float":
            return f"((float){a[0]})"
        if op == "fdiv":
            return f"vx_fdiv({a[0]}, {k})"
        if op == "fmod":
            return f"vx_fmod({a[0]}, {k})"
        if op == "select":
            return f"({a[0]} ? {a[1]} : {a[2]})"
        if op == "get":
            return f"{a[0]}.{'xyz'[k]}"
        if op == "perlin2":
            return f"perlin2({a[0]}, {a[1]}, perm, s{k})"
        if op == "perlin3":
            return f"perlin3({a[0]}, {a[1]}, {a[2]}, perm, s{k})"
        if op == "voronoi2":
            return f"voronoi2({a[0]}, {a[1]}, {k[1]}, s{k[0]})"
        if op == "voronoi3":
            return f"voronoi3({a[0]}, {a[1]}, {a[2]}, {k[1]}, s{k[0]})"
        if op == "rand2":
            return f"vx_unit(vx_hash2({a[0]}, {a[1]}, s{k}))"
        if op == "rand3":
            return f"vx_unit(vx_hash3({a[0]}, {a[1]}, {a[2]}, s{k}))"
        if op == "irand2":
            return f"((int)((vx_hash2({a[0]}, {a[1]}, s{k[0]}) >> 8) % {k[1]}u))"
        if op == "read":
            name, dx, dy, reach = k
            _, hf = self.fields[name]
            wf = C.SIZE + 2 * hf
            if dx is None:
                dx = f"min(max({a[0]}, {-reach}), {reach})"
                dy = f"min(max({a[1]}, {-reach}), {reach})"
            return f"f_{name}[c * {wf * wf} + (ly + {hf} + ({dy})) * {wf} + (lx + {hf} + ({dx}))]"
        if op == "prev":
            return (f"((z + {k}) >= 0 && (z + {k}) < {C.HEIGHT} ? "
                    f"(int)prev[gid + {k * C.SIZE * C.SIZE}] : 0)")
        raise ValueError(f"unknown op {op}")

    def body(self, roots, unit, done):
        lines = []
        for e in nodes(roots):
            if e.id in done:
                continue
            done[e.id] = f"v{e.id}"
            a = [done[x.id] for x in e.a]
            lines.append(f"    {CT[e.t]} v{e.id} = {self.expr(e, a, unit)};")
        return lines

    def reads(self, roots):
        names = []
        for e in nodes(roots):
            if e.op == "read" and e.k[0] not in names:
                names.append(e.k[0])
        return names

    def salts(self, roots):
        s = set()
        for e in nodes(roots):
            if e.op in ("perlin2", "perlin3", "rand2", "rand3"):
                s.add(e.k)
            elif e.op in ("voronoi2", "voronoi3", "irand2"):
                s.add(e.k[0])
        return [f"    uint s{k} = vx_inst(seed, {k}u);" for k in sorted(s)]

    def kernel(self, i, u: Unit):
        roots = u.roots()
        args = ["__global const int* org", "__constant const int* perm", "uint seed", "int n"]
        if u.kind == "2d":
            args += [f"__global {CT[e.t]}* o_{n}" for n, e in u.outs.items()]
        else:
            args += ["__global ushort* blocks", "__global const ushort* prev"]
        ins = self.reads(roots)
        args += [f"__global const {CT[self.fields[n][0]]}* f_{n}" for n in ins]
        out = [f"__kernel void unit{i}({', '.join(args)}) {{", "    int gid = get_global_id(0);"]
        if u.kind == "2d":
            w = C.SIZE + 2 * u.halo
            out += [f"    if (gid >= n * {w * w}) return;",
                    f"    int c = gid / {w * w}, r = gid - c * {w * w};",
                    f"    int lx = r % {w} - {u.halo}, ly = r / {w} - {u.halo};"]
        else:
            out += [f"    if (gid >= n * {C.VOLUME}) return;",
                    "    int c = gid >> 16, r = gid & 65535;",
                    "    int lx = r & 15, ly = (r >> 4) & 15, z = r >> 8;"]
        out += ["    int x = org[2 * c] + lx, y = org[2 * c + 1] + ly;"]
        out += self.salts(roots)
        done = {}
        if u.kind == "2d":
            out += self.body(roots, u, done)
            out += [f"    o_{n}[gid] = {done[e.id]};" for n, e in u.outs.items()]
        else:
            if u.top is not None:
                out += self.body([u.top], u, done)
                out += [f"    if (z > {done[u.top.id]}) {{ blocks[gid] = 0; return; }}"]
            out += self.body([u.blk], u, done)
            out += [f"    blocks[gid] = (ushort){done[u.blk.id]};"]
        return "\n".join(out + ["}", ""])


def source(units) -> str:
    g = _Gen(units)
    return resources.kernel("gen.cl") + "\n".join(g.kernel(i, u) for i, u in enumerate(units))


class Runner:
    """A compiled program; `run(keys, seed32, perm)` like np_exec.Run.run."""

    def __init__(self, units):
        import pyopencl as cl
        self.units = units
        self.src = source(units)
        self.ctx, self.queue, _ = opencl.context()
        prog = opencl.build(self.src, OPTIONS)
        self.kernels = [cl.Kernel(prog, f"unit{i}") for i in range(len(units))]
        self.gen = _Gen(units)
        self._perm = {}

    def _perm_buf(self, seed32, perm):
        import pyopencl as cl
        b = self._perm.get(seed32)
        if b is None:
            if len(self._perm) > 8:
                self._perm.clear()
            b = self._perm[seed32] = cl.Buffer(self.ctx, cl.mem_flags.READ_ONLY |
                                               cl.mem_flags.COPY_HOST_PTR, hostbuf=perm)
        return b

    def run(self, keys, seed32, perm, want=()):
        import pyopencl as cl
        mf = cl.mem_flags
        q, n = self.queue, len(keys)
        org = (np.array(keys, np.int64).reshape(-1, 2) * C.SIZE).astype(np.int32)
        borg = cl.Buffer(self.ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=org)
        bperm = self._perm_buf(seed32, perm)
        fields, blocks, prev = {}, None, None
        dummy = cl.Buffer(self.ctx, mf.READ_WRITE, 2)
        for i, u in enumerate(self.units):
            k = self.kernels[i]
            args = [borg, bperm, np.uint32(seed32), np.int32(n)]
            if u.kind == "2d":
                w = C.SIZE + 2 * u.halo
                for name in u.outs:
                    fields[name] = (cl.Buffer(self.ctx, mf.READ_WRITE, 4 * n * w * w), u.halo)
                    args.append(fields[name][0])
                size, local = n * w * w, LOCAL2D
            else:
                prev = blocks
                blocks = cl.Buffer(self.ctx, mf.READ_WRITE, 2 * n * C.VOLUME)
                args += [blocks, prev if prev is not None else dummy]
                size, local = n * C.VOLUME, LOCAL3D
            args += [fields[name][0] for name in self.gen.reads(u.roots())]
            k.set_args(*args)
            cl.enqueue_nd_range_kernel(q, k, (-(-size // local) * local,), (local,))
        out = np.zeros((n, C.VOLUME), np.uint16)
        if blocks is not None:
            cl.enqueue_copy(q, out, blocks)
        got = {}
        for name in want:
            buf, h = fields[name]
            w = C.SIZE + 2 * h
            t = np.float32 if self.gen.fields[name][0] == "f" else np.int32
            a = np.empty((n, w, w), t)
            cl.enqueue_copy(q, a, buf)
            got[name] = a.transpose(0, 2, 1)[:, h:h + C.SIZE, h:h + C.SIZE]
        q.finish()
        return out, got
