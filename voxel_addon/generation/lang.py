"""The generator language (thesis code 5.1): passes of expressions, written once in
Python, run by NumPy (execute.py) and compiled to OpenCL C (cl.py).

A `Program` is a list of passes. A 2D pass computes per column values (`out`); a 3D
pass computes a block id per voxel (`block`) and may write per column values from
the one invocation at height `at` (`column`). A pass reads only what earlier passes
wrote: 2D values with `read` (also at neighbour columns: the runtime computes them
on a wide enough border, so features cross chunk borders seamlessly) and the
previous 3D pass's block at the same column with `prev`.

Values are float32 ('f'), int32 ('i') or bool ('b'); Python numbers become
constants; int mixes with float as float. Everything is a pure function of world
coordinates and the seed, and each backend performs the same IEEE operations in the
same order, so block ids agree exactly between backends.
"""
from __future__ import annotations

import contextlib
import itertools

import numpy as np

_stack: list["Program"] = []


class E:
    """An expression node. op: operation; a: argument nodes; t: type; k: payload."""
    __slots__ = ("op", "a", "t", "k", "id")
    _ids = itertools.count()

    def __init__(self, op, a=(), t="f", k=None):
        self.op, self.a, self.t, self.k = op, tuple(a), t, k
        self.id = next(E._ids)

    def __bool__(self):
        raise TypeError("a generator expression has no truth value here: "
                        "use select(c, a, b), & | ~ instead of if/and/or/not")

    __hash__ = object.__hash__

    # arithmetic
    def __add__(s, o): return _arith("add", s, o)
    def __radd__(s, o): return _arith("add", o, s)
    def __sub__(s, o): return _arith("sub", s, o)
    def __rsub__(s, o): return _arith("sub", o, s)
    def __mul__(s, o): return _arith("mul", s, o)
    def __rmul__(s, o): return _arith("mul", o, s)
    def __truediv__(s, o): return _arith("div", s, o, force_float=True)
    def __rtruediv__(s, o): return _arith("div", o, s, force_float=True)
    def __neg__(s): return E("neg", (s,), s.t)

    def __floordiv__(s, o):
        return _intconst_op("fdiv", s, o)

    def __mod__(s, o):
        return _intconst_op("fmod", s, o)

    # comparisons -> bool
    def __lt__(s, o): return _cmp("lt", s, o)
    def __le__(s, o): return _cmp("le", s, o)
    def __gt__(s, o): return _cmp("gt", s, o)
    def __ge__(s, o): return _cmp("ge", s, o)
    def __eq__(s, o): return _cmp("eq", s, o)
    def __ne__(s, o): return _cmp("ne", s, o)

    # logic on bools
    def __and__(s, o): return _logic("and", s, o)
    def __rand__(s, o): return _logic("and", o, s)
    def __or__(s, o): return _logic("or", s, o)
    def __ror__(s, o): return _logic("or", o, s)
    def __invert__(s):
        if s.t != "b":
            raise TypeError("~ needs a bool expression")
        return E("not", (s,), "b")

    def __getitem__(self, i):
        """Component of a Voronoi result: 0 F1, 1 F2, 2 cell value."""
        if self.t != "f3":
            raise TypeError("only Voronoi results have components")
        return E("get", (self,), "f", int(i))

    f1 = property(lambda s: s[0])
    f2 = property(lambda s: s[1])
    value = property(lambda s: s[2])

    def __repr__(self):
        return f"E({self.op}:{self.t})"


def const(v) -> E:
    if isinstance(v, E):
        return v
    if isinstance(v, (bool, np.bool_)):
        return E("const", (), "b", bool(v))
    if isinstance(v, (int, np.integer)):
        if not -2**31 <= int(v) < 2**31:
            raise ValueError(f"integer constant {v} does not fit int32")
        return E("const", (), "i", int(v))
    if isinstance(v, (float, np.floating)):
        return E("const", (), "f", float(np.float32(v)))
    raise TypeError(f"cannot use {v!r} in a generator expression")


def tofloat(e) -> E:
    e = const(e)
    if e.t == "f":
        return e
    if e.t == "i":
        return E("float", (e,), "f")
    raise TypeError(f"cannot use a {e.t} value as a number")


def _num(a, b, force_float=False):
    a, b = const(a), const(b)
    if a.t in ("b", "f3") or b.t in ("b", "f3"):
        raise TypeError("arithmetic needs numbers, not bools or Voronoi results")
    if force_float or a.t != b.t:
        return tofloat(a), tofloat(b), "f"
    return a, b, a.t


def _arith(op, a, b, force_float=False):
    a, b, t = _num(a, b, force_float)
    return E(op, (a, b), t)


def _cmp(op, a, b):
    a, b, _ = _num(a, b)
    return E(op, (a, b), "b")


def _logic(op, a, b):
    a, b = const(a), const(b)
    if a.t != "b" or b.t != "b":
        raise TypeError("& and | combine bool expressions (comparisons)")
    return E(op, (a, b), "b")


def _intconst_op(op, a, n):
    a = const(a)
    if a.t != "i" or not isinstance(n, int) or n <= 0:
        raise TypeError("// and % take an int expression and a positive int constant")
    return E(op, (a,), "i", n)


# ---- functions ----------------------------------------------------------------
def minimum(a, b):
    a, b, t = _num(a, b)
    return E("min", (a, b), t)


def maximum(a, b):
    a, b, t = _num(a, b)
    return E("max", (a, b), t)


def min_(*xs):
    out = xs[0]
    for x in xs[1:]:
        out = minimum(out, x)
    return out


def max_(*xs):
    out = xs[0]
    for x in xs[1:]:
        out = maximum(out, x)
    return out


def clamp(v, lo, hi):
    return minimum(maximum(v, lo), hi)


def clamp01(v):
    return clamp(tofloat(v), 0.0, 1.0)


def absolute(v):
    v = const(v)
    return E("abs", (v,), v.t)


def floor(v):
    return E("floor", (tofloat(v),), "f")


def ifloor(v):
    """floor as int32 (v must stay within int range)."""
    return E("int", (floor(v),), "i")


def sqrt(v):
    return E("sqrt", (tofloat(v),), "f")


def select(c, a, b):
    """c ? a : b (both sides are computed)."""
    c = const(c)
    if c.t != "b":
        raise TypeError("select needs a bool condition")
    a, b, t = _num(a, b)
    return E("select", (c, a, b), t)


def lerp(t, a, b):
    a, b = tofloat(a), tofloat(b)
    return a + t * (b - a)


def smoothstep(e0, e1, v):
    t = clamp01((v - e0) / (e1 - e0))
    return t * t * (3.0 - 2.0 * t)


def _salt(salt):
    if salt is not None:
        return int(salt)
    if not _stack:
        raise RuntimeError("noise outside a pass needs an explicit salt=")
    return _stack[-1].new_salt()


def perlin2(x, y, salt=None):
    """Perlin 2002 noise in 2D, about -0.7..0.7; unit lattice."""
    return E("perlin2", (tofloat(x), tofloat(y)), "f", _salt(salt))


def perlin3(x, y, z, salt=None):
    """Perlin 2002 noise in 3D (12 gradients), about -1..1; unit lattice."""
    return E("perlin3", (tofloat(x), tofloat(y), tofloat(z)), "f", _salt(salt))


def voronoi2(x, y, metric="euclid", salt=None):
    """Voronoi/Worley 2D, one point per unit cell: result .f1 .f2 .value."""
    return E("voronoi2", (tofloat(x), tofloat(y)), "f3", (_salt(salt), _metric(metric)))


def voronoi3(x, y, z, metric="euclid", salt=None):
    return E("voronoi3", (tofloat(x), tofloat(y), tofloat(z)), "f3",
             (_salt(salt), _metric(metric)))


def _metric(m):
    try:
        return {"euclid": 0, "l4": 1}[m]
    except KeyError:
        raise ValueError(f"unknown Voronoi metric {m!r} (euclid or l4)") from None


def octaves(fn, coords, n=4, lacunarity=2.0, gain=0.5, salt=None):
    """Thesis eq. 2.10: sum of fn(coords * lacunarity^o) * gain^o for o < n."""
    base = _salt(salt)
    if salt is None:  # reserve one salt per octave
        for _ in range(n - 1):
            _stack[-1].new_salt()
    total = None
    for o in range(n):
        f, amp = float(lacunarity ** o), float(gain ** o)
        v = fn(*[tofloat(c) * f for c in coords], salt=base + o) * amp
        total = v if total is None else total + v
    return total


def rand2(ix, iy, salt=None):
    """Uniform [0,1) from integer coordinates (an integer hash: exact everywhere)."""
    return E("rand2", (const(ix), const(iy)), "f", _salt(salt))


def rand3(ix, iy, iz, salt=None):
    return E("rand3", (const(ix), const(iy), const(iz)), "f", _salt(salt))


def irand2(ix, iy, n, salt=None):
    """Uniform int in [0, n) from integer coordinates."""
    return E("irand2", (const(ix), const(iy)), "i", (_salt(salt), int(n)))


# ---- passes and programs --------------------------------------------------------
class Pass:
    def __init__(self, prog: "Program", index: int, kind: str):
        self.prog, self.index, self.kind = prog, index, kind
        self.outs: dict[str, E] = {}      # 2D outputs (2D pass) or column outputs (3D)
        self.at: dict[str, E] = {}        # column output -> z of the writing invocation
        self.blk: E | None = None
        self.top_e: E | None = None
        self.x = E("x", (), "i")
        self.y = E("y", (), "i")
        self.z = E("z", (), "i") if kind == "3d" else None

    def read(self, name: str, dx=0, dy=0, reach: int | None = None) -> E:
        """A 2D value of an earlier pass at column (x+dx, y+dy).

        Constant offsets need nothing else; computed offsets need `reach`, the
        largest |dx|, |dy| they can take (offsets are clamped to it)."""
        f = self.prog.fields.get(name)
        if f is None or f[0] >= self.index:
            raise ValueError(f"pass {self.index} reads {name!r}, which no earlier pass writes")
        if isinstance(dx, E) or isinstance(dy, E):
            if reach is None:
                raise ValueError("read at computed offsets needs reach=")
            return E("read", (const(dx), const(dy)), f[1], (name, None, None, int(reach)))
        return E("read", (), f[1], (name, int(dx), int(dy), max(abs(int(dx)), abs(int(dy)))))

    def out(self, name: str, v):
        if self.kind != "2d":
            raise ValueError("out() is for 2D passes; 3D passes use column(name, v, at=z)")
        self._add(name, v)

    def _add(self, name, v):
        v = const(v)
        if v.t not in ("f", "i"):
            raise TypeError(f"{name!r}: a pass output must be a float or an int")
        if name in self.prog.fields:
            raise ValueError(f"{name!r} is written twice")
        self.outs[name] = v
        self.prog.fields[name] = (self.index, v.t)

    # 3D only
    def prev(self, dz: int = 0) -> E:
        """Block id written by the previous 3D pass at (x, y, z+dz); 0 outside 0..255."""
        if self.kind != "3d" or self.prog.last3d(self.index) is None:
            raise ValueError("prev() needs an earlier 3D pass")
        return E("prev", (), "i", int(dz))

    def block(self, v):
        v = const(v)
        if self.kind != "3d" or v.t != "i":
            raise TypeError("block() takes an int expression, in a 3D pass")
        self.blk = v

    def top(self, v):
        """Voxels above this height are air and are not computed. Must depend on the
        column only (x, y, reads); the OpenCL backend launches only the z layers up
        to each chunk's highest top, so a tight top is the biggest speed lever."""
        self.top_e = const(v)
        if self.top_e.t != "i":
            raise TypeError("top() takes an int expression")

    def column(self, name: str, v, at):
        """Per column value, written by the invocation at z == at (thesis §5.2)."""
        if self.kind != "3d":
            raise ValueError("column() is for 3D passes")
        self._add(name, v)
        self.at[name] = const(at)


class Program:
    """A generator description: the passes in order."""

    def __init__(self, name="program"):
        self.name = name
        self.passes: list[Pass] = []
        self.fields: dict[str, tuple[int, str]] = {}
        self._salt = 0

    def new_salt(self) -> int:
        self._salt += 1
        return self._salt

    @contextlib.contextmanager
    def _pass(self, kind):
        p = Pass(self, len(self.passes), kind)
        _stack.append(self)
        try:
            yield p
        finally:
            _stack.pop()
        if kind == "3d" and p.blk is None:
            raise ValueError(f"3D pass {p.index} never calls block()")
        self.passes.append(p)

    def pass2d(self):
        return self._pass("2d")

    def pass3d(self):
        return self._pass("3d")

    def last3d(self, before: int):
        for p in reversed(self.passes[:before]):
            if p.kind == "3d":
                return p
        return None

    def units(self):
        return lower(self)


# ---- lowering: passes -> evaluation units with halos ------------------------------
class Unit:
    """One kernel: a 2D domain (chunk + halo columns) or the 3D chunk volume.

    A 3D unit's `top` is the name of a 2D field (z above it is air, not computed)
    or None (all 256 layers)."""

    def __init__(self, kind, outs, halo=0, blk=None, top=None):
        self.kind, self.outs, self.halo, self.blk, self.top = kind, outs, halo, blk, top

    def roots(self):
        r = list(self.outs.values())
        if self.blk is not None:
            r.append(self.blk)
        return r


def nodes(roots):
    """Nodes reachable from roots, arguments before users."""
    seen, order = set(), []
    stack = [(r, False) for r in reversed(roots)]
    while stack:
        e, done = stack.pop()
        if done:
            order.append(e)
            continue
        if e.id in seen:
            continue
        seen.add(e.id)
        stack.append((e, True))
        stack.extend((a, False) for a in reversed(e.a) if a.id not in seen)
    return order


def _rebuild(roots, fn):
    """Rewrite bottom-up: fn(e, new_args) -> replacement node or None (keep/copy e)."""
    memo = {}
    for e in nodes(roots):
        a = tuple(memo[x.id] for x in e.a)
        n = fn(e, a)
        if n is None:
            n = e if all(x is y for x, y in zip(a, e.a)) else E(e.op, a, e.t, e.k)
        memo[e.id] = n
    return [memo[r.id] for r in roots]


def _subst_z(roots, at):
    """Rewrite expressions with z := at (a column output evaluated as a 2D value)."""
    def fn(e, a):
        if e.op == "z":
            return at
        if e.op == "prev":
            raise ValueError("a column output cannot depend on prev()")
    return _rebuild(roots, fn)


def cse(roots):
    """Merge identical subexpressions (same op, payload and arguments): e.g. the same
    rand3 written in a loop is computed once. Exact: the same ops on the same values."""
    seen = {}

    def fn(e, a):
        key = (e.op, e.t, repr(e.k), tuple(x.id for x in a))  # repr keeps -0.0 apart
        n = seen.get(key)
        if n is None:
            n = seen[key] = e if all(x is y for x, y in zip(a, e.a)) else E(e.op, a, e.t, e.k)
        return n
    return _rebuild(roots, fn)


# Rough cost of a node when evaluated per voxel; hoisting pays above HOIST_COST.
_COST = {"perlin2": 20, "perlin3": 30, "voronoi2": 60, "voronoi3": 150, "rand2": 6,
         "rand3": 7, "irand2": 6, "div": 2, "sqrt": 2, "const": 0, "x": 0, "y": 0}
HOIST_COST = 3


def _hoist(index, roots):
    """Move the column-invariant work of a 3D pass (parts depending on neither z nor
    prev) into hidden 2D fields `_<pass>_<n>` computed once per column: NumPy already
    broadcasts such values, the OpenCL kernel would redo them per voxel. Exact: the
    same operations, only evaluated elsewhere. Returns (fields, new roots)."""
    order = nodes(roots)
    dep, cost = {}, {}
    for e in order:
        dep[e.id] = e.op in ("z", "prev") or any(dep[a.id] for a in e.a)
        if not dep[e.id]:
            cost[e.id] = _COST.get(e.op, 1) + sum(cost[a.id] for a in e.a)
    # frontier: invariant nodes used by a z-dependent node (or roots themselves)
    want = {r.id for r in roots if not dep[r.id] and r.t != "f3"}
    for e in order:
        if dep[e.id]:
            want.update(a.id for a in e.a if not dep[a.id] and a.t != "f3")
    fields, repl = {}, {}
    for e in order:
        if e.id in want and cost[e.id] >= HOIST_COST and e.op != "read":
            name = f"_{index}_{len(fields)}"
            if e.t == "b":  # fields hold numbers; bools travel as 0/1
                fields[name] = E("select", (e, const(1), const(0)), "i")
                repl[e.id] = E("ne", (E("read", (), "i", (name, 0, 0, 0)), const(0)), "b")
            else:
                fields[name] = e
                repl[e.id] = E("read", (), e.t, (name, 0, 0, 0))
    return fields, _rebuild(roots, lambda e, a: repl.get(e.id))


def lower(prog: Program) -> list[Unit]:
    units = []
    for p in prog.passes:
        if p.kind == "2d":
            outs = dict(zip(p.outs, cse(list(p.outs.values()))))
            units.append(Unit("2d", outs))
            continue
        top = None
        roots = [p.blk]
        if p.top_e is not None:
            if any(e.op in ("z", "prev") for e in nodes([p.top_e])):
                raise ValueError("top() must depend on the column only (not z or prev)")
            if p.top_e.op == "read" and p.top_e.k[1:3] == (0, 0):
                top = p.top_e.k[0]
            else:
                top = f"_{p.index}_top"
                units.append(Unit("2d", {top: cse([p.top_e])[0]}))
        fields, (blk,) = _hoist(p.index, cse(roots))
        if fields:
            units.append(Unit("2d", fields))
        units.append(Unit("3d", {}, 0, blk, top))
        for name, v in p.outs.items():
            units.append(Unit("2d", {name: cse(_subst_z([v], p.at[name]))[0]}))
    return halos(units)


def halos(units: list[Unit]) -> list[Unit]:
    """Set each 2D unit's halo, last unit first: a field must cover every reader's
    domain plus reach."""
    need: dict[str, int] = {}
    for u in reversed(units):
        if u.kind == "2d":
            u.halo = max([need.get(n, 0) for n in u.outs] + [0])
        for e in nodes(u.roots()):
            if e.op == "read":
                need[e.k[0]] = max(need.get(e.k[0], 0), u.halo + e.k[3])
        if u.top is not None:
            need[u.top] = max(need.get(u.top, 0), 0)
    return units


def prune(units: list[Unit], want) -> list[Unit]:
    """The 2D units the fields `want` need, with halos for just those readers: e.g.
    the height map and surface without the 3D passes and the wide halos that tree
    crowns need (far terrain, far/README.md). A column output of a 3D pass is a 2D
    unit already (lower: z := at), so no 3D unit is ever needed."""
    need, keep = set(want), []
    for u in reversed(units):
        if u.kind != "2d" or not need & set(u.outs):
            continue
        keep.append(u)
        need.update(e.k[0] for e in nodes(u.roots()) if e.op == "read")
    missing = set(want) - {n for u in keep for n in u.outs}
    if missing:
        raise ValueError(f"no 2D pass writes {', '.join(sorted(missing))}")
    return halos([Unit("2d", dict(u.outs)) for u in reversed(keep)])


def lazy_blocks(order, roots, min_cost):
    """Operands worth computing lazily (cl.py: inside an `if`; execute.py: on the
    voxels that need them): {node id: {slot: [exclusive nodes in order]}}
    and owner {node id: (lazy node id, slot)} of the innermost block holding it. A
    node is exclusive to an operand when every path from it to the roots goes
    through that operand's edge, so skipping it cannot starve another user."""
    users = {}
    for e in order:
        for a in e.a:
            users.setdefault(a.id, []).append(e.id)
    rootids = {r.id for r in roots}
    pos = {e.id: i for i, e in enumerate(order)}
    sub = {}  # node id -> ids of its subtree (itself included)
    for e in order:
        t = {e.id}
        for a in e.a:
            t |= sub[a.id]
        sub[e.id] = t
    byid = {e.id: e for e in order}
    lazy, owner, size = {}, {}, {}
    for e in order:
        slots = {"and": (1,), "or": (1,), "select": (1, 2)}.get(e.op, ())
        for i in slots:
            o = e.a[i]
            if o.id in rootids or users.get(o.id) != [e.id] or o.op == "const":
                continue
            excl = {o.id}
            for nid in sorted(sub[o.id] - {o.id}, key=pos.get, reverse=True):
                if nid not in rootids and all(u in excl for u in users[nid]):
                    excl.add(nid)
            members = sorted(excl, key=pos.get)
            cost = sum(_COST.get(byid[n].op, 1) for n in members)
            if cost < min_cost:
                continue
            lazy.setdefault(e.id, {})[i] = [byid[n] for n in members]
            for n in members:  # innermost block wins: smaller blocks come later
                if n not in owner or len(members) < size[owner[n]]:
                    owner[n] = (e.id, i)
            size[(e.id, i)] = len(members)
    return lazy, owner
