"""Runs a lang.Program with NumPy: the reference backend (cl.py is its OpenCL twin).

Values are arrays that broadcast over (chunk, x, y[, z]); a value that depends only
on x stays (n, W, 1), so column math is not repeated per voxel. Each node is
computed once and dropped after its last use.
"""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from . import noise as N
from .lower import Unit, lattice_dims, lazy_blocks, levels, nodes

F, I = np.float32, np.int32
DT = {"f": F, "i": I, "b": bool}
# Lazy operands (see Runner._eval): NumPy pays a gather per input, so only noise-sized
# operands are worth it, and only where they are needed on at most this share of voxels.
LAZY_COST = 20
LAZY_SHARE = 0.7


# _at_points: at least this many columns, a unit's fields wanted at fewer offsets
# (groundZ's neighbours) are evaluated apart; below it, Python's per-node steps
# cost more than the columns saved
SPLIT = 4096

_PLANS: dict = {}  # (LAZY_COST, root node ids: unique in a process) -> _plan's analysis


def _plan(roots):
    """What _eval needs of a graph, analysed once per unit: lazy blocks, the nodes
    computed at top level, what each consumes, and how often each is consumed."""
    key = (LAZY_COST,) + tuple(r.id for r in roots)
    if key in _PLANS:
        return _PLANS[key]
    order = nodes(roots)
    lazy, owner = lazy_blocks(order, roots, LAZY_COST)
    top = [e for e in order if e.id not in owner]
    deps = {}
    for e in top:
        d = {a.id for a in e.a}
        if e.id in lazy:  # a lazy node also consumes what its blocks read
            inner = [n for ms in lazy[e.id].values() for n in ms]
            d = {a.id for n in [e] + inner for a in n.a} - {n.id for n in inner}
        deps[e.id] = d
    count: dict[int, int] = {}
    for d in deps.values():
        for i in d:
            count[i] = count.get(i, 0) + 1
    if len(_PLANS) > 256:
        _PLANS.clear()
    _PLANS[key] = lazy, owner, top, deps, count
    return _PLANS[key]


class _Scope:
    """Values on a subset of the voxels: the root scope holds arrays that broadcast over
    the domain; a child holds 1D arrays over the voxels where its parent's mask is set."""

    def __init__(self, parent, mask, shape):
        self.parent, self.mask, self.v = parent, mask, {}
        self.shape = shape if parent is None else (int(np.count_nonzero(mask)),)

    def get(self, i):
        if i not in self.v:  # a value of an outer scope, gathered once
            self.v[i] = self._take(self.parent.get(i))
        return self.v[i]

    def _take(self, val):
        if isinstance(val, tuple):
            return tuple(self._take(x) for x in val)
        if np.ndim(val) == 0:
            return val
        return np.broadcast_to(val, self.parent.shape)[self.mask]

    def down(self, val):
        """A root-scope (domain) value on this scope's voxels."""
        return val if self.parent is None else self._take(self.parent.down(val))


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
                elif u.kind in ("g3", "gc"):
                    self._unitg3(u)
                else:
                    blocks = self._unit3d(u, blocks)
        if blocks is None:
            blocks = np.zeros((self.n,) + C.SHAPE, np.uint16)
        # (n, 65536) in each chunk's linear order, like the OpenCL buffer
        flat = blocks.transpose(0, 3, 2, 1).reshape(self.n, C.VOLUME)
        return flat, {k: self.field(k) for k in want}

    def at(self, org, seed32: int, perm: np.ndarray, want=()):
        """The 2D fields named in want, (n, size, size) [c, x, y], over the domains
        whose first column is org (n, 2) (every unit must be 2D: lower.prune)."""
        org = np.asarray(org, np.int64).reshape(-1, 2)
        st = self._stencils(want) if self.size == 1 else None
        if st is not None:
            return self._at_points(org, seed32, perm, want, st)
        self._start(org, seed32, perm)
        with np.errstate(all="ignore"):
            for u in self.units:
                if u.kind != "2d":
                    raise ValueError("Runner.at evaluates 2D units only (lower.prune)")
                self._unit2d(u)
        return {k: np.ascontiguousarray(self.field(k)) for k in want}

    # ---- single columns: only the points a reader needs ----------------------
    # A 1-column domain with halo h computes a unit on (2h+1)^2 columns, though its
    # readers may need fewer (the Overworld's slope reads groundZ at 4 neighbours:
    # 5 of 9, and there groundZ alone, not the unit's 6 other fields), and far samples
    # 2 apart share neighbours. Here each unit's fields are computed on the distinct
    # columns their readers' constant offsets reach: the same operations per column,
    # so the same values (far terrain's CPU on NumPy, issue 28).
    def _stencils(self, want):
        """Per unit {field: offsets (dx, dy) it is needed at around a column}, or None
        when a unit reads at a computed offset or uses its domain's layout."""
        if getattr(self, "_st_want", None) == tuple(want):
            return self._st
        need = {n: {(0, 0)} for n in want}
        out = []
        for u in reversed(self.units):
            if any(e.op in ("lx", "ly", "c") or e.op == "read" and e.k[1] is None
                   for e in nodes(u.roots())):
                out = None
                break
            st = {n: need[n] for n in u.outs if need.get(n)}
            for n, offs in st.items():
                for e in nodes([u.outs[n]]):
                    if e.op == "read":
                        _, dx, dy, _ = e.k
                        need.setdefault(e.k[0], set()).update((a + dx, b + dy) for a, b in offs)
            out.append(st)
        self._st_want, self._st = tuple(want), out and out[::-1]
        return self._st

    def _at_points(self, org, seed32, perm, want, st):
        self._start(org[:0], seed32, perm)
        self._pts: dict = {}  # field -> sorted keys of the columns it was computed on
        z = np.zeros(1, I)
        with np.errstate(all="ignore"):
            for u, need in zip(self.units, st):
                if not need:
                    continue
                if u.kind != "2d":
                    raise ValueError("Runner.at evaluates 2D units only (lower.prune)")
                groups: dict = {}  # the fields wanted at an offset -> those offsets
                for o in set().union(*need.values()):
                    fs = tuple(n for n in need if o in need[n]) if len(org) >= SPLIT \
                        else tuple(need)  # few columns: one evaluation costs less
                    groups.setdefault(fs, []).append(o)
                parts: dict = {n: [] for n in need}
                for names, offs in sorted(groups.items()):
                    off = np.array(sorted(offs), np.int64)
                    q = (org[:, None, :] + off[None]).reshape(-1, 2)
                    k, i = np.unique(_key(q), return_index=True)
                    q = q[i]
                    self.n = n = len(q)
                    self.ox, self.oy = q[:, 0].astype(I), q[:, 1].astype(I)
                    self.dom = dict(kind="2d", halo=0, w=1, pts=q,
                                    c=np.arange(n)[:, None, None], lx=z[None, :, None],
                                    ly=z[None, None, :], x=self.ox[:, None, None],
                                    y=self.oy[:, None, None])
                    vals = self._eval([u.outs[x] for x in names])
                    for x in names:
                        e = u.outs[x]
                        parts[x].append((k, np.broadcast_to(vals[e.id], (n, 1, 1)).astype(DT[e.t])))
                for x, got in parts.items():
                    k, v = got[0]
                    if len(got) > 1:  # the same column in two groups: one of its values
                        k, i = np.unique(np.concatenate([g[0] for g in got]), return_index=True)
                        v = np.concatenate([g[1] for g in got])[i]
                    self.fields[x], self._pts[x] = (v, 0), k
        out = {}
        for name in want:
            i = np.searchsorted(self._pts[name], _key(org))
            out[name] = np.ascontiguousarray(self.fields[name][0][i])
        return out

    def _start(self, org, seed32, perm):
        self.seed, self.perm = seed32, perm
        self.ox = org[:, 0].astype(I)
        self.oy = org[:, 1].astype(I)
        self.n = len(org)
        self.fields: dict[str, tuple[np.ndarray, int]] = {}
        self.grids: dict[str, np.ndarray] = {}  # g3 units: (n, ni, nj, nk) samples

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

    def _unitg3(self, u: Unit):
        """Coarse functions (lower.lattice): "g3" samples them at the lattice points of
        each chunk, (n, ni, nj, nk); "gc" interpolates those per column at each
        lattice level, (n, 16, 16, nk)."""
        n, (cx, cy, cz) = self.n, u.cell
        ni, nj, nk = lattice_dims(u.cell)
        if u.top is not None:  # the levels the 3D unit's voxels need (its zn: _unit3d)
            nk = max(levels(u.cell, np.clip(self.field(u.top).max(), -1, C.HEIGHT - 1)), 1)
        if u.kind == "gc":
            ni, nj, cx, cy = C.SIZE, C.SIZE, 1, 1
        li, lj = np.arange(ni, dtype=I) * I(cx), np.arange(nj, dtype=I) * I(cy)
        self.dom = dict(kind="g3", shape=(n, ni, nj, nk), c=np.arange(n)[:, None, None, None],
                        x=self.ox[:, None, None, None] + li[None, :, None, None],
                        y=self.oy[:, None, None, None] + lj[None, None, :, None],
                        z=I(cz) * np.arange(nk, dtype=I)[None, None, None, :])
        vals = self._eval(list(u.outs.values()))
        for name, e in u.outs.items():
            self.grids[name] = np.ascontiguousarray(np.broadcast_to(vals[e.id], (n, ni, nj, nk)), F)

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
        """Values of roots (and nodes) by id. An expensive operand of & | select that
        nothing else needs (lower.lazy_blocks, as cl.py's `if`s) is computed only on
        the voxels where it decides the result, e.g. the second cave noise only where
        the first passed: same values, fewer voxels."""
        lazy, owner, top, deps, count = _plan(roots)
        uses = dict(count)
        keep = {r.id for r in roots}
        self._lazy, self._owner = lazy, owner
        root = _Scope(None, None, self._shape())
        v = root.v
        for e in top:
            self._node(e, root)
            for i in deps[e.id]:
                uses[i] -= 1
                if uses[i] == 0 and i not in keep:
                    del v[i]
        return v

    def _shape(self):
        d = self.dom
        n = self.n
        if d["kind"] == "2d":
            return (n, d["w"], d["w"])
        if d["kind"] == "g3":
            return d["shape"]
        return (n, d["w"], d["w"], d["z"].shape[-1])

    def _node(self, e, sc):
        """Computes e into scope sc (sc.v holds values on sc's voxels)."""
        slots = self._lazy.get(e.id)
        if slots:
            sc.v[e.id] = self._lazy_node(e, slots, sc)
            return
        a = [sc.get(x.id) for x in e.a]
        if sc.mask is not None and (e.op in ("x", "y", "z", "prev", "lx", "ly", "c")
                                    or (e.op == "read" and e.k[1] is not None)):
            sc.v[e.id] = sc.down(self._op(e, a))  # computed on the chunk, then gathered
        elif sc.mask is not None and e.op in ("read", "gread", "cread"):
            sc.v[e.id] = (self._read if e.op == "read" else self._gread)(e, a, sc)
        else:
            sc.v[e.id] = self._op(e, a)

    def _block(self, e, i, sc):
        """Operand i of lazy node e on the voxels of scope sc."""
        for n in self._lazy[e.id].get(i, ()):
            if self._owner.get(n.id) == (e.id, i):
                self._node(n, sc)
        return sc.get(e.a[i].id)

    def _lazy_node(self, e, slots, sc):
        c = np.broadcast_to(np.asarray(sc.get(e.a[0].id), bool), sc.shape)
        on = int(np.count_nonzero(c))
        size = c.size
        if e.op in ("and", "or"):
            need = c if e.op == "and" else ~c
            k = on if e.op == "and" else size - on
            if k == 0:
                return c
            if k > LAZY_SHARE * size:  # nearly everywhere: not worth the gathers
                return _OPS[e.op](c, self._block(e, 1, sc))
            out = c.copy()
            out[need] = self._block(e, 1, _Scope(sc, need, None))
            return out
        share = {1: on, 2: size - on}
        if all(share[i] > LAZY_SHARE * size for i in slots):
            return np.where(c, self._block(e, 1, sc), self._block(e, 2, sc))
        out = np.empty(sc.shape, DT[e.t])
        for i, m in ((1, c), (2, ~c)):
            if m.any():
                out[m] = self._block(e, i, _Scope(sc, m, None))
        return out
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
        if op in ("gread", "cread"):
            return self._gread(e, a)
        if op == "coarse":
            return self._coarse(e, a)
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

    def _read(self, e, a, sc=None):
        name, dx, dy, reach = e.k
        arr, hf = self.fields[name]
        d = self.dom
        if sc is not None:  # dynamic offsets on a scope's voxels: gather the indices
            d = dict(d, **{k: sc.down(d[k]) for k in ("lx", "ly", "c")})
        off = hf - d["halo"]
        if "pts" in d:  # single columns (_at_points): those at the offset, by key
            return arr[np.searchsorted(self._pts[name], _key(d["pts"] + (dx, dy)))]
        if dx is not None:  # constant offset: a slice
            w = d["w"]
            r = arr[:, off + dx:off + dx + w, off + dy:off + dy + w]
            return r[..., None] if d["kind"] == "3d" else r
        ix = d["lx"] + I(hf) + np.clip(a[0], -reach, reach)
        iy = d["ly"] + I(hf) + np.clip(a[1], -reach, reach)
        return arr[d["c"], ix, iy]

    def _gread(self, e, a, sc=None):
        """gread: the sample at lattice corner (i, j) of (x, y)'s cell, level z;
        cread: level z's cell level + k of column (x, y) (lower.lattice)."""
        d = self.dom
        x, y, z = a
        m = I(C.SIZE - 1)  # the voxel within its chunk (origins are multiples of 16)
        if e.op == "gread":
            name, (cx, cy, cz), i, j = e.k
            arr = self.grids[name]
            c = d["c"] if sc is None else sc.down(d["c"])
            return arr[c, (x & m) // cx + i, (y & m) // cy + j, z // cz]
        name, (cx, cy, cz), k = e.k
        arr = self.grids[name]
        if sc is None:  # the whole chunk: a slice of levels along z
            return arr[..., z[0, 0, 0] // cz + k]
        return arr[sc.down(d["c"]), x & m, y & m, z // cz + k]

    def _coarse(self, e, a):
        """A coarse node outside the lattice units (a column output): the function at
        the 8 corners evaluated once on stacked coordinates, then interpolated with
        lower.expand's operations in its order (so the same bits as the lattice)."""
        (cx, cy, cz), body = e.k[0], e.k[1].e
        x, y, z = np.broadcast_arrays(*[np.asarray(v, I) for v in a])
        org = [v - v % I(c) for v, c in ((x, cx), (y, cy), (z, cz))]
        order = [(i, j, k) for k in (0, 1) for j in (0, 1) for i in (0, 1)]
        X = np.stack([org[0] + I(i * cx) for i, j, k in order])
        Y = np.stack([org[1] + I(j * cy) for i, j, k in order])
        Z = np.stack([org[2] + I(k * cz) for i, j, k in order])
        saved = self.dom, self._lazy, self._owner
        self.dom = dict(kind="g3", shape=X.shape, x=X, y=Y, z=Z)
        try:
            v = np.broadcast_to(self._eval([body])[body.id], X.shape)
        finally:
            self.dom, self._lazy, self._owner = saved
        s = dict(zip(order, v))
        t = [(q % I(c)).astype(F) * F(1.0 / c) for q, c in ((x, cx), (y, cy), (z, cz))]

        def lerp(f, p, q):
            return p + f * (q - p)
        lv = [lerp(t[1], lerp(t[0], s[0, 0, k], s[1, 0, k]), lerp(t[0], s[0, 1, k], s[1, 1, k]))
              for k in (0, 1)]
        return lerp(t[2], lv[0], lv[1])

    def _prev(self, dz):
        z = self.dom["z"][0, 0, 0]
        src = z + dz
        ok = (src >= 0) & (src < C.HEIGHT)
        out = np.zeros(self.prev.shape[:3] + (len(z),), I)
        out[..., ok] = self.prev[..., src[ok]]
        return out


def _key(xy):
    """One int64 per column (x, y), each within int32, ordered by x then y."""
    return (xy[:, 0] << 32) + (xy[:, 1] + 2 ** 31)


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
