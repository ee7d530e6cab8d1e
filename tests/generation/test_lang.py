"""The pass language: the README example runs on both backends with equal results;
halos, neighbour reads, prev() and column outputs behave; mistakes are refused."""
import re
from pathlib import Path

import numpy as np
import pytest

from voxel_addon.generation import lang as L
from voxel_addon.generation import lower
from voxel_addon.generation.passgen import PassGenerator

README = Path(__file__).resolve().parents[2] / "voxel_addon/generation/README.md"


def _example():
    code = re.search(r"```python\n(.*?)```", README.read_text(), re.S).group(1)
    code = code.replace('chunks = Islands(seed=1, backend="numpy")', "# ")
    ns = {}
    exec(compile(code, str(README), "exec"), ns)
    return ns["Islands"]


def test_readme_example_both_backends(cl_device):
    Islands = _example()
    keys = [(0, 0), (5, -3), (-20, 7)]
    a = Islands(seed=1, backend="numpy").generate(keys)
    b = Islands(seed=1, backend="opencl").generate(keys)
    for x, y in zip(a, b):
        assert np.array_equal(x, y)
    allb = np.concatenate([x.ravel() for x in a])
    assert len(np.unique(allb)) >= 5  # stone, dirt, grass/sand, water, air, flowers...


class Probe(PassGenerator):
    """Checks halo reads against a brute-force formula of the same noise."""
    name = "probe"

    def program(self):
        g = L.Program()
        with g.pass2d() as p:
            p.out("h", L.ifloor(L.perlin2(p.x / 9, p.y / 9, salt=1) * 40 + 100))
        with g.pass2d() as p:
            off = L.irand2(p.x, p.y, 7, salt=2) - 3
            p.out("nb", p.read("h", off, -off, reach=3))
            p.out("east", p.read("h", 2, 0))
        with g.pass3d() as p:
            p.top(p.read("h"))
            p.block(select_block(p))
            p.column("solid_at_h", L.select(p.z < 0, 1, 2), at=p.read("h"))
        with g.pass3d() as p:
            p.block(L.select(p.prev(-1) == 1, 2, p.prev()))
        return g


def select_block(p):
    return L.select(p.z < p.read("east"), 1, 3)


@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_halo_reads_match_brute_force(backend, cl_device):
    from voxel_addon.generation import noise as N
    g = Probe(3, None, backend)
    keys = [(0, 0), (-1, 2)]
    cols = g.columns(keys, ["h", "nb", "east", "solid_at_h"])
    blocks = g.generate(keys)
    s32 = N.seed32(3)
    perm = N.perm_table(s32)
    for i, (cx, cy) in enumerate(keys):
        x = (cx * 16 + np.arange(-4, 20, dtype=np.int32))[:, None]
        y = (cy * 16 + np.arange(-4, 20, dtype=np.int32))[None, :]
        hh = np.floor(N.perlin2(x.astype(np.float32) / np.float32(9), y.astype(np.float32)
                                / np.float32(9), perm, N.inst(s32, 1)) * np.float32(40)
                      + np.float32(100)).astype(np.int32)
        core = np.s_[4:20, 4:20]
        assert np.array_equal(cols["h"][i], hh[core])
        assert np.array_equal(cols["east"][i], hh[6:22, 4:20])
        off = (N.hash2(x[4:20], y[:, 4:20], N.inst(s32, 2)) >> np.uint32(8)) % np.uint32(7)
        off = off.astype(np.int32) - 3
        ii, jj = np.meshgrid(np.arange(16), np.arange(16), indexing="ij")
        assert np.array_equal(cols["nb"][i], hh[ii + 4 + off, jj + 4 - off])
        assert (cols["solid_at_h"][i] == 2).all()
        b = blocks[i]
        zs = np.arange(256)
        top = hh[core][:, :, None]
        want = np.where(zs[None, None] <= top,
                        np.where(zs[None, None] < hh[6:22, 4:20][:, :, None], 1, 3), 0)
        # pass 2 turns a block above stone (1) into dirt (2)
        below = np.concatenate([np.zeros((16, 16, 1), int), want[:, :, :-1]], 2)
        want = np.where(below == 1, 2, want)
        assert np.array_equal(b, want)


def test_mistakes_are_refused():
    g = L.Program()
    with pytest.raises(ValueError):
        with g.pass2d() as p:
            p.read("nothing")
    with pytest.raises(TypeError):
        with g.pass2d() as p:
            if p.x > 3:
                pass
    with pytest.raises(ValueError):
        with g.pass2d() as p:
            p.read("x", dx=p.x, dy=0)
    g = L.Program()
    with g.pass2d() as p:
        p.out("a", 1)
    with pytest.raises(ValueError):
        with g.pass3d() as p:
            p.out("b", 1)
    with pytest.raises(ValueError):
        with g.pass3d() as p:
            p.prev()


class Lazy(PassGenerator):
    """Column-only noise in a 3D pass, a repeated rand3 and expensive operands on the
    right of & / select: exercises hoisting, CSE and the lazy OpenCL blocks."""
    name = "lazy"

    def program(self):
        g = L.Program()
        with g.pass2d() as p:
            p.out("h", L.ifloor(L.perlin2(p.x / 9, p.y / 9, salt=1) * 40 + 100))
        with g.pass3d() as p:
            x, y, z = p.x, p.y, p.z
            col = L.perlin2(x / 7, y / 7, salt=3) > 0.1
            r = L.rand3(x, y, z, salt=4)
            p.top(p.read("h") + 2)
            deep = (z < p.read("h") - 3) & (L.perlin3(x / 11, y / 11, z / 5, salt=5) > 0.0)
            hole = (L.octaves(L.perlin3, (x / 20, y / 20, z / 9), n=2, salt=6) > 0.2) | (r < 0.01)
            p.block(L.select(deep, L.select(hole, 0, 1), L.select(col & (L.rand3(x, y, z, salt=4)
                                                                       < 0.5), 2, 3)))
        return g


def test_lowering_hoists_merges_and_stays_exact(cl_device):
    units = Lazy(2, None, "numpy").units
    u3 = [u for u in units if u.kind == "3d"][0]
    ops = [e.op for e in lower.nodes(u3.roots())]
    assert "perlin2" not in ops            # column-only noise went to a hidden 2D field
    assert ops.count("rand3") == 1         # the repeated rand3 is computed once
    from voxel_addon.generation.clsource import source
    assert "if (" in source(units)         # expensive operands are computed lazily
    keys = [(0, 0), (3, -2)]
    a = Lazy(2, None, "numpy").generate(keys)
    b = Lazy(2, None, "opencl").generate(keys)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert len(np.unique(np.concatenate([x.ravel() for x in a]))) == 4


def test_top_must_depend_on_the_column_only():
    g = L.Program()
    with g.pass2d() as p:
        p.out("h", 5)
    with g.pass3d() as p:
        p.top(p.z)
        p.block(1)
    with pytest.raises(ValueError):
        lower.lower(g)


class AllOps(PassGenerator):
    """Every op the 8-lane 3D kernels implement (cl._GenV), in z-dependent forms that
    stay in the 3D pass, plus a 3D pass with Voronoi that stays scalar."""
    name = "allops"

    def program(self):
        g = L.Program()
        with g.pass2d() as p:
            p.out("h", L.ifloor(L.perlin2(p.x / 23, p.y / 23) * 30 + 90))
            p.out("w", L.perlin2(p.x / 7, p.y / 7))
            p.out("flag", L.select(L.perlin2(p.x / 5, p.y / 5) > 0, 1, 0))
        with g.pass3d() as p:
            x, y, z = p.x, p.y, p.z
            p.top(p.read("h") + 3)
            n3 = L.perlin3(x / 13, y / 17, z / 7)
            n2 = L.perlin2(x / 9 + z / 5, y / 11)
            r3, r2 = L.rand3(x, y, z), L.rand2(x + z, y)
            ir = L.irand2(x - z, y, 5)
            nb = p.read("h", ir - 2, 2 - ir, reach=2)          # a neighbour per lane
            f = L.floor(n3 * 10.0) + L.sqrt(L.absolute(n3)) + L.min_(n3, p.read("w")) \
                + L.max_(n2, r2) - L.clamp01(n2) \
                + L.select(r3 < 0.5, L.perlin3(y / 4, x / 6, z / 5), n2 * 2.0)  # lazy float arm
            i = L.ifloor(f * 7.0) + (x - z) // 3 + (y + z) % 5 + L.absolute(x - 40 * z) \
                + L.min_(x, z) + L.max_(y, nb - z)
            c = ((n3 > 0.1) & ~(r3 < 0.3)) | (p.read("w") > 0.2) | (p.read("flag") == 1)
            lazy = c & (L.perlin3(x / 5, y / 5, z / 3) > 0.0)    # computed inside an `if`
            arm = L.select(n2 > 0.0, L.ifloor(L.perlin3(x / 3, z / 3, y / 3) * 4.0), -i)
            lor = (r2 > 0.6) | (L.perlin3(x / 6, y / 4, z / 4) > 0.2)  # lazy `|`, nested
            p.block(L.select(lazy, 9, 1 + (i + arm + L.select(c | lor, 0, 3)) % 7))
        with g.pass3d() as p:
            p.block(L.select((p.prev(-1) == 9) & (p.prev(1) != 9), 8, p.prev()))
        with g.pass3d() as p:
            hole = L.voronoi3(p.x / 9, p.y / 9, p.z / 9)[0] > 0.5
            p.block(L.select(hole & (p.prev() == 1), 0, p.prev()))
        return g


def test_vector_kernels_every_op_exact(cl_device):
    from voxel_addon.generation import clsource as cl
    units = AllOps(5, None, "numpy").units
    assert [cl.vectorizable(u) for u in units if u.kind == "3d"] == [True, True, False]
    # two-load lookups (perlin3_8r) only where x spans < 1 cell per row and y, z are
    # lane-uniform: perlin3(x / 13, y / 17, z / 7) and not x / 3, x / 5 or y / 4, x / 6
    assert len(re.findall(r"= perlin3_8r\(", cl.source(units))) == 1
    keys = [(0, 0), (-1, -1), (-3, 2), (5, -7), (-200, 130)]
    a = AllOps(5, None, "numpy").generate(keys)
    b = AllOps(5, None, "opencl").generate(keys)
    for k, x, y in zip(keys, a, b):
        assert np.array_equal(x, y), f"chunk {k}: {(x != y).sum()} voxels differ"
    allb = np.concatenate([x.ravel() for x in a])
    assert set(np.unique(allb)) == set(range(10))   # every branch taken somewhere


@pytest.mark.parametrize("gen", ["allops", "overworld"])
def test_numpy_lazy_operands_change_nothing(gen, monkeypatch):
    """execute.py computes lazy operands on gathered voxels: an oracle without OpenCL,
    the same program evaluated eagerly (no lazy blocks) must give the same blocks."""
    from voxel_addon.generation import execute, make_generator

    def run():
        g = AllOps(5, None, "numpy") if gen == "allops" else make_generator("overworld", 7, None, "numpy")
        keys = [(0, 0), (-3, 2), (-200, 130)] if gen == "allops" else [(0, -12), (-3, -10), (255, -150)]
        return g.generate(keys), g.units
    monkeypatch.setattr(execute, "LAZY_SHARE", 2.0)   # always gather, however many voxels
    lazy, units = run()
    order = execute.nodes([r for u in units for r in u.roots()])
    assert execute.lazy_blocks(order, [r for u in units for r in u.roots()], execute.LAZY_COST)[0]
    monkeypatch.setattr(execute, "LAZY_COST", 10**9)  # nothing lazy
    eager, _ = run()
    for x, y in zip(lazy, eager):
        assert np.array_equal(x, y), f"{(x != y).sum()} voxels differ"


def test_the_same_program_is_the_same_source():
    """A second generator of the same program (another world, seed or scene) writes the
    very text of the first, so opencl.build and pocl's disk cache find its build (node
    ids, which named the variables, come from one counter per process)."""
    from voxel_addon.generation import make_generator
    from voxel_addon.generation.clsource import source
    from voxel_addon.generation.lower import prune
    a, b = (make_generator("overworld", s, None, "numpy") for s in (1, 2))
    assert source(a.units) == source(b.units)
    want = a.surface_wants()
    assert source(prune(a.units, want), 1) == source(prune(b.units, want), 1)
    assert source(make_generator("overworld", 1, None, "numpy", 1).units) != source(a.units)


def test_and_chains_nest_to_the_right_and_the_first_test_guards_the_rest():
    """lower.right_nest: ((a & b) & c) | d becomes (a & (b & c)) | d, so lazy_blocks can
    put b & c behind a (each of b, c alone is too cheap to be lazy: issue 29's plants
    pass ran its cactus tests on every voxel); a chain node with another user stays."""
    x = L.E("x", (), "i")
    a, b, c, d = (x > 1), (x < 9), (L.E("rand2", (x, x), "f", 3) < 0.5), (x == 4)
    nested, = lower.right_nest([((a & b) & c) | d])
    assert nested.op == "or" and nested.a[1] is d
    left = nested.a[0]
    assert left.op == "and" and left.a[0] is a
    assert left.a[1].op == "and" and left.a[1].a == (b, c)
    # a cost bound (9) over c alone (8) and under b & c: lazy only once nested
    e = ((a & b) & c) | d
    assert not lower.lazy_blocks(lower.nodes([e]), [e], 9)[0]
    lazy, _ = lower.lazy_blocks(lower.nodes([nested]), [nested], 9)
    assert 1 in lazy.get(left.id, {})  # b & c behind a
    shared = a & b
    kept = lower.right_nest([shared & c, shared | d])
    assert kept[0].a[0] is shared  # (shared has another user: not taken apart)
