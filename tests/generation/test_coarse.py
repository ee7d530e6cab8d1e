"""lang.coarse (issue 29): a function of x, y, z sampled on a lattice and trilinearly
interpolated. Oracle: the same noise evaluated by noise.py at the lattice corners of
every voxel and interpolated here in float32, op for op; both backends must give its
bits, in the 3D pass (lattice units) and in a column output (the expanded form)."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.generation import lang as L
from voxel_addon.generation import lower
from voxel_addon.generation import noise as N
from voxel_addon.generation.passgen import PassGenerator

F = np.float32


class Coarse(PassGenerator):
    name = "coarse-test"
    cell = (4, 4, 8)

    def program(self):
        g = L.Program()
        with g.pass2d() as p:
            p.out("h", L.ifloor(L.perlin2(p.x / 23, p.y / 23, salt=1) * 30 + 90))
        with g.pass3d() as p:
            p.top(p.read("h"))
            c = L.coarse(p, lambda x, y, z: L.perlin3(x / 13, y / 11, z / 9, salt=2), self.cell)
            p.block(L.select(c > 0.1, 1, L.select(c > -0.1, 2, 3)))
            p.column("cv", c, at=p.read("h") - 5)
        return g


def _oracle(g, key):
    """(16, 16, 256) interpolated values of chunk key, float32."""
    cx, cy, cz = g.cell
    x = (key[0] * 16 + np.arange(16))[:, None, None]
    y = (key[1] * 16 + np.arange(16))[None, :, None]
    z = np.arange(256)[None, None, :]

    def f(a, b, c):
        a, b, c = np.broadcast_arrays(a, b, c)
        return N.perlin3(a.astype(F) / F(13), b.astype(F) / F(11), c.astype(F) / F(9),
                         g.perm, N.inst(g.seed32, 2))

    def lerp(t, a, b):
        return a + t * (b - a)
    o = [v - v % s for v, s in ((x, cx), (y, cy), (z, cz))]
    t = [(v % s).astype(F) * F(1.0 / s) for v, s in ((x, cx), (y, cy), (z, cz))]
    lv = []
    for k in (0, 1):
        c = {(i, j): f(o[0] + i * cx, o[1] + j * cy, o[2] + k * cz) for i in (0, 1) for j in (0, 1)}
        lv.append(lerp(t[1], lerp(t[0], c[0, 0], c[1, 0]), lerp(t[0], c[0, 1], c[1, 1])))
    return lerp(t[2], lv[0], lv[1])


@pytest.mark.parametrize("cell", [(4, 4, 8), (2, 8, 16)])
@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_coarse_is_the_interpolated_lattice(cl_device, backend, cell):
    keys = [(0, 0), (-1, -1), (5, -7)]
    g = Coarse(3, None, backend)
    g.cell = cell
    g.units = lower.lower(g.program())
    assert {u.kind for u in g.units} >= {"g3", "gc"}
    got = g.generate(keys)
    cols = g.columns(keys, ["h", "cv"])
    for n, k in enumerate(keys):
        v = _oracle(g, k)
        h = cols["h"][n][..., None]
        want = np.where(v > F(0.1), 1, np.where(v > F(-0.1), 2, 3))
        want = np.where(np.arange(256) <= h, want, 0)
        assert np.array_equal(got[n], want), f"chunk {k}: {(got[n] != want).sum()} voxels differ"
        at = (cols["h"][n] - 5)[..., None]
        assert np.array_equal(cols["cv"][n], np.take_along_axis(v, at, 2)[..., 0])


def test_coarse_samples_coordinates_only():
    g = L.Program()
    with g.pass2d() as p:
        p.out("h", 5)
    with g.pass3d() as p:
        p.block(L.select(L.coarse(p, lambda x, y, z: p.read("h") + z, (4, 4, 8)) > 3, 1, 0))
    with pytest.raises(ValueError, match="coarse"):
        lower.lower(g)
    with pytest.raises(ValueError):
        with L.Program().pass3d() as p:
            L.coarse(p, lambda x, y, z: x, (3, 4, 8))
