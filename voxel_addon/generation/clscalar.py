"""lang units -> OpenCL C, one work item per column (2D), lattice point or voxel
(3D units the 8-lane writer cannot take): `_Gen`, and what every kernel writer shares
(the build options, C types, literals, padded sizes, g3 indexing)."""
from __future__ import annotations

import numpy as np

from ..core import chunk as C
from .lower import Unit, expand, lattice_dims, lazy_blocks, nodes, right_nest
# No fast-math, no mad: IEEE results identical to NumPy's (see gpu/noise.h).
OPTIONS = ("-cl-fp32-correctly-rounded-divide-sqrt",)
CT = {"f": "float", "i": "int", "b": "int", "f3": "float3"}
LOCAL2D = 64
LAYER = C.SIZE * C.SIZE  # a 3D work-group: one z layer of one chunk, x fastest
VLANES = 8
VLOCAL = LAYER // VLANES  # a 3D work-group: one z layer, one row of 8 voxels per item


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


LAZY_COST = 12  # cheaper operands are computed unconditionally
