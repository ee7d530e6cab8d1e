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


def coarse(p, fn, cell):
    """fn(x, y, z) (a float function of the voxel's coordinates alone: no reads, no
    prev) sampled on a lattice of cells (cx, cy, cz) voxels and trilinearly
    interpolated in between, as Minecraft samples its density: a 3D pass evaluates
    fn once per lattice point of the chunk instead of once per voxel (lower.py)."""
    cx, cy, cz = (int(c) for c in cell)
    if p.kind != "3d" or not all(c in (1, 2, 4, 8, 16) for c in (cx, cy, cz)):
        raise ValueError("coarse() is for 3D passes, cells of 1, 2, 4, 8 or 16 voxels")
    return E("coarse", (p.x, p.y, p.z), "f", ((cx, cy, cz), Body(tofloat(fn(p.x, p.y, p.z)))))


class Body:
    """A coarse function's expression in its node's payload, not among its arguments
    (those are the voxel's x, y, z): it is evaluated at lattice points, never at the
    voxel, and a column output's z := at must not reach into it."""
    __slots__ = ("e",)

    def __init__(self, e):
        self.e = e

    def __repr__(self):  # lower.cse keys nodes by their payload's repr
        return f"body{self.e.id}"


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
