"""The batched paths: build_chunks over a whole area equals chunk-by-chunk meshing, the
OpenCL batch (many tiles per launch, compacted output) equals NumPy, overflow regrows."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import meshing
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.meshing import cl as mcl
from voxel_addon.meshing import scenes

from .helpers import covered_by_quads, exposed


@pytest.fixture(scope="module")
def cave():
    return np.asfortranarray(scenes.blocks("cave")[:50, :34])     # 3x2 chunks + ring


def _same(a, b):
    assert a.keys() == b.keys()
    for k in a:
        assert np.array_equal(a[k].vertices, b[k].vertices), k
        assert np.array_equal(a[k].ranges, b[k].ranges), k
        assert np.array_equal(a[k].quads, b[k].quads), k


def test_build_chunks_equals_one_by_one(cave):
    got = meshing.build_chunks(cave, (5, -2), region_h=32)
    assert set(got) == {(5 + i, -2 + j) for i in range(3) for j in range(2)}
    for (i, j), w in scenes.chunk_windows(cave):
        one = meshing.build_chunk(np.asfortranarray(w), region_h=32)
        _same({0: got[5 + i, -2 + j]}, {0: one})
        q = meshing.quads(np.asfortranarray(w), split=32)
        assert np.array_equal(np.sort(one.quads, order=["face", "z", "y", "x"]), q)
    sub = meshing.build_chunks(cave, (5, -2), region_h=32, keys=[(6, -1)])
    _same(sub, {(6, -1): got[6, -1]})


@pytest.mark.parametrize("method", meshing.METHODS)
def test_build_chunks_opencl_equals_numpy(method, greedy_path, cave):
    _same(meshing.build_chunks(cave, method=method),
          meshing.build_chunks(cave, method=method, backend="opencl"))


def test_opencl_z_range_and_split(greedy_path, cave):
    w = np.asfortranarray(cave[16:34, 0:18])
    for kw in (dict(z0=5, z1=200, split=16), dict(z0=33, z1=40), dict(z0=0, z1=1),
               dict(split=1, z0=60, z1=75)):
        for m in ("greedy", "none", "squares_ext"):
            a = meshing.quads(w, method=m, **kw)
            assert np.array_equal(a, meshing.quads(w, method=m, backend="opencl", **kw)), kw
            if m == "greedy":
                want = {k: n for k, n in exposed(w, "context").items()
                        if kw["z0"] <= k[3] < kw["z1"]}
                assert covered_by_quads(a) == want


def test_opencl_output_overflow_regrows(cl_device, cave):
    ref = meshing.build_chunks(cave, method="none")
    old = mcl.START_CAP
    mcl._bufs.pop("out", None)
    mcl._bufs.pop("cap", None)
    mcl.START_CAP = 16
    try:
        _same(ref, meshing.build_chunks(cave, method="none", backend="opencl"))
    finally:
        mcl.START_CAP = old
    assert mcl._bufs["cap"] >= sum(len(c.quads) for c in ref.values())


def test_build_chunks_bad_input():
    with pytest.raises(VoxelError, match="ring"):
        meshing.build_chunks(np.zeros((20, 18, 256), np.uint16))
    with pytest.raises(VoxelError, match="region"):
        meshing.build_chunks(np.zeros((18, 18, 256), np.uint16), region_h=3)


def _sparse(seed):
    """2×2 chunks + ring: rock below z=100 with single air pockets, air above with single
    blocks, many of them on tile edges and in the ring (the layer-skipping must see them)."""
    rng = np.random.default_rng(seed)
    b = np.zeros((34, 34, 256), np.uint16, order="F")
    b[:, :, :100] = 1
    edge = np.array([0, 1, 2, 15, 16, 17, 18, 31, 32, 33])
    for k in range(120):
        x, y = (rng.choice(edge), rng.integers(34)) if k % 2 else (rng.integers(34), rng.choice(edge))
        if k % 3 == 0:
            b[x, y, rng.integers(1, 100)] = 0          # pocket in the rock
        else:
            b[x, y, rng.integers(100, 255)] = rng.choice([1, 8, 9, 14, 16])
    b[:, :, 0] = 0                                      # open floor in places
    b[5:30, 5:30, 0] = 1
    return b


@pytest.mark.parametrize("seed", [1, 2])
def test_opencl_sparse_edges(seed, greedy_path):
    b = _sparse(seed)
    for m in ("greedy", "none"):
        _same(meshing.build_chunks(b, method=m), meshing.build_chunks(b, method=m, backend="opencl"))
        w = np.asfortranarray(b[15:33, 15:33])
        assert covered_by_quads(meshing.quads(w, method=m, backend="opencl")) == exposed(w, "context")


def test_wide_window_falls_back(cl_device):
    from .helpers import random_window
    b = random_window(9, shape=(300, 4, 256), band=(50, 54))
    assert np.array_equal(meshing.quads(b, border="air"),
                          meshing.quads(b, border="air", backend="opencl"))


@pytest.mark.parametrize("switch", ["MASKS", "CPU_TUNED"])
def test_opencl_flag_table_path(greedy_path, cave, switch):
    """The kernels' table-lookup variant (used past 64 block types) and their portable
    forms (devices other than a CPU) give the same."""
    ref = meshing.build_chunks(cave[:, :18])
    setattr(mcl, switch, False)
    try:
        _same(ref, meshing.build_chunks(cave[:, :18], backend="opencl"))
        b = _sparse(3)
        assert np.array_equal(meshing.quads(b, method="none"),
                              meshing.quads(b, method="none", backend="opencl"))
    finally:
        setattr(mcl, switch, True)


@pytest.mark.parametrize("region_h", [64, 1])   # the 16-bit radix order and the 64-bit key
def test_build_chunks_vertex_order(cave, region_h):
    from voxel_addon.meshing.vertex import PASS_OF
    for m in meshing.build_chunks(cave, region_h=region_h).values():
        q = m.quads
        want = np.lexsort((q["x"], q["y"], q["z"], q["face"], PASS_OF[q["block"]],
                           q["z"] // region_h))
        assert (want == np.arange(len(q))).all()


@pytest.mark.parametrize("kw", [{}, dict(split=32), dict(z0=61, z1=131, split=64)])
def test_opencl_greedy_bit_rows(greedy_path, kw):
    """The greedy on bit rows (gpu/mesh_greedy.cl `tile`): z-slice rows wider than one
    64-bit word, x/y rows (along z) whose runs cross word and region boundaries."""
    from .helpers import random_window
    names = ["stone"] * 6 + ["air", "glass", "water", "leaves", "cactus"]
    b = random_window(4, shape=(150, 7, 256), band=(40, 150), names=names)
    b[:, 3, 60:140] = REGISTRY.id("glass")     # long runs over z 64 and 128
    b[5:140, :, 90] = REGISTRY.id("log")       # a layer with one long x run
    for border in ("air", "context"):
        assert np.array_equal(meshing.quads(b, border=border, **kw),
                              meshing.quads(b, border=border, backend="opencl", **kw))
    # chunk tiles (rows of 16 as vectors): blend and # blocks stacked, faces between hidden
    c = random_window(5, shape=(34, 34, 256), band=(60, 140),
                      names=["water", "glass", "water", "cactus", "stone", "air"])
    c[:, :, 100:110] = REGISTRY.id("water")
    _same(meshing.build_chunks(c, region_h=kw.get("split", 64)),
          meshing.build_chunks(c, region_h=kw.get("split", 64), backend="opencl"))


def test_greedy_path_by_device(cl_device, monkeypatch):
    """The tile kernel on a CPU device (pocl), the per-slice kernels elsewhere; the
    environment overrides, a wrong name is a one-line error."""
    from voxel_addon import opencl
    monkeypatch.delenv("VOXEL_MESH_KERNEL", raising=False)
    assert mcl.path() == ("tile" if opencl.on_cpu() else "slices")
    monkeypatch.setenv("VOXEL_MESH_KERNEL", "slices")
    assert mcl.path() == "slices"
    monkeypatch.setenv("VOXEL_MESH_KERNEL", "tiles")
    with pytest.raises(VoxelError, match="VOXEL_MESH_KERNEL='tiles'"):
        meshing.build_chunks(np.zeros((18, 18, 256), np.uint16), backend="opencl")


def test_greedy_as_on_a_gpu(cl_device, cave, monkeypatch):
    """What a GPU platform runs (`slices`, work groups of up to 64 over a padded launch,
    no CPU_DEVICE forms), here on pocl: the NumPy reference's meshes."""
    monkeypatch.setattr(mcl, "_on_cpu", lambda: False)
    monkeypatch.delenv("VOXEL_MESH_KERNEL", raising=False)
    assert mcl.path() == "slices"
    for m in ("greedy", "none"):
        _same(meshing.build_chunks(cave, method=m),
              meshing.build_chunks(cave, method=m, backend="opencl"))
