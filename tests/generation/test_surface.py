"""Generator.surface: the 2D passes alone (pruned, 1-column domains) give exactly the
height, block and water of the generated chunks' columns, on both backends."""
import numpy as np
import pytest

from voxel_addon.core import chunk as C
from voxel_addon.core import surface
from voxel_addon.generation import lower, make_generator
from voxel_addon.generation import overworld as O

SEED = 7


def _columns(gen, keys):
    arrays = gen.generate(keys)
    cx0, cy0 = min(k[0] for k in keys), min(k[1] for k in keys)
    cx1, cy1 = max(k[0] for k in keys) + 1, max(k[1] for k in keys) + 1
    return surface.columns(C.paste(zip(keys, arrays), cx0, cy0, cx1, cy1)), cx0 * 16, cy0 * 16


def test_prune_keeps_only_what_the_fields_need():
    g = make_generator("overworld", SEED, None, "numpy")
    units = lower.prune(g.units, ["groundZ", "top"])
    assert all(u.kind == "2d" for u in units)
    outs = [set(u.outs) for u in units]
    assert "groundZ" in outs[0] and "top" in outs[-1]
    # the slope of `top` reads groundZ one column away; tree crowns (3+) are gone
    assert units[0].halo == 1 and units[-1].halo == 0
    full = {n: u.halo for u in g.units if u.kind == "2d" for n in u.outs}
    assert full["groundZ"] > 1
    with pytest.raises(ValueError, match="nothing"):
        lower.prune(g.units, ["nothing"])


@pytest.mark.parametrize("backend,version", [("numpy", None), ("opencl", None), ("numpy", 1)])
def test_surface_is_the_generated_column(backend, version, cl_device):
    """Far terrain meets the chunks of each version (old worlds keep version 1)."""
    gen = make_generator("overworld", SEED, None, backend, version)
    keys = [(cx, cy) for cx in range(-9, -6) for cy in range(2, 5)]   # ocean, beach, land
    col, x0, y0 = _columns(gen, keys)
    rng = np.random.default_rng(3)
    xy = np.stack([rng.integers(0, 48, 400), rng.integers(0, 48, 400)], -1)
    got = gen.surface(xy + (x0, y0))
    ix, iy = xy[:, 0], xy[:, 1]
    assert np.array_equal(got["height"], col["height"][ix, iy])
    assert np.array_equal(got["top"], col["top"][ix, iy])
    assert np.array_equal(got["water"], col["water"][ix, iy])
    assert (got["water"] >= 0).any() and (got["water"] < 0).any()


def test_numpy_equals_opencl(cl_device):
    a = make_generator("overworld", SEED, None, "numpy")
    b = make_generator("overworld", SEED, None, "opencl")
    rng = np.random.default_rng(5)
    xy = rng.integers(-40000, 40000, (3000, 2))
    sa, sb = a.surface(xy), b.surface(xy)
    for k in sa:
        assert sa[k].dtype == sb[k].dtype
        assert np.array_equal(sa[k], sb[k]), k


def test_tree_cover_matches_generated_crowns(cl_device):
    """The far canopy (treeRate x TREE_COVER on grass above the sea) covers about as
    much as the crowns of generated chunks do."""
    gen = make_generator("overworld", SEED, None, "opencl")
    keys = [(cx, cy) for cx in range(40, 50) for cy in range(-30, -20)]
    col, x0, y0 = _columns(gen, keys)
    X, Y = np.meshgrid(np.arange(160) + x0, np.arange(160) + y0, indexing="ij")
    got = gen.surface(np.stack([X.ravel(), Y.ravel()], -1))
    real, est = col["tree"].mean(), got["trees"].mean()
    assert real > 0.05
    assert abs(est - real) < 0.25 * real, (est, real, O.TREE_COVER)


def test_flat_surface():
    gen = make_generator("flat", 1, {"layers": [["stone", 10], ["water", 3]]})
    s = gen.surface(np.zeros((4, 2), int))
    assert list(s["height"]) == [9] * 4 and list(s["water"]) == [12] * 4
    assert gen.generate([(0, 0)])[0][0, 0, 9] == s["top"][0]


@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_surface_allocates_no_blocks(backend, cl_device):
    """A full surface batch (16384 one-column domains) allocates memory for columns,
    not for chunks: a (n, VOLUME) block array per batch was 2 GiB, which Blender's
    allocator zeroes page by page (surface ~20x slower in Blender than here, issue 28).
    NumPy reports its arrays to tracemalloc."""
    import tracemalloc
    gen = make_generator("overworld", SEED, None, backend)
    xy = np.stack(np.meshgrid(np.arange(128), np.arange(128)), -1).reshape(-1, 2)
    gen.surface(xy[:8])  # build the program outside the measurement
    tracemalloc.start()
    try:
        gen.surface(xy[:gen.surface_batch[gen.backend_used]])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 256 << 20, f"{peak / 2**20:.0f} MiB"


def test_numpy_single_columns_on_far_grids(cl_device, monkeypatch):
    """NumPy's surface computes each 2D pass only on the columns its readers reach
    (execute.Runner._at_points): on far tiles' grids (spacing 2: neighbours shared
    by two samples; 4; mountains, where the slope picks rock) it equals OpenCL's and
    the whole-halo domains it replaces."""
    from voxel_addon.generation import execute
    a = make_generator("overworld", SEED, None, "numpy")
    b = make_generator("overworld", SEED, None, "opencl")
    g = np.stack(np.meshgrid(np.arange(40), np.arange(40), indexing="ij"), -1).reshape(-1, 2)
    xy = np.concatenate([g * 2 + (-4000, 4000), g * 4 + (1000, -1000), g * 2 + (-3, -5)])
    assert len(xy) >= execute.SPLIT  # groundZ's neighbours apart from the centres
    sa, sb = a.surface(xy), b.surface(xy)
    sd = a.surface(xy[:1000])  # fewer columns: each unit's fields at once
    assert len(np.unique(sa["top"])) > 2  # rock on slopes among the rest
    monkeypatch.setattr(execute.Runner, "_stencils", lambda self, want: None)
    a._surf = None
    sc = a.surface(xy)
    for k in sa:
        assert np.array_equal(sa[k], sb[k]), k
        assert np.array_equal(sa[k], sc[k]), k
        assert np.array_equal(sd[k], sb[k][:1000]), k
