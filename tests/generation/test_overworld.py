"""Overworld (F5): exact agreement of the backends, seamless borders in any order,
and a census of a wide area (every feature present, in the right place)."""
import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.generation import default_backend, make_generator

B = {n: REGISTRY.id(n) for n in REGISTRY.names()}
SEA = 62


def _keys(seed, n):
    rng = np.random.default_rng(abs(seed) % 1000)
    return [tuple(int(v) for v in rng.integers(-4000, 4000, 2)) for _ in range(n)]


@pytest.mark.parametrize("version", [1, 2])
def test_many_noise_calls_are_calls(version):
    """A chunk program's kernels with many calls of a big noise function call gen.cl's
    never-inlined twin (pocl compiles each inlined copy at a fresh install's first
    launch: seconds, issue 28); the hot per-voxel kernels and the far surface's
    program inline them. test_backends_identical checks the values."""
    import re
    from voxel_addon.generation.clsource import source
    g = make_generator("overworld", 7, None, "numpy", version)
    kernels = re.split(r"(?=__kernel void )", source(g.units))[1:]
    calls = [set(re.findall(r"\b(\w+)_c\(", k)) for k in kernels]
    # the biomes: 26 perlin2, 4 voronoi2 (8 columns a work-item)
    assert {"perlin2_8", "voronoi2_8"} <= calls[0]
    if version == 2:
        assert "perlin3_8" in calls[5]  # the surface caves: 24 perlin3_8 at 8 corners
    assert not any(calls[i] for i, u in enumerate(g.units) if u.kind == "3d")
    assert "_c(" not in source(g.units, 1, inline=True).split("// ---- generated passes")[1]


@pytest.mark.parametrize("seed,version", [(0, None), (7, None), (-3, None), (2**40 + 5, None),
                                          (7, 1), (-3, 1)])
def test_backends_identical(cl_device, seed, version):
    """The newest version (None) and version 1, which old worlds keep using."""
    keys = _keys(seed, 10) + [(0, 0), (-1, -1), (100000, -70000)]
    a = make_generator("overworld", seed, None, "numpy", version).generate(keys)
    b = make_generator("overworld", seed, None, "opencl", version).generate(keys)
    for k, x, y in zip(keys, a, b):
        assert x.shape == (16, 16, 256) and x.dtype == np.uint16 and x.flags.f_contiguous
        assert np.array_equal(x, y), f"seed {seed} chunk {k}: {(x != y).sum()} voxels differ"


def test_wide_launches_go_in_small_grid_pieces(cl_device, monkeypatch):
    """A layer-indexed unit wider than pocl's small grid launches in pieces
    (generation/cl.Runner._launch: a stream batch of 30+ chunks compiled another
    work-group variant of each, issue 28); the pieces make NumPy's values."""
    import pyopencl as cl
    from voxel_addon.generation import cl as gcl
    keys = _keys(5, 4) + [(0, 0)]
    a = make_generator("overworld", 5, None, "numpy").generate(keys)
    real, sizes = cl.enqueue_nd_range_kernel, []

    def spy(q, k, size, local, *args, **kw):
        sizes.append(size[0])
        return real(q, k, size, local, *args, **kw)
    monkeypatch.setattr(cl, "enqueue_nd_range_kernel", spy)
    g = make_generator("overworld", 5, None, "opencl")
    g.generate(keys)  # the kernels' first launches outside the count
    whole = len(sizes)
    sizes.clear()
    monkeypatch.setattr(gcl, "SMALL_GRID", 5000)
    b = g.generate(keys)
    assert len(sizes) > whole, (len(sizes), whole)  # some units went in pieces
    for k, x, y in zip(keys, a, b):
        assert np.array_equal(x, y), f"chunk {k}: {(x != y).sum()} voxels differ"


def test_params_change_the_world_and_still_agree(cl_device):
    p = {"sea_level": 70, "caves": 0, "trees": 2.0}
    keys = _keys(11, 6)
    a = make_generator("overworld", 11, p, "numpy").generate(keys)
    b = make_generator("overworld", 11, p, "opencl").generate(keys)
    c = make_generator("overworld", 11, None, "opencl").generate(keys)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert any(not np.array_equal(x, y) for x, y in zip(a, c))


def test_same_program_shares_its_kernels(cl_device):
    """Generators of one program (any seed) share one compiled Runner (a new world's
    source was written again: ~40 ms of its first batch, issue 29); another program
    (a sea level one higher: only constants differ) has its own; concurrent batches
    of two seeds each get their own seed's chunks."""
    import threading
    keys = [(0, 0), (5, -2)]
    a = make_generator("overworld", 3, None, "opencl")
    b = make_generator("overworld", 4, None, "opencl")
    c = make_generator("overworld", 3, {"sea_level": 63}, "opencl")
    want = {g: make_generator("overworld", s, p, "numpy").generate(keys)
            for g, s, p in ((a, 3, None), (b, 4, None), (c, 3, {"sea_level": 63}))}
    assert any(not np.array_equal(x, y) for x, y in zip(want[a], want[c]))
    c.generate(keys)
    got, errors = {a: [], b: []}, []

    def run(g):
        try:
            for _ in range(4):
                got[g].append(g.generate(keys))
        except BaseException as e:  # noqa: BLE001 (reported below)
            errors.append(e)
    ts = [threading.Thread(target=run, args=(g,)) for g in (a, b)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert not errors, errors
    assert a._runner is b._runner and c._runner is not a._runner
    for g in (a, b):
        for res in got[g]:
            assert all(np.array_equal(x, y) for x, y in zip(res, want[g]))
    assert all(np.array_equal(x, y) for x, y in zip(c.generate(keys), want[c]))


@pytest.mark.parametrize("backend", ["opencl", "numpy"])
def test_seamless_any_order(backend, cl_device):
    """A chunk alone equals the same chunk in a batch, in any order; and a tree
    near a border appears on both sides (checked in the census)."""
    g = make_generator("overworld", 5, None, backend)
    keys = [(x, y) for y in range(-1, 2) for x in range(-1, 2)]
    batch = g.generate(keys)
    rev = g.generate(keys[::-1])[::-1]
    for k, a, b in zip(keys, batch, rev):
        assert np.array_equal(a, b)
    for k, a in list(zip(keys, batch))[::4]:
        assert np.array_equal(g.generate([k])[0], a)


def test_backend_choice():
    g = make_generator("overworld", 1)
    assert g.backend_used == default_backend() in ("opencl", "numpy")
    assert make_generator("overworld", 1, None, "numpy").backend_used == "numpy"
    with pytest.raises(VoxelError):
        make_generator("overworld", 1, None, "cuda")


# ---- census ------------------------------------------------------------------
# Windows (chunk rectangles) of seed 7 around a coast, a desert and a snowy range.
WINDOWS = [(-8, -20, 8, -4), (250, -156, 262, -144), (292, -214, 304, -202)]


@pytest.fixture(scope="module")
def census(cl_device):
    g = make_generator("overworld", 7, None, "opencl")
    out = []
    for cx0, cy0, cx1, cy1 in WINDOWS:
        keys = [(x, y) for y in range(cy0, cy1) for x in range(cx0, cx1)]
        chunks = g.generate(keys)
        cols = g.columns(keys, ["groundZ", "river", "ocean"])
        w, h = 16 * (cx1 - cx0), 16 * (cy1 - cy0)
        reg = np.zeros((w, h, 256), np.uint16)
        f = {n: np.zeros((w, h), v[0].dtype) for n, v in cols.items()}
        for i, (x, y) in enumerate(keys):
            sx, sy = 16 * (x - cx0), 16 * (y - cy0)
            reg[sx:sx + 16, sy:sy + 16] = chunks[i]
            for n in f:
                f[n][sx:sx + 16, sy:sy + 16] = cols[n][i]
        out.append((reg, f))
    return out


def test_every_feature_present(census):
    total = sum(np.bincount(r.ravel(), minlength=len(REGISTRY)) for r, _ in census)
    want = ["stone", "dirt", "grass", "snow", "sand", "ore", "log", "leaves", "flowers",
            "tall_grass", "wheat", "mushroom", "glowing_mushroom", "cactus", "water"]
    missing = [n for n in want if total[B[n]] == 0]
    assert not missing, f"missing features: {missing}"


def _below(reg, mask):
    xs, ys, zs = np.nonzero(mask)
    return reg[xs, ys, zs - 1], zs


def test_placement_rules(census):
    for reg, f in census:
        gz = f["groundZ"]
        z = np.arange(256)
        # water never above sea level; a river column holds water up to sea level
        water = reg == B["water"]
        assert not water[:, :, SEA + 1:].any()
        river = (f["river"] > 0.5) & (f["ocean"] < 0) & (gz < SEA)
        if river.any():
            assert water[river][:, SEA].all()
        # snow only high up
        _, zs = _below(reg, reg == B["snow"])
        assert (zs > 130).all()
        # cactus on sand or cactus
        b, _ = _below(reg, reg == B["cactus"])
        assert np.isin(b, [B["sand"], B["cactus"]]).all()
        # logs on grass/dirt or log
        b, _ = _below(reg, reg == B["log"])
        assert np.isin(b, [B["grass"], B["dirt"], B["log"]]).all()
        # small plants on grass
        for n in ("flowers", "tall_grass", "wheat"):
            b, _ = _below(reg, reg == B[n])
            assert (b == B["grass"]).all(), n
        # ore and glowing mushrooms underground
        for n in ("ore", "glowing_mushroom"):
            xs, ys, zs = np.nonzero(reg == B[n])
            assert (zs < gz[xs, ys]).all(), n
        # leaves always near a trunk, also across chunk borders (region stitched)
        logs = reg == B["log"]
        near = logs.copy()
        for axis, r in ((0, 3), (1, 3), (2, 2)):
            acc = near.copy()
            for s in range(1, r + 1):
                acc |= np.roll(near, s, axis) | np.roll(near, -s, axis)
            near = acc
        leaves = reg == B["leaves"]
        inner = leaves[3:-3, 3:-3]
        assert near[3:-3, 3:-3][inner].all(), "leaves far from any trunk"
        # beaches: land at sea level next to the ocean is sand
        top = np.take_along_axis(reg, gz[:, :, None], 2)[:, :, 0]
        beach = (gz >= SEA - 1) & (gz <= SEA + 1) & (f["ocean"] > -0.02) & (f["ocean"] <= 0)
        if beach.sum() > 50:
            assert np.mean(top[beach] == B["sand"]) > 0.8
