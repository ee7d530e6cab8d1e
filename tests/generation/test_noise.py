"""Noise (F4): NumPy and OpenCL agree (bit for bit, which is stronger than the
tolerance the spec asks for), and the noise has the properties it claims."""
import numpy as np
import pytest

from voxel_addon.generation import noise as N

KINDS = [("perlin2", 0, 0), ("perlin3", 1, 0), ("voronoi2", 2, 0), ("voronoi2_l4", 2, 1),
         ("voronoi3", 3, 0), ("voronoi3_l4", 3, 1)]


def _points(n=60000, seed=3):
    rng = np.random.default_rng(seed)
    p = (rng.standard_normal((n, 3)) * 200).astype(np.float32)
    p[:500] = np.round(p[:500])          # lattice points and cell borders
    p[500:1000] = np.round(p[500:1000] * 4) / 4
    p[1000:1200] *= 1e-4                 # near the origin, tiny fractions
    p[1200:1210] = -0.0                  # signed zeros must agree too
    return p


def _numpy(kind, metric, pts, perm, s):
    x, y, z = pts.T
    if kind == 0:
        return N.perlin2(x, y, perm, s)
    if kind == 1:
        return N.perlin3(x, y, z, perm, s)
    v = N.voronoi2(x, y, s, metric) if kind == 2 else N.voronoi3(x, y, z, s, metric)
    return np.stack(v, 1).ravel()


@pytest.mark.parametrize("name,kind,metric", KINDS)
def test_numpy_equals_opencl(cl_device, name, kind, metric):
    import pyopencl as cl
    from voxel_addon import opencl
    from voxel_addon.generation.clscalar import OPTIONS
    ctx, q, _ = cl_device
    prg = opencl.program("noise.cl", OPTIONS)
    pts = _points()
    n = len(pts)
    for seed in (0, 987654321):
        s32 = N.seed32(seed)
        perm, s = N.perm_table(s32), N.inst(s32, 5)
        mf = cl.mem_flags
        bp = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=pts)
        bperm = cl.Buffer(ctx, mf.READ_ONLY | mf.COPY_HOST_PTR, hostbuf=perm)
        out = np.zeros(3 * n, np.float32)
        bo = cl.Buffer(ctx, mf.WRITE_ONLY, out.nbytes)
        cl.Kernel(prg, "sample")(q, (n,), None, bp, bo, bperm, np.uint32(s), np.int32(kind),
                                 np.int32(metric), np.int32(n))
        cl.enqueue_copy(q, out, bo)
        ref = _numpy(kind, metric, pts, perm, s)
        got = out[:ref.size]
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-6)
        assert np.array_equal(got.view(np.uint32), ref.view(np.uint32)), "not bit-identical"


def test_perlin_properties():
    s32 = N.seed32(42)
    perm, s = N.perm_table(s32), N.inst(s32, 1)
    assert sorted(perm[:256]) == list(range(256)) and np.array_equal(perm[:256], perm[256:])
    assert not np.array_equal(perm, N.perm_table(N.seed32(43)))
    g = np.arange(-20, 20, dtype=np.float32)
    # zero at lattice points; bounded; continuous (small steps give small changes)
    assert np.all(N.perlin3(g, g[::-1], g * 0 + 3, perm, s) == 0)
    assert np.all(N.perlin2(g, g * 0 - 7, perm, s) == 0)
    x = np.linspace(-50, 50, 200001, dtype=np.float32)
    v3 = N.perlin3(x, x * 0.37, x * -0.61, perm, s)
    v2 = N.perlin2(x, x * 0.37, perm, s)
    assert np.abs(v3).max() <= 1.05 and np.abs(v2).max() <= 0.75
    assert np.abs(np.diff(v3)).max() < 0.02 and np.abs(np.diff(v2)).max() < 0.02
    assert v3.std() > 0.15 and abs(v3.mean()) < 0.05
    # instances differ
    assert not np.allclose(v3, N.perlin3(x, x * 0.37, x * -0.61, perm, N.inst(s32, 2)))


def test_octaves_eq_2_10():
    s32 = N.seed32(1)
    perm = N.perm_table(s32)
    x = np.linspace(0, 9, 1000, dtype=np.float32)
    y = x * 0.5
    got = N.octaves(N.perlin2, (x, y), perm, s32, 10, n=3, lacunarity=2.0, gain=0.5)
    want = sum(N.perlin2(x * np.float32(2 ** o), y * np.float32(2 ** o), perm, N.inst(s32, 10 + o))
               * np.float32(0.5 ** o) for o in range(3))
    np.testing.assert_allclose(got, want, atol=1e-6)


@pytest.mark.parametrize("metric", [0, 1])
def test_voronoi_against_brute_force(metric):
    """F1/F2/value equal a brute-force search over all feature points around."""
    s = N.inst(N.seed32(9), 3)
    rng = np.random.default_rng(0)
    pts = rng.uniform(-30, 30, (400, 2)).astype(np.float32)
    f1, f2, val = N.voronoi2(pts[:, 0], pts[:, 1], s, metric)
    cells = np.array([(i, j) for i in range(-33, 33) for j in range(-33, 33)], np.int32)
    h = N.hash2(cells[:, 0], cells[:, 1], s)
    fp = np.stack([cells[:, 0] + N.unit(h), cells[:, 1] + N.unit(N.nxt(h))], 1)
    fv = N.unit(N.nxt(N.nxt(h)))
    for k, p in enumerate(pts):
        d = np.abs(fp - p).astype(np.float64)
        d = (d[:, 0] ** 4 + d[:, 1] ** 4) ** 0.25 if metric else np.hypot(d[:, 0], d[:, 1])
        o = np.argsort(d)
        assert abs(f1[k] - d[o[0]]) < 1e-5 and val[k] == fv[o[0]]
        # a 3x3 search may miss the true F2 in rare layouts; it never undershoots
        assert f2[k] >= d[o[1]] - 1e-5
    assert np.mean(np.abs(f2 - np.array([np.sort(np.hypot(*(fp - p).T) if not metric else
                  (np.abs(fp - p)[:, 0] ** 4 + np.abs(fp - p)[:, 1] ** 4) ** 0.25)[1]
                  for p in pts])) < 1e-5) > 0.97
