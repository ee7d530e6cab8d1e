"""Independent brute-force oracle for meshing tests: per voxel, per face, from Block objects."""
from __future__ import annotations

from collections import Counter

import numpy as np

from voxel_addon.core.blocks import BLOCKS, REGISTRY

STEP = ((-1, 0, 0), (1, 0, 0), (0, -1, 0), (0, 1, 0), (0, 0, -1), (0, 0, 1))


def exposed(blocks, border):
    """Counter of (face code, x, y, z) unit faces the rule exposes, window-local."""
    b = np.asarray(blocks)
    off = 1 if border == "context" else 0
    W, H = b.shape[0] - 2 * off, b.shape[1] - 2 * off

    def at(x, y, z):  # window-local coordinates; outside = air
        if not 0 <= z < 256:
            return 0
        X, Y = x + off, y + off
        if not (0 <= X < b.shape[0] and 0 <= Y < b.shape[1]):
            return 0
        if border == "air" and not (0 <= x < W and 0 <= y < H):
            return 0
        return int(b[X, Y, z])

    out = Counter()
    inner = b[off:off + W, off:off + H]
    for x, y, z in zip(*np.nonzero(inner)):
        a = BLOCKS[int(inner[x, y, z])]
        if a.shape == "x":
            out[(6, x, y, z)] += 1
            out[(7, x, y, z)] += 1
            continue
        for f, (dx, dy, dz) in enumerate(STEP):
            if a.shape == "hash" and f < 4:
                out[(8 + f, x, y, z)] += 1
                continue
            if a.shape == "hash" and "top" not in a.textures:
                continue
            nb_id = at(x + dx, y + dy, z + dz)
            nb = BLOCKS[nb_id]
            if nb.shape == "cube" and nb.render == "opaque":
                continue
            if a.shape == "cube" and a.render == "blend" and nb_id == inner[x, y, z]:
                continue
            if a.shape == "hash" and nb_id == inner[x, y, z]:
                continue
            out[(f, x, y, z)] += 1
    return out


def covered_by_quads(q):
    """Counter of unit faces the quad list covers (expanding w×h)."""
    out = Counter()
    t = {0: (1, 2), 1: (0, 2), 2: (0, 1)}
    for r in q:
        f = int(r["face"])
        if f >= 6:
            assert r["w"] == r["h"] == 1
            out[(f, int(r["x"]), int(r["y"]), int(r["z"]))] += 1
            continue
        t1, t2 = t[f // 2]
        for i in range(int(r["w"])):
            for j in range(int(r["h"])):
                p = [int(r["x"]), int(r["y"]), int(r["z"])]
                p[t1] += i
                p[t2] += j
                out[(f, *p)] += 1
    return out


def covered_by_triangles(mesh):
    """Counter of unit cube faces covered by a Mesh's triangles, read from positions only;
    also asserts each quad's two triangles tile its rectangle with the right winding."""
    out = Counter()
    p = mesh.positions.reshape(-1, 4, 3)
    n = mesh.normals.reshape(-1, 4, 3)[:, 0]
    tri = mesh.triangles()
    P = mesh.positions[tri]
    cr = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    area = np.linalg.norm(cr, axis=1) / 2
    facing = (cr * np.repeat(n, 2, axis=0)).sum(1)
    assert (facing > 0).all(), "a triangle faces away from its normal"
    for k in range(len(p)):
        f = int(mesh.face[k])
        lo, hi = p[k].min(0), p[k].max(0)
        if f >= 6:
            cell = np.floor(p[k].mean(0)).astype(int)
            out[(f, *cell)] += 1
            continue
        a = f // 2
        ext = np.delete(hi - lo, a)
        assert abs(area[2 * k] + area[2 * k + 1] - ext[0] * ext[1]) < 1e-4
        base = lo.astype(int)
        base[a] -= f % 2          # +face plane sits at voxel + 1
        rng = [range(int(lo[i]), int(hi[i])) if i != a else [base[a]] for i in range(3)]
        for x in rng[0]:
            for y in rng[1]:
                for z in rng[2]:
                    out[(f, x, y, z)] += 1
    return out


def random_window(seed, shape=(10, 9, 256), band=(100, 112), names=None):
    names = names or ["air", "air", "stone", "grass", "leaves", "glass", "water", "water",
                      "flowers", "wheat", "cactus", "log"]
    ids = [REGISTRY.id(n) for n in names]
    rng = np.random.default_rng(seed)
    b = np.zeros(shape, np.uint16, order="F")
    b[:, :, :band[0]] = REGISTRY.id("stone")
    b[:, :, band[0]:band[1]] = rng.choice(ids, size=(shape[0], shape[1], band[1] - band[0]))
    b[:, :, 0] = REGISTRY.id("water")   # the world's floor and ceiling are air
    b[:, :, 255] = REGISTRY.id("glass")
    return b
