"""3D units -> explicit 8-lane OpenCL C (`_GenV`: one row of 8 voxels per work item;
with `free`, lanes that are not a row: g3 and 2D units), and which units it can take
(`vectorizable`)."""
from __future__ import annotations

from ..core import chunk as C
from .clscalar import _BIN, CT, LAYER, VLANES, _Gen, _pad, g3_row
from .lower import Unit, expand, lattice_dims, nodes
# ops the 8-lane 3D kernels implement; a unit using others stays scalar
_VEC_OPS = set(_BIN) | {"const", "x", "y", "z", "neg", "not", "min", "max", "abs", "floor",
                        "sqrt", "int", "float", "fdiv", "fmod", "select", "perlin2",
                        "perlin3", "rand2", "rand3", "irand2", "read", "prev", "cread",
                        "voronoi2", "get"}
VECTOR = True  # False: every unit scalar (for comparisons)


def _constant(e):
    """The value of a constant (possibly converted) as a float, else None."""
    while e.op in ("float", "int") and e.a[0].op in ("const", "float", "int"):
        if e.op == "int":
            return None
        e = e.a[0]
    return float(e.k) if e.op == "const" and e.t in ("f", "i") else None


def vectorizable(u: Unit, size: int = C.SIZE) -> bool:
    """8-lane code: 3D units, lattice samples, 2D units with coarse nodes (written out
    by expand) and, in chunk programs (SIZE: a chunk's columns), every 2D unit whose
    ops all have 8-lane forms. Those ran scalar before (issue 29): the height map's 26
    perlin2 as never-inlined calls, which keep pocl's work-group vectorizer off, and
    the trees' hashes. The far surface's 1-column domains stay scalar (8 lanes would
    compute one column 8 times)."""
    if not VECTOR or u.kind not in ("3d", "g3", "2d"):
        return False
    roots = u.roots()
    if u.kind == "2d":
        if size < C.SIZE and not any(e.op == "coarse" for e in nodes(roots)):
            return False
        roots = expand(roots)
    return all(e.op in _VEC_OPS and (e.t != "f3" or e.op == "voronoi2") for e in nodes(roots))


class _GenV(_Gen):
    """The 3D kernels as explicit 8-lane code (gpu/noise8.h): pocl's work-group
    vectorizer gives up on the big generated kernels (README), explicit vectors need
    none. Bools are 0/-1 lanes; numbers as in the scalar code, op for op."""
    vec = True
    ct = {"f": "vf8", "i": "vi8", "b": "vi8", "f3": "vf8x3"}
    free = False  # True for g3 kernels (lanes are any 8 lattice points)

    def expr(self, e, a, unit):
        op, k = e.op, e.k
        if op == "const" and e.t == "b":
            return "(-1)" if e.k else "0"
        if op in ("const", "x", "y", "z") or op in _BIN or op == "neg":
            return super().expr(e, a, unit)
        if op == "not":
            return f"(~{a[0]})"
        if op in ("min", "max"):
            return f"vx_{'f' if e.t == 'f' else 'i'}{op}8({a[0]}, {a[1]})"
        if op == "abs":
            return f"fabs({a[0]})" if e.t == "f" else f"vx_iabs8({a[0]})"
        if op in ("floor", "sqrt"):
            return f"{op}({a[0]})"
        src = e.a[0].t if e.a else None
        if op == "int":
            return {"f": f"convert_int8({a[0]})", "b": f"(-{a[0]})"}.get(src, a[0])
        if op == "float":
            return f"convert_float8({'-' if src == 'b' else ''}{a[0]})"
        if op in ("fdiv", "fmod"):
            return f"vx_{op}8({a[0]}, {k})"
        if op == "select":
            return f"select({a[2]}, {a[1]}, {a[0]})"
        if op == "perlin2":
            return f"perlin2_8({a[0]}, {a[1]}, perm, s{k})"
        if op == "voronoi2":
            return f"voronoi2_8({a[0]}, {a[1]}, {k[1]}, s{k[0]})"
        if op == "get":
            return f"{a[0]}.{'xyz'[k]}"
        if op == "perlin3":
            sp = [self.span(x) for x in e.a]
            row = sp[0] is not None and sp[0][0] < ROW_SPAN and sp[1] == sp[2] == (0.0, 0)
            return f"perlin3_8{'r' if row else ''}({a[0]}, {a[1]}, {a[2]}, perm, s{k})"
        if op == "rand2":
            return f"vx_unit8(vx_hash2_8({a[0]}, {a[1]}, s{k}))"
        if op == "rand3":
            return f"vx_unit8(vx_hash3_8({a[0]}, {a[1]}, {a[2]}, s{k}))"
        if op == "irand2":
            return f"convert_int8((vx_hash2_8({a[0]}, {a[1]}, s{k[0]}) >> 8) % {k[1]}u)"
        if op == "read":
            name, dx, dy, reach = k
            v = self.read(name, dx, dy, a, reach)
            return f"(-{v})" if e.t == "b" else v
        if op == "prev":
            return f"vx_prev8(prev, c, zs + ({k}), row)"
        if op == "cread":  # the row's 8 columns are consecutive: one load
            (cz, nk), lv = (k[1][2], lattice_dims(k[1])[2]), k[2]
            return f"vload8(0, f_{k[0]} + ((c * {nk} + (zs / {cz} + {lv})) * {C.SIZE} + ly) * {C.SIZE} + lx0)"
        raise ValueError(f"no 8-lane form of {op}")

    def span(self, e):
        """(bound on max - min, direction) of e over a row's 8 lanes (consecutive x,
        one y and z), or None when unknown. Direction 1 / -1: the lanes are monotone
        (correctly rounded + - * / by constants keep them so), 0: all lanes equal.
        Reads of 2D fields at constant offsets follow the field's expression."""
        memo = self.__dict__.setdefault("_spans", {})
        if e.id not in memo:
            memo[e.id] = self._span(e)
        return memo[e.id]

    def _span(self, e):
        op, a = e.op, e.a
        if self.free:  # lanes are lattice points: no row structure to rely on
            return None
        if op == "const" or op in ("y", "z"):
            return (0.0, 0)
        if op == "x":
            return (float(VLANES - 1), 1)
        if op == "read":
            d = self.defs.get(e.k[0])
            return None if e.k[1] is None or d is None else self.span(d)
        if op in ("prev", "gread", "cread"):
            return None
        s = [self.span(x) for x in a]
        if any(x is None for x in s):
            return None
        if all(x == (0.0, 0) for x in s):  # a function of lane-uniform values
            return (0.0, 0)
        if op == "float":  # int -> float32 rounds only beyond 2**24: at most 1 each end
            return s[0] if a[0].t == "f" or s[0][1] == 0 else (s[0][0] + 2.0, s[0][1])
        if op == "neg":
            return (s[0][0], -s[0][1])
        if op in ("add", "sub"):
            d0, d1 = s[0][1], s[1][1] * (-1 if op == "sub" else 1)
            if d0 and d1 and d0 != d1:
                return None
            return (s[0][0] + s[1][0], d0 or d1)
        if op in ("mul", "div"):
            k = [_constant(x) for x in a]
            if k[1] is None and not (op == "mul" and k[0] is not None):
                return None
            c, v = (k[1], s[0]) if k[1] is not None else (k[0], s[1])
            if c == 0:
                return None if op == "div" else (0.0, 0)
            f = abs(c) if op == "mul" else 1 / abs(c)
            return (v[0] * f * 1.001, v[1] * (1 if c > 0 else -1))
        return None

    def read(self, name, dx, dy, a=(), reach=0):
        t, hf = self.fields[name]
        wf = self.size + 2 * hf
        base = f"f_{name} + c * {wf * wf}"
        gather = dx is None or self.free  # lanes at any columns (free: a 2D unit's items)
        if dx is None:  # a different neighbour per lane
            dx = f"vx_imin8(vx_imax8({a[0]}, (vi8){-reach}), (vi8){reach})"
            dy = f"vx_imin8(vx_imax8({a[1]}, (vi8){-reach}), (vi8){reach})"
        if gather:
            idx = f"((ly + {hf} + ({dy})) * {wf} + (lx + {hf} + ({dx})))"
            return f"VX_GATHER8({self.ct[t]}, {base}, {idx})"
        return f"vload8(0, {base} + (ly + {hf} + ({dy})) * {wf} + (lx0 + {hf} + ({dx})))"

    def kernel_2d(self, i, u: Unit, roots, outs):
        """A 2D unit holding a coarse node (a column output: 8 corner samples of the
        function per column) as 8-lane code, 8 consecutive items of a chunk's domain
        per work-item: its lazy `if`s then skip the samples where no lane needs them
        (pocl's work-group vectorizer evaluated both sides of the scalar kernel's)."""
        h = u.halo
        w = self.size + 2 * h
        t, q = w * w, _pad(w * w, VLANES) // VLANES
        args = ["__global const int* org", "__constant const int* perm", "uint seed", "int n"]
        args += [f"__global {CT[e.t]}* o_{n}" for n, e in u.outs.items()]
        args += [f"__global const {CT[self.fields[n][0]]}* f_{n}" for n in self.reads(u)]
        out = [f"__kernel void unit{i}({', '.join(args)}) {{",
               "    int gid = get_global_id(0);",
               f"    int g = vx_imin(gid, n * {q} - 1), c = g / {q};",
               f"    vi8 r = vx_imin8((g - c * {q}) * {VLANES} + VX_LANES, (vi8)({t - 1}));",
               f"    vi8 lx = r % {w} - {h}, ly = r / {w} - {h};",
               "    vi8 x = org[c] + lx, y = org[n + c] + ly;"]
        out += self.salts(roots)
        done = {}
        out += self.body(roots, u, done)
        for n, e in outs.items():
            out += [f"    o_{n}[c * {t} + r.s{k}] = {done[e.id]}.s{k};" for k in range(VLANES)]
        return "\n".join(out + ["}", ""])

    def kernel_g3(self, i, u: Unit):
        """A g3 unit (lattice samples) 8 points per work-item: the scalar one ran
        perlin3 unvectorized (pocl), ~3x slower per point than the 3D kernels."""
        (cx, cy, cz), (ni, nj, nk) = u.cell, lattice_dims(u.cell)
        roots = u.roots()
        args = ["__global const int* org", "__constant const int* perm", "uint seed", "int n",
                "__global const int* layers"]
        args += [f"__global float* o_{n}" for n in u.outs]
        args += [f"__global const {CT[self.fields[n][0]]}* f_{n}" for n in self.reads(u)]
        out = [f"__kernel void unit{i}({', '.join(args)}) {{",
               "    int grp = get_group_id(0), lid = get_local_id(0);",
               "    int ck = layers[grp], c = ck >> 8, k = ck & 255;",
               f"    vi8 p = vx_imin8(lid * {VLANES} + VX_LANES, (vi8)({ni * nj - 1}));",
               f"    vi8 i = p / {nj}, j = p - i * {nj};",
               f"    vi8 x = org[c] + i * {cx}, y = org[n + c] + j * {cy}, z = (vi8)(k * {cz});"]
        out += self.salts(roots)
        done = {}
        out += self.body(roots, u, done)
        row = g3_row(u.cell)
        out += [f"    vstore8({done[e.id]}, 0, o_{n} + (c * {nk} + k) * {row} + lid * {VLANES});"
                for n, e in u.outs.items()]
        return "\n".join(out + ["}", ""])

    def kernel(self, i, u: Unit):
        if u.kind == "g3":
            return self.kernel_g3(i, u)
        if u.kind == "2d":
            roots = expand(u.roots())
            return self.kernel_2d(i, u, roots, dict(zip(u.outs, roots)))
        roots = u.roots()
        args = ["__global const int* org", "__constant const int* perm", "uint seed", "int n",
                "__global const int* layers", "__global ushort* blocks",
                "__global const ushort* prev"]
        args += [f"__global const {CT[self.fields[n][0]]}* f_{n}" for n in self.reads(u)]
        out = [f"__kernel void unit{i}({', '.join(args)}) {{",
               "    int grp = get_group_id(0), lid = get_local_id(0);",
               "    int cz = layers[grp], c = cz >> 8, zs = cz & 255;",
               f"    int lx0 = (lid & {C.SIZE // VLANES - 1}) * {VLANES};",
               f"    int ly = lid / {C.SIZE // VLANES}, row = ly * {C.SIZE} + lx0;",
               "    vi8 lx = lx0 + VX_LANES;",
               "    vi8 x = org[c] + lx, y = (vi8)(org[n + c] + ly), z = (vi8)zs;"]
        if u.top is not None:
            # the blocks buffer is zero-filled: nothing to compute above each column's top
            out += [f"    vi8 top = {self.read(u.top, 0, 0)};",
                    "    if (!any(z <= top)) return;"]
        out += self.salts(roots)
        done = {}
        out += self.body(roots, u, done)
        blk = done[u.blk.id]
        if u.top is not None:
            blk = f"select((vi8)0, {blk}, z <= top)"
        out += [f"    vstore8(convert_ushort8({blk}), 0, blocks + c * {C.VOLUME} + zs * {LAYER} + row);"]
        return "\n".join(out + ["}", ""])


ROW_SPAN = 0.9  # perlin3's x over a row spans less than this (cells): perlin3_8r
