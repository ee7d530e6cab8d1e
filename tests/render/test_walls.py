"""render/walls.edges_many (a whole view's border columns in a few NumPy calls) against a
brute-force count over each quad and column, on real chunk meshes and random quads."""
from __future__ import annotations

import numpy as np

from voxel_addon.render import walls


def _brute(q) -> np.ndarray:
    """Per quad and border column: the highest top face of an opaque cube; of equal
    heights the quad first in the mesh."""
    out = np.zeros((12, 16), np.uint16)
    best = {}
    for i in range(len(q)):
        b = int(q["block"][i])
        if q["face"][i] != walls.TOP or not walls._SOLID[min(b, len(walls._SOLID) - 1)]:
            continue
        x, y, w, h = (int(q[k][i]) for k in ("x", "y", "w", "h"))
        top = int(q["z"][i]) + 1
        for row, on, lo, n in ((0, x == 0, y, h), (1, x + w == 16, y, h),
                               (2, y == 0, x, w), (3, y + h == 16, x, w)):
            for col in range(lo, lo + n) if on else ():
                if top > best.get((row, col), (0, 0))[0]:
                    best[row, col] = (top, b)
    for (row, col), (top, b) in best.items():
        out[row, col], out[4 + row, col], out[8 + row, col] = top, walls._SIDE[b], walls._FILL[b]
    return out


class _Mesh:
    def __init__(self, quads):
        self.quads = quads


def _random(rng, like, n):
    q = np.zeros(n, like.dtype)
    q["x"], q["y"] = rng.integers(0, 16, n), rng.integers(0, 16, n)
    q["w"] = rng.integers(1, 17 - q["x"])
    q["h"] = rng.integers(1, 17 - q["y"])
    q["z"] = rng.integers(0, 8, n)  # few heights: many ties
    q["face"] = rng.choice([walls.TOP, 0, 1], n, p=[0.7, 0.15, 0.15])
    q["block"] = rng.choice(np.unique(like["block"]), n)
    return q


def test_edges_many_matches_a_brute_force_count():
    from voxel_addon.meshing import build_chunk, scenes
    blocks = scenes.blocks("landscape")
    real = [build_chunk(blocks[16 * i:16 * i + 18, 16 * j:16 * j + 18], backend=None)
            for i in range(2) for j in range(2)]
    rng = np.random.default_rng(3)
    like = real[0].quads
    meshes = real + [_Mesh(_random(rng, like, n)) for n in (1, 7, 60, 300)]
    meshes += [_Mesh(like[:0]), _Mesh(None), _Mesh(like[::-3])]  # empty, none, strided
    got = walls.edges_many(meshes)
    assert got.shape == (len(meshes), 12, 16)
    for g, m in zip(got, meshes):
        want = _brute(m.quads) if m.quads is not None else np.zeros((12, 16), np.uint16)
        assert (g == want).all()
    assert got[:4, :4].any(), "the real chunks have border columns"
    assert (walls.edges(meshes[5]) == got[5]).all()
