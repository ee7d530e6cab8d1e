"""Compiles a lang.Program to OpenCL C: one kernel per unit, appended to gpu/gen.cl
(cl.Runner builds and runs them on batches of chunks).

Every node becomes one C statement doing exactly the float32 operation NumPy does
(execute.py); constants are written as hex floats so no decimal rounding sneaks in.

Speed on pocl: 2D kernels rely on its work-group vectorizer (see gpu/noise.h), so
they have no control flow: no early returns (domains are padded), no && || (they
branch), and loads that might be out of range are clamped and then masked. 3D
kernels run on a list of (chunk, z) layers below the pass's `top`, skip columns
above their own top, and are written as explicit 8-lane code (`_GenV`, README).
"""
from __future__ import annotations

import re

import numpy as np

from .. import resources
from ..core import chunk as C
from .lower import Unit, expand, lattice_dims, lazy_blocks, nodes, right_nest

# No fast-math, no mad: IEEE results identical to NumPy's (see gpu/noise.h).
OPTIONS = ("-cl-fp32-correctly-rounded-divide-sqrt",)
CT = {"f": "float", "i": "int", "b": "int", "f3": "float3"}
LOCAL2D = 64
LAYER = C.SIZE * C.SIZE  # a 3D work-group: one z layer of one chunk, x fastest


def _lit(e):
    if e.t == "f":
        v = float(np.float32(e.k))
        if v != v or v in (float("inf"), float("-inf")):
            raise ValueError("non-finite constant")
        return f"({v.hex()}f)"
    if e.t == "b":
        return "1" if e.k else "0"
    return f"({int(e.k)})"


# bools are ints 0/1, so & and | are exact and, unlike && ||, do not branch
_BIN = {"add": "+", "sub": "-", "mul": "*", "div": "/", "lt": "<", "le": "<=", "gt": ">",
        "ge": ">=", "eq": "==", "ne": "!=", "and": "&", "or": "|"}


def _pad(size, local):
    return -(-size // local) * local


class _Gen:
    vec = False
    ct = CT

    def __init__(self, units, size=C.SIZE):
        self.units, self.size = units, size  # size: a domain's side (execute.Runner)
        self.fields = {}  # name -> (type, halo)
        self.defs = {}    # name -> expression of a 2D field
        for u in units:
            if u.kind == "2d":
                for n, e in u.outs.items():
                    self.fields[n] = (e.t, u.halo)
                    self.defs[n] = e
            elif u.kind in ("g3", "gc"):
                for n in u.outs:
                    self.fields[n] = ("f", None)

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
        # helpers from gen.cl/noise.h rather than OpenCL builtins: pocl's builtins
        # are calls, which keep the work-group loop from vectorizing
        if op in ("min", "max"):
            return f"vx_{'f' if e.t == 'f' else 'i'}{op}({a[0]}, {a[1]})"
        if op == "abs":
            return f"vx_fabs({a[0]})" if e.t == "f" else f"vx_iabs({a[0]})"
        if op in ("floor", "sqrt"):
            return f"vx_{op}({a[0]})"
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
            return self.read(name, dx, dy, a, reach)
        if op == "prev":
            return f"vx_prev(prev, c, z + ({k}), lid)"
        if op in ("gread", "cread"):
            return f"f_{k[0]}[{gindex(e.op, k, a)}]"
        raise ValueError(f"unknown op {op}")

    def read(self, name, dx, dy, a=(), reach=0):
        _, hf = self.fields[name]
        wf = self.size + 2 * hf
        if dx is None:
            dx = f"vx_imin(vx_imax({a[0]}, {-reach}), {reach})"
            dy = f"vx_imin(vx_imax({a[1]}, {-reach}), {reach})"
        return f"f_{name}[c * {wf * wf} + (ly + {hf} + ({dy})) * {wf} + (lx + {hf} + ({dx}))]"

    def body(self, roots, unit, done):
        """C statements for roots. An expensive operand that nothing else needs (of &,
        | or select) is computed inside an `if` only when it decides the result: the
        big kernels run scalar on pocl anyway (see README), so a branch costs little
        and e.g. cave noise is skipped outside cave regions. Same values, fewer ops.
        Chains of & and | are nested to the right first (lower.right_nest); DONE gets
        the given roots' names too."""
        nested = right_nest(roots)
        order = nodes(nested)
        lazy, owner = lazy_blocks(order, nested, LAZY_COST)
        out = []
        self._emit([e for e in order if e.id not in owner], lazy, owner, unit, done, out, 1)
        for r, n in zip(roots, nested):
            done[r.id] = done[n.id]
        return out

    def _emit(self, seq, lazy, owner, unit, done, out, depth):
        pad = "    " * depth
        for e in seq:
            if e.id in done:
                continue
            slots = lazy.get(e.id)
            if not slots:
                a = [done[x.id] for x in e.a]
                done[e.id] = f"v{e.id}"
                out.append(f"{pad}{self.ct[e.t]} v{e.id} = {self.expr(e, a, unit)};")
                continue
            v = done[e.id] = f"v{e.id}"

            def block(i, merge="{}"):  # statements computing operand i, then v = operand i
                inner = [n for n in slots.get(i, ()) if owner.get(n.id) == (e.id, i)]
                self._emit(inner, lazy, owner, unit, done, out, depth + 1)
                out.append(f"{pad}    {v} = {merge.format(done[e.a[i].id])};")
            if self.vec:  # lanes share the branch: taken when any lane needs the operand
                c = done[e.a[0].id]
                if e.op in ("and", "or"):
                    out.append(f"{pad}vi8 {v} = {c};")
                    out.append(f"{pad}if ({'any' if e.op == 'and' else '!all'}({v})) {{")
                    block(1, f"{v} {_BIN[e.op]} {{}}")
                    out.append(f"{pad}}}")
                else:  # an arm computed for all lanes, then merged by the condition
                    out.append(f"{pad}{self.ct[e.t]} {v} = ({self.ct[e.t]})0;")
                    out.append(f"{pad}if (any({c})) {{")
                    block(1)
                    out.append(f"{pad}}}")
                    out.append(f"{pad}if (!all({c})) {{")
                    block(2, f"select({{}}, {v}, {c})")
                    out.append(f"{pad}}}")
            elif e.op in ("and", "or"):
                out.append(f"{pad}int {v} = {done[e.a[0].id]};")
                out.append(f"{pad}if ({'' if e.op == 'and' else '!'}{v}) {{")
                block(1)
                out.append(f"{pad}}}")
            else:  # select
                out.append(f"{pad}{CT[e.t]} {v};")
                out.append(f"{pad}if ({done[e.a[0].id]}) {{")
                block(1)
                out.append(f"{pad}}} else {{")
                block(2)
                out.append(f"{pad}}}")

    def reads(self, u: Unit):
        names = [u.top] if u.top is not None else []
        for e in nodes(u.roots()):
            if e.op in ("read", "gread", "cread") and e.k[0] not in names:
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
        roots, outs = u.roots(), u.outs
        if u.kind == "2d" and any(e.op == "coarse" for e in nodes(roots)):
            roots = expand(roots)   # a column output: its 8 corner samples in place
            outs = dict(zip(u.outs, roots))
        args = ["__global const int* org", "__constant const int* perm", "uint seed", "int n"]
        if u.kind == "2d":
            args += [f"__global {CT[e.t]}* o_{n}" for n, e in u.outs.items()]
        elif u.kind in ("g3", "gc"):
            args += ["__global const int* layers"]
            args += [f"__global {CT[e.t]}* o_{n}" for n, e in u.outs.items()]
        else:
            args += ["__global const int* layers", "__global ushort* blocks",
                     "__global const ushort* prev"]
        args += [f"__global const {CT[self.fields[n][0]]}* f_{n}" for n in self.reads(u)]
        out = [f"__kernel void unit{i}({', '.join(args)}) {{"]
        if u.kind == "2d":
            # the global size is padded to the work-group size: the tail recomputes
            # the last column into the buffer's padding instead of branching
            w = self.size + 2 * u.halo
            out += ["    int gid = get_global_id(0);",
                    f"    int g = vx_imin(gid, n * {w * w} - 1);",
                    f"    int c = g / {w * w}, r = g - c * {w * w};",
                    f"    int lx = r % {w} - {u.halo}, ly = r / {w} - {u.halo};"]
        elif u.kind in ("g3", "gc"):  # a work-group per (chunk, lattice level): layers
            (cx, cy, cz), (ni, nj, nk) = u.cell, lattice_dims(u.cell)
            out += ["    int grp = get_group_id(0), lid = get_local_id(0);",
                    "    int ck = layers[grp], c = ck >> 8, k = ck & 255, z = k * " f"{cz};"]
            if u.kind == "g3":  # lattice points p = (i, j) of the level, [c][k][p]
                out += [f"    int p = vx_imin(lid, {ni * nj - 1}), i = p / {nj}, j = p - i * {nj};",
                        f"    int lx = i * {cx}, ly = j * {cy};",
                        f"    int gid = (c * {nk} + k) * {g3_row(u.cell)} + lid;"]
            else:  # the level at each column, [c][k][y][x]
                out += [f"    int lx = lid & {C.SIZE - 1}, ly = lid >> 4;",
                        f"    int gid = (c * {nk} + k) * {LAYER} + lid;"]
        else:
            out += ["    int grp = get_group_id(0), lid = get_local_id(0);",
                    "    int cz = layers[grp], c = cz >> 8, z = cz & 255;",
                    f"    int lx = lid & {C.SIZE - 1}, ly = lid >> 4;",
                    f"    int gid = c * {C.VOLUME} + z * {LAYER} + lid;"]
        out += ["    int x = org[c] + lx, y = org[n + c] + ly;"]
        if u.kind == "3d" and u.top is not None:
            # the blocks buffer is zero-filled: nothing to compute above this column's top
            out += [f"    if (z > {self.read(u.top, 0, 0)}) return;"]
        out += self.salts(roots)
        done = {}
        out += self.body(roots, u, done)
        if u.kind in ("2d", "g3", "gc"):
            out += [f"    o_{n}[gid] = {done[e.id]};" for n, e in outs.items()]
        else:
            top = "255" if u.top is None else self.read(u.top, 0, 0)
            out += [f"    blocks[gid] = (ushort)(z <= {top} ? {done[u.blk.id]} : 0);"]
        return "\n".join(out + ["}", ""])


def g3_row(cell) -> int:
    """A g3 buffer's entries per (chunk, level): the level's points padded to 8 lanes."""
    ni, nj, _ = lattice_dims(cell)
    return _pad(ni * nj, VLANES)


def gindex(op, k, a):
    """Index of a coarse value (execute.Runner._gread) in its unit's buffer; a: x, y, z
    (scalars). gread: sample at lattice corner (i, j) of (x, y)'s cell at level z,
    buffer [chunk][level][i * nj + j, padded: g3_row]; cread: level z / cz + k of
    column (x, y), buffer [chunk][level][y][x] (rows of x contiguous: one 8-lane load)."""
    (cx, cy, cz), m = k[1], C.SIZE - 1  # origins are multiples of 16: x & 15 in the chunk
    _, nj, nk = lattice_dims(k[1])
    if op == "gread":
        i, j = k[2], k[3]
        return (f"(c * {nk} + ({a[2]}) / {cz}) * {g3_row(k[1])}"
                f" + ((({a[0]}) & {m}) / {cx} + {i}) * {nj} + ((({a[1]}) & {m}) / {cy} + {j})")
    return (f"((c * {nk} + (({a[2]}) / {cz} + {k[2]})) * {C.SIZE} + (({a[1]}) & {m}))"
            f" * {C.SIZE} + (({a[0]}) & {m})")


# ops the 8-lane 3D kernels implement; a unit using others stays scalar
_VEC_OPS = set(_BIN) | {"const", "x", "y", "z", "neg", "not", "min", "max", "abs", "floor",
                        "sqrt", "int", "float", "fdiv", "fmod", "select", "perlin2",
                        "perlin3", "rand2", "rand3", "irand2", "read", "prev", "cread",
                        "voronoi2", "get"}
VLANES = 8
VECTOR = True  # False: every unit scalar (for comparisons)
VLOCAL = LAYER // VLANES  # a 3D work-group: one z layer, one row of 8 voxels per item


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


LAZY_COST = 12  # cheaper operands are computed unconditionally
ROW_SPAN = 0.9  # perlin3's x over a row spans less than this (cells): perlin3_8r


def source(units, size=C.SIZE, inline: bool = False) -> str:
    """The OpenCL C of UNITS: the same text for the same program, whichever process or
    generator object made it (`_renumber`). INLINE: every noise call inlined (`called`
    not applied), for a program whose build is off the path to a picture and that runs
    big batches (the far surface: ~10 % faster per 16384 columns)."""
    g, gv, free = _Gen(units, size), _GenV(units), _GenV(units, size)
    free.free = True  # lanes that are not a row of 8 voxels: g3 and 2D units
    most = (10 ** 9,) * 2 if inline else CALLS_INLINED
    return resources.kernel("gen.cl") + _renumber("\n".join(
        called(((gv if u.kind == "3d" else free) if vectorizable(u, size) else g).kernel(i, u),
               most[u.kind == "3d"])
        for i, u in enumerate(units)))


# A kernel inlines a big noise function up to this many calls (per-column and
# lattice kernels, per-voxel 3D ones); with more it calls gen.cl's never-inlined `_c`
# twin: each inlined copy is compiled again by pocl at the kernel's first launch
# (seconds on a fresh install, issue 28), while a call costs a few instructions next
# to a noise body's ~100. The hot per-voxel kernels (3 calls) stay inlined.
CALLS_INLINED = (2, 4)
_CALLED = re.compile(r"\b(perlin2|perlin3|voronoi2|voronoi3|perlin2_8|perlin3_8|voronoi2_8)\(")


def called(text: str, most: int) -> str:
    """TEXT (one kernel) with its big noise calls made calls of the `_c` twins when it
    has more than MOST of one function."""
    n: dict = {}
    for m in _CALLED.finditer(text):
        n[m[1]] = n.get(m[1], 0) + 1
    many = {f for f, k in n.items() if k > most}
    return _CALLED.sub(lambda m: f"{m[1]}_c(" if m[1] in many else m[0], text) if many else text


_VAR = re.compile(r"\bv(\d+)\b")


def _renumber(text: str) -> str:
    """Variables v<node id> renamed v0, v1, ... in order of appearance. Node ids come
    from one counter per process (lang.E), so the same program made twice (a second
    generator, world or scene) had other names: another source, which opencl.build and
    pocl's disk cache missed, so pocl compiled it all again (seconds per generator)."""
    names: dict[str, str] = {}
    return _VAR.sub(lambda m: names.setdefault(m.group(1), f"v{len(names)}"), text)
