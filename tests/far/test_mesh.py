"""Far meshes: the vertices are the samples (heights, water, canopy), holes stay
holes, surfaces face up, and between tiles of different levels the skirts close
every gap (checked on a real view's tiles of the real generator)."""
import numpy as np
import pytest

from voxel_addon.far import grid, mesh
from voxel_addon.far.tiles import empty
from voxel_addon.generation import make_generator

from .skyline import tile_of

T = grid.TILE


def decode(m):
    w0, w1 = m.vertices[:, 0], m.vertices[:, 1]
    kx, ky = (w0 & 63).astype(int), ((w0 >> 6) & 63).astype(int)
    z = ((w0 >> 12) & 8191) / 8.0
    kind = (w0 >> 25) & 3
    x = m.origin[0] + kx * m.spacing + 0.5
    y = m.origin[1] + ky * m.spacing + 0.5
    nx = ((w1 & 255).astype(np.uint8).view(np.int8)) / 127.0
    ny = (((w1 >> 8) & 255).astype(np.uint8).view(np.int8)) / 127.0
    up = kind == mesh.WATER  # (its word 1 holds its floor's colour and depth instead)
    nx, ny = np.where(up, 0.0, nx), np.where(up, 0.0, ny)
    return np.stack([x, y, z], -1), kx, ky, kind, nx, ny




def test_vertices_are_the_samples():
    a = empty()
    rng = np.random.default_rng(1)
    a["height"][:] = rng.integers(40, 90, a["height"].shape)
    a["top"][:] = 3
    a["trees"][5, 7] = 255
    a["water"][10:14, 10:14] = 95
    a["height"][20, 20] = -1   # a hole: the 4 cells around it go
    m = mesh.build((2, 3, -1), a)
    p, kx, ky, kind, nx, ny = decode(m)
    g = kind == mesh.GROUND
    assert g.sum() == (T + 1) ** 2
    want = a["height"][kx[g] + 1, ky[g] + 1] + 1.0 + a["trees"][kx[g] + 1, ky[g] + 1] / 255 * mesh.CANOPY
    ok = a["height"][kx[g] + 1, ky[g] + 1] >= 0
    assert np.allclose(p[g, 2][ok], want[ok], atol=1 / 16)
    w = kind == mesh.WATER
    assert np.allclose(p[w, 2], 95 + mesh.WATER_TOP)
    assert (nx ** 2 + ny ** 2 <= 1.001).all()
    # cells: all but the 4 around the hole; skirts: 4 edges x T quads
    assert len(m.ground) // 3 == 2 * (T * T - 4) + 2 * 4 * T
    # water cells: those with water at a corner (the 4x4 wet samples: 5x5 cells)
    assert len(m.water) // 3 == 2 * 5 * 5
    assert m.vertices.dtype == np.uint32 and m.vertices.shape[1] * 4 == mesh.BYTES_PER_VERTEX
    # next to the hole the coarse surface is undefined: no morph
    zc = (m.vertices[:, 2] & 8191) / 8.0
    near = g & (np.abs(kx - 19) <= 1) & (np.abs(ky - 19) <= 1)
    assert np.allclose(zc[near], p[near, 2])


def test_surfaces_face_up(cl_device):
    gen = make_generator("overworld", 7, None, "opencl")
    m = mesh.build((2, 7, -8), tile_of(gen, (2, 7, -8)))
    p = decode(m)[0]
    for idx in (m.ground, m.water):
        t = p[idx.reshape(-1, 3)]
        n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        kinds = decode(m)[3][idx.reshape(-1, 3)]
        top = (kinds != mesh.SKIRT).all(1)
        assert (n[top, 2] > 0).all()


def _edge(m, side):
    """(positions along the edge, top z, skirt bottom z) of a mesh's edge, sorted."""
    p, kx, ky, kind, _, _ = decode(m)
    k = {"x0": kx == 0, "x1": kx == T, "y0": ky == 0, "y1": ky == T}[side]
    along = p[:, 1] if side[0] == "x" else p[:, 0]
    top = k & (kind == mesh.GROUND)
    bot = k & (kind == mesh.SKIRT)
    o1 = np.argsort(along[top])
    # corners have a skirt twin on each of their two edges (the same z)
    pos, o2 = np.unique(along[bot], return_index=True)
    assert np.array_equal(along[top][o1], pos)
    return along[top][o1], p[top, 2][o1], p[bot, 2][o2]


def test_no_cracks_between_levels(cl_device):
    gen = make_generator("overworld", 7, None, "opencl")
    sel = [k for k, _ in grid.select(960.0, -928.0, far=48, near=2)]
    meshes = {k: mesh.build(k, tile_of(gen, k)) for k in sel}
    pairs = 0
    for a in sel:
        ra = grid.rect(a)
        for b in sel:
            rb = grid.rect(b)
            if b[0] <= a[0]:
                continue  # a is the finer one
            for side, other, same in (("x1", "x0", ra[2] == rb[0]), ("x0", "x1", ra[0] == rb[2]),
                                      ("y1", "y0", ra[3] == rb[1]), ("y0", "y1", ra[1] == rb[3])):
                if not same:
                    continue
                lo, hi = (1, 3) if side[0] == "x" else (0, 2)
                lo = max(ra[lo], rb[lo])
                hi = min(ra[hi], rb[hi])
                if lo >= hi:
                    continue
                fa, ta, sa = _edge(meshes[a], side)
                fb, tb, sb = _edge(meshes[b], other)
                at = (fa >= lo) & (fa <= hi + 0.5)
                pos = fa[at]
                top_a, skirt_a = ta[at], sa[at]
                top_b, skirt_b = np.interp(pos, fb, tb), np.interp(pos, fb, sb)
                # the higher edge's skirt reaches below the lower edge everywhere
                closed = np.where(top_a >= top_b, skirt_a <= top_b + 1e-3,
                                  skirt_b <= top_a + 1e-3)
                assert closed.all(), (a, b, side)
                pairs += 1
    assert pairs > 10


def _surface_at(m, pts):
    """z of mesh m's ground surface (unmorphed, no skirts) at points (n, 2)."""
    p = decode(m)[0]
    kind = decode(m)[3]
    t = m.ground.reshape(-1, 3)
    t = t[(kind[t] != mesh.SKIRT).all(1)]
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    out = np.full(len(pts), np.nan)
    for i, q in enumerate(pts):
        v0, v1, v2 = b[:, :2] - a[:, :2], c[:, :2] - a[:, :2], q - a[:, :2]
        den = v0[:, 0] * v1[:, 1] - v1[:, 0] * v0[:, 1]
        u = (v2[:, 0] * v1[:, 1] - v1[:, 0] * v2[:, 1]) / den
        v = (v0[:, 0] * v2[:, 1] - v2[:, 0] * v0[:, 1]) / den
        inside = (u >= -1e-9) & (v >= -1e-9) & (u + v <= 1 + 1e-9)
        j = np.flatnonzero(inside)[0]
        out[i] = a[j, 2] + u[j] * (b[j, 2] - a[j, 2]) + v[j] * (c[j, 2] - a[j, 2])
    return out


def test_a_new_level_starts_as_its_parent(cl_device):
    """Walking toward a tile until it splits: at the switch its children, morphed as
    drawn, are its surface exactly (no pop), and they get their own shape nearer."""
    from .skyline import positions
    gen = make_generator("overworld", 7, None, "opencl")
    parent = (3, 3, -4)          # 256-block tile on the slopes at (768..1024, -1024..-768)
    r = grid.rect(parent)
    switch = grid.DETAIL * grid.spacing(3)
    y = (r[1] + r[3]) / 2
    before = (r[0] - switch - 0.5, y)   # not split yet
    after = (r[0] - switch + 0.5, y)    # split: the 4 children drawn
    assert grid._dist(*before, r) >= switch > grid._dist(*after, r)
    pm = mesh.build(parent, tile_of(gen, parent))
    worst = 0.0
    for i in (0, 1):
        for j in (0, 1):
            child = (2, 2 * parent[1] + i, 2 * parent[2] + j)
            cm = mesh.build(child, tile_of(gen, child))
            kind = decode(cm)[3]
            g = kind == mesh.GROUND
            drawn = positions(cm, after)[g]
            inside = (drawn[:, 0] < r[2]) & (drawn[:, 1] < r[3])  # the last row is the next tile's
            want = _surface_at(pm, drawn[inside, :2])
            worst = max(worst, np.abs(drawn[inside, 2] - want).max())
            own = positions(cm)[g]
            near = positions(cm, (r[0] - 10.0, y))[g]
            assert np.abs(own[:, 2] - drawn[:, 2]).max() > 1.0   # the level has detail to add
            assert np.allclose(near[:, 2], own[:, 2], atol=0.13) or \
                np.abs(near[:, 2] - own[:, 2]).mean() < np.abs(drawn[:, 2] - own[:, 2]).mean()
    assert worst <= 1 / 8 + 1e-6, worst   # the vertex's 1/8-block z quantum

