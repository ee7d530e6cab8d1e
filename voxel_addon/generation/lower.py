"""Lowering the generator language (lang.py) to evaluation units: a 2D domain with the
halo its readers need, or the 3D chunk volume; with the exact rewrites both backends
share (common subexpressions, column-invariant work hoisted into 2D fields, pruning
to the fields asked for, lazily computed costly operands). execute.py (NumPy) and
cl.py (OpenCL C) run the units."""
from __future__ import annotations

from ..core import chunk as C
from .lang import Body, E, Program, const, tofloat

class Unit:
    """One kernel: a 2D domain (chunk + halo columns) or the 3D chunk volume.

    A 3D unit's `top` is the name of a 2D field (z above it is air, not computed)
    or None (all 256 layers)."""

    def __init__(self, kind, outs, halo=0, blk=None, top=None, cell=None):
        self.kind, self.outs, self.halo, self.blk, self.top = kind, outs, halo, blk, top
        self.cell = cell  # "g3" and "gc" units: the lattice's cell (cx, cy, cz), see lattice()

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


def shape(units) -> tuple:
    """What the units compute, without node ids (a new per-process counter value each
    time a program is built): equal for the same program built twice, so its compiled
    kernels can be shared (cl.shared)."""
    order, key = _shape([r for u in units for r in u.roots()])
    num = {e.id: i for i, e in enumerate(order)}
    return key, tuple((u.kind, tuple((n, num[e.id]) for n, e in u.outs.items()), u.halo,
                       None if u.blk is None else num[u.blk.id], u.top, u.cell)
                      for u in units)


def _shape(roots):
    order = nodes(roots)
    num = {e.id: i for i, e in enumerate(order)}
    return order, tuple((e.op, e.t, _payload(e.k), tuple(num[a.id] for a in e.a))
                        for e in order)


def _payload(k):
    """A payload by value (repr, as `cse` keys them), a coarse Body by its expression."""
    if isinstance(k, tuple):
        return tuple(_payload(x) for x in k)
    if isinstance(k, Body):
        return "body", _shape([k.e])[1]
    return repr(k)


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


# ---- coarse (lang.coarse): a lattice of samples, interpolated -------------------
def lattice_dims(cell):
    """Lattice points per chunk along x, y, z: both chunk faces and z = 256 included."""
    cx, cy, cz = cell
    return C.SIZE // cx + 1, C.SIZE // cy + 1, C.HEIGHT // cz + 1


def levels(cell, top):
    """The lattice levels a voxel at z <= top interpolates between: 0..levels - 1
    (top: a column's or chunk's highest computed voxel, -1 for none)."""
    return min(int(top) // cell[2] + 2, lattice_dims(cell)[2]) if top >= 0 else 0


def _frac(v, c):
    """The position of coordinate v in its cell of c voxels, 0..1 (exact: c is 2**k)."""
    return tofloat(v % c) * (1.0 / c)


def _lerp(t, a, b):
    return a + t * (b - a)


def _interp_xy(cell, x, y, corner):
    """Bilinear in x then y between corner(di, dj) samples: the first stage of the one
    order of operations every form of a coarse node shares (exact weights)."""
    fx, fy = _frac(x, cell[0]), _frac(y, cell[1])
    return _lerp(fy, _lerp(fx, corner(0, 0), corner(1, 0)), _lerp(fx, corner(0, 1), corner(1, 1)))


def _check_body(body):
    for n in nodes([body]):
        if n.op in ("read", "prev", "coarse", "gread", "cread"):
            raise ValueError(f"coarse(): the sampled function may use x, y, z only, not {n.op}")


def _xyz():
    return E("x", (), "i"), E("y", (), "i"), E("z", (), "i")


def expand(roots):
    """coarse nodes written out: the samples at the 8 corners computed in place, the
    reference form: cl.py compiles column outputs (2D units) so; execute.py evaluates
    the 8 corners of such a node stacked, in one go (Runner._coarse), op for op this."""
    def fn(e, a):
        if e.op != "coarse":
            return None
        (cx, cy, cz), body = e.k[0], e.k[1].e
        _check_body(body)
        x, y, z = a   # the voxel (a column output: z is its `at`)
        org = [v - (v % c) for v, c in ((x, cx), (y, cy), (z, cz))]

        def level(k):
            def corner(i, j):
                at = {"x": org[0] + i * cx, "y": org[1] + j * cy, "z": org[2] + k * cz}
                return _rebuild([body], lambda n, _: at.get(n.op))[0]
            return _interp_xy(e.k[0], x, y, corner)
        return _lerp(_frac(z, cz), level(0), level(1))
    return _rebuild(roots, fn)


def lattice(index, roots, top=None):
    """coarse nodes of a 3D pass in three stages, the same values as expand() (the
    same samples, the same operations): a "g3" unit samples the function at every
    lattice point of the chunk; a "gc" unit interpolates those in x and y for every
    column at every lattice level (`gread`: a sample at a lattice corner); the voxel
    interpolates its column's two levels in z (`cread`: a column's level). Per voxel
    that is two loads and a lerp instead of the function. Like the 3D unit, the
    lattice units stop at the levels the pass's `top` needs.
    Returns (units in order, new roots)."""
    units: dict = {}  # cell -> [g3 unit, gc unit]: one kernel each for all its functions
    got: dict = {}

    def fn(e, a):
        if e.op != "coarse":
            return None
        cell, body = e.k[0], e.k[1].e
        _check_body(body)
        key = (body.id, cell)
        if key not in got:
            name = got[key] = f"_{index}_g{len(got)}"
            x, y, z = _xyz()
            col = _interp_xy(cell, x, y, lambda i, j: E("gread", (x, y, z), "f", (name, cell, i, j)))
            g3, gc = units.setdefault(cell, [Unit("g3", {}, top=top, cell=cell),
                                             Unit("gc", {}, top=top, cell=cell)])
            g3.outs[name] = body
            gc.outs[name + "c"] = col
        name = got[key] + "c"
        x, y, z = a
        lv = [E("cread", (x, y, z), "f", (name, cell, k)) for k in (0, 1)]
        return _lerp(_frac(z, cell[2]), lv[0], lv[1])
    new = _rebuild(roots, fn)
    return [u for pair in units.values() for u in pair], new


# Rough cost of a node when evaluated per voxel; hoisting pays above HOIST_COST.
_COST = {"coarse": 240, "perlin2": 20, "perlin3": 30, "voronoi2": 60, "voronoi3": 150, "rand2": 6,
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
        dep[e.id] = e.op in ("z", "prev", "cread") or any(dep[a.id] for a in e.a)
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
        grids, roots = lattice(p.index, cse(roots), top)
        units += [Unit(g.kind, dict(zip(g.outs, cse(list(g.outs.values())))), top=top,
                       cell=g.cell) for g in grids]
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


def right_nest(roots):
    """Chains of boolean & (|) nested to the right: ((a & b) & c) becomes a & (b & c),
    where the inner node has no other user. Bitwise & and | of booleans are associative,
    so the values are the same; but lazy_blocks weighs each right operand alone, and a
    left-nested chain of cheap tests (`air & (z > gz) & (read(top) == sand) & ...`) was
    computed whole on every voxel, where nested the first test decides whether the
    rest runs at all (issue 29: the plants pass, most of its voxels not air)."""
    users: dict = {}
    order = nodes(roots)
    for e in order:
        for a in e.a:
            users[a.id] = users.get(a.id, 0) + 1
    rootids = {r.id for r in roots}

    def fn(e, a):
        if e.op not in ("and", "or") or e.t != "b":
            return None
        left = e.a[0]
        if left.op != e.op or left.t != "b" or users.get(left.id) != 1 or left.id in rootids:
            return None
        x, y = a[0].a  # the rewritten left node: (x op y)
        return E(e.op, (x, E(e.op, (y, a[1]), "b")), "b", e.k)
    return _rebuild(roots, fn)


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
