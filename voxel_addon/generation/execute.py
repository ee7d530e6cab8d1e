"""Runs a lang.Program with NumPy: the reference backend (cl.py is its OpenCL twin).

Values are arrays that broadcast over (chunk, x, y[, z]); a value that depends only
on x stays (n, W, 1), so column math is not repeated per voxel. Each node is
computed once and dropped after its last use.
"""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from . import noise as N
from .lang import Unit, nodes

F, I = np.float32, np.int32
DT = {"f": F, "i": I, "b": bool}


class Runner:
    """Evaluates the units of one program for groups of chunk origins (cl.Runner is
    its OpenCL twin, with the same calls). `size`: the side of one domain in columns;
    chunks are 16, far terrain evaluates 2D units on 1-column domains (`at`)."""

    def __init__(self, units: list[Unit], size: int = C.SIZE):
        self.units, self.size = units, int(size)

    def run(self, keys, seed32: int, perm: np.ndarray, want=()):
        """Blocks (n, 65536) uint16 in linear order, and the 2D fields named in want
        as (n, 16, 16) [c, x, y] arrays."""
        if self.size != C.SIZE:
            raise ValueError("Runner.run makes chunks: size must be 16")
        self._start(np.array(keys, np.int64).reshape(-1, 2) * C.SIZE, seed32, perm)
        blocks = None
        with np.errstate(all="ignore"):  # unselected branches may divide by zero
            for u in self.units:
                if u.kind == "2d":
                    self._unit2d(u)
                else:
                    blocks = self._unit3d(u, blocks)
        if blocks is None:
            blocks = np.zeros((self.n,) + C.SHAPE, np.uint16)
        # (n, 65536) in each chunk's linear order, like the OpenCL buffer
        flat = blocks.transpose(0, 3, 2, 1).reshape(self.n, C.VOLUME)
        return flat, {k: self.field(k) for k in want}

    def at(self, org, seed32: int, perm: np.ndarray, want=()):
        """The 2D fields named in want, (n, size, size) [c, x, y], over the domains
        whose first column is org (n, 2) (every unit must be 2D: lang.prune)."""
        self._start(np.asarray(org, np.int64).reshape(-1, 2), seed32, perm)
        with np.errstate(all="ignore"):
            for u in self.units:
                if u.kind != "2d":
                    raise ValueError("Runner.at evaluates 2D units only (lang.prune)")
                self._unit2d(u)
        return {k: np.ascontiguousarray(self.field(k)) for k in want}

    def _start(self, org, seed32, perm):
        self.seed, self.perm = seed32, perm
        self.ox = org[:, 0].astype(I)
        self.oy = org[:, 1].astype(I)
        self.n = len(org)
        self.fields: dict[str, tuple[np.ndarray, int]] = {}

    def field(self, name):
        """A 2D field over the domain itself, (n, size, size) [c, x, y]."""
        a, h = self.fields[name]
        return a[:, h:h + self.size, h:h + self.size]

    # ---- domains ----------------------------------------------------------
    def _unit2d(self, u: Unit):
        h, n = u.halo, self.n
        w = self.size + 2 * h
        lx = np.arange(w, dtype=I) - I(h)
        self.dom = dict(kind="2d", halo=h, w=w,
                        c=np.arange(n)[:, None, None], lx=lx[None, :, None], ly=lx[None, None, :],
                        x=self.ox[:, None, None] + lx[None, :, None],
                        y=self.oy[:, None, None] + lx[None, None, :])
        vals = self._eval(list(u.outs.values()))
        for name, e in u.outs.items():
            a = np.broadcast_to(vals[e.id], (n, w, w)).astype(DT[e.t])
            self.fields[name] = (a, h)

    def _unit3d(self, u: Unit, prev):
        n, s = self.n, C.SIZE
        lx = np.arange(s, dtype=I)
        base = dict(kind="3d", halo=0, w=s, c=np.arange(n)[:, None, None, None],
                    lx=lx[None, :, None, None], ly=lx[None, None, :, None],
                    x=self.ox[:, None, None, None] + lx[None, :, None, None],
                    y=self.oy[:, None, None, None] + lx[None, None, :, None])
        self.dom = base
        self.prev = prev
        if u.top is not None:
            top = self.field(u.top)[..., None]
            zn = int(np.clip(top.max(), -1, C.HEIGHT - 1)) + 1
        else:
            top, zn = None, C.HEIGHT
        out = np.zeros((n, s, s, C.HEIGHT), np.uint16)
        if zn > 0:
            self.dom = dict(base, z=np.arange(zn, dtype=I)[None, None, None, :])
            b = np.broadcast_to(self._eval([u.blk])[u.blk.id], (n, s, s, zn))
            if top is not None:
                b = np.where(self.dom["z"] <= top, b, 0)
            out[..., :zn] = b
        return out

    # ---- expression evaluation ----------------------------------------------
    def _eval(self, roots):
        order = nodes(roots)
        uses: dict[int, int] = {}
        for e in order:
            for a in e.a:
                uses[a.id] = uses.get(a.id, 0) + 1
        keep = {r.id for r in roots}
        v: dict[int, object] = {}
        for e in order:
            v[e.id] = self._op(e, [v[a.id] for a in e.a])
            for a in e.a:
                uses[a.id] -= 1
                if uses[a.id] == 0 and a.id not in keep:
                    del v[a.id]
        return v

    def _op(self, e, a):
        op, k, d = e.op, e.k, self.dom
        if op == "const":
            return DT[e.t](k)
        if op in ("x", "y", "z"):
            return d[op]
        if op == "read":
            return self._read(e, a)
        if op == "prev":
            return self._prev(k)
        f = _OPS.get(op)
        if f is not None:
            return f(*a)
        if op == "fdiv":
            return a[0] // I(k)
        if op == "fmod":
            return a[0] % I(k)
        if op == "get":
            return a[0][k]
        if op == "min":  # as vx_fmin / vx_imin: b < a ? b : a (NaN and -0 included)
            return np.where(a[1] < a[0], a[1], a[0]) if e.t == "f" else np.minimum(*a)
        if op == "max":
            return np.where(a[1] > a[0], a[1], a[0]) if e.t == "f" else np.maximum(*a)
        if op == "perlin2":
            return N.perlin2(a[0], a[1], self.perm, N.inst(self.seed, k))
        if op == "perlin3":
            return N.perlin3(a[0], a[1], a[2], self.perm, N.inst(self.seed, k))
        if op == "voronoi2":
            return N.voronoi2(a[0], a[1], N.inst(self.seed, k[0]), k[1])
        if op == "voronoi3":
            return N.voronoi3(a[0], a[1], a[2], N.inst(self.seed, k[0]), k[1])
        if op == "rand2":
            return N.unit(N.hash2(a[0], a[1], N.inst(self.seed, k)))
        if op == "rand3":
            return N.unit(N.hash3(a[0], a[1], a[2], N.inst(self.seed, k)))
        if op == "irand2":
            h = N.hash2(a[0], a[1], N.inst(self.seed, k[0])) >> np.uint32(8)
            return (h % np.uint32(k[1])).astype(I)
        raise ValueError(f"unknown op {op}")

    def _read(self, e, a):
        name, dx, dy, reach = e.k
        arr, hf = self.fields[name]
        d = self.dom
        off = hf - d["halo"]
        if dx is not None:  # constant offset: a slice
            w = d["w"]
            r = arr[:, off + dx:off + dx + w, off + dy:off + dy + w]
            return r[..., None] if d["kind"] == "3d" else r
        ix = d["lx"] + I(hf) + np.clip(a[0], -reach, reach)
        iy = d["ly"] + I(hf) + np.clip(a[1], -reach, reach)
        return arr[d["c"], ix, iy]

    def _prev(self, dz):
        z = self.dom["z"][0, 0, 0]
        src = z + dz
        ok = (src >= 0) & (src < C.HEIGHT)
        out = np.zeros(self.prev.shape[:3] + (len(z),), I)
        out[..., ok] = self.prev[..., src[ok]]
        return out


_OPS = {
    "add": lambda a, b: a + b, "sub": lambda a, b: a - b, "mul": lambda a, b: a * b,
    "div": lambda a, b: a / b, "neg": lambda a: -a, "abs": np.abs,
    "floor": np.floor, "sqrt": np.sqrt,
    "int": lambda a: np.asarray(a).astype(I), "float": lambda a: np.asarray(a).astype(F),
    "lt": lambda a, b: a < b, "le": lambda a, b: a <= b, "gt": lambda a, b: a > b,
    "ge": lambda a, b: a >= b, "eq": lambda a, b: a == b, "ne": lambda a, b: a != b,
    "and": np.logical_and, "or": np.logical_or, "not": np.logical_not,
    "select": lambda c, a, b: np.where(c, a, b),
}
