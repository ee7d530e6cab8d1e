"""Coloured voxels: `color` faces of different colours never share a quad, every unit
face is still covered exactly once (the brute-force oracle), each quad's colour is the
data of every voxel under it, and NumPy and OpenCL give the same meshes."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.core.blocks import REGISTRY
from voxel_addon.meshing import build_chunks
from voxel_addon.meshing.run import quads

from .helpers import covered_by_quads, exposed

COLOR = REGISTRY.id("color")


def scene(seed, w=34, h=18):
    rng = np.random.default_rng(seed)
    b = np.zeros((w, h, 256), np.uint16, order="F")
    d = np.zeros_like(b)
    b[:, :, :40] = REGISTRY.id("stone")
    box = (slice(2, w - 3), slice(2, h - 2), slice(40, 60))
    b[box] = np.where(rng.random(b[box].shape) < 0.7, COLOR, 0)
    b[5, 5, 45] = REGISTRY.id("glass")
    # colours in blocks (so some faces do merge) plus noise
    d[box] = (np.arange(w)[:, None, None] // 4 % 3 + 1)[box[0]] \
        + (rng.random(b[box].shape) < 0.1) * 5
    d[b != COLOR] = 0
    return b, d


def cell_colors(q, data, off=1):
    t = {0: (1, 2), 1: (0, 2), 2: (0, 1)}
    for r in q[q["block"] == COLOR]:
        f = int(r["face"])
        t1, t2 = t[f // 2]
        for i in range(int(r["w"])):
            for j in range(int(r["h"])):
                p = [int(r["x"]) + off, int(r["y"]) + off, int(r["z"])]
                p[t1] += i
                p[t2] += j
                assert data[tuple(p)] == r["color"], (r, p)


def test_quads_keep_colours_apart():
    b, d = scene(1)
    q = quads(b, data=d)
    assert covered_by_quads(q) == exposed(b, "context")
    cell_colors(q, d)
    plain = quads(b)
    assert len(q) > len(plain)                     # split where colours differ
    merged = q[(q["block"] == COLOR) & (q["w"] > 1)]
    assert len(merged)                              # and merged where they agree
    assert np.array_equal(np.sort(q[q["block"] != COLOR], order=["face", "z", "y", "x"]),
                          np.sort(plain[plain["block"] != COLOR], order=["face", "z", "y", "x"]))


@pytest.mark.parametrize("backend", ["numpy", "opencl"])
def test_chunk_meshes_carry_colours(backend, request):
    if backend == "opencl":
        request.getfixturevalue("cl_device")
    b, d = scene(2)
    out = build_chunks(b, (0, 0), backend=backend, data=d)
    ref = build_chunks(b, (0, 0), backend="numpy", data=d)
    for k, m in out.items():
        assert np.array_equal(m.vertices, ref[k].vertices) and np.array_equal(m.quads, ref[k].quads)
        assert m.colors is not None and len(m.colors) == len(m.vertices)
        assert np.array_equal(m.colors, np.repeat(m.quads["color"], 4))
        # tile-local quads of chunk k: colours match the data under them
        sub = d[16 * k[0]:16 * k[0] + 18, 16 * k[1]:16 * k[1] + 18]
        cell_colors(m.quads, sub)
    assert build_chunks(b, (0, 0))[(0, 0)].colors is None   # no data: as before


def test_spliced_region_keeps_colours():
    """An edit's remesh of some render regions spliced into the old mesh carries the
    per-vertex colours as a full build does (the colours live beside the packed
    vertices, so splice must cut them the same way)."""
    from voxel_addon.meshing import splice
    b, d = scene(3, w=18, h=18)
    old = build_chunks(b, (0, 0), data=d)[(0, 0)]
    b[8, 8, 50], d[8, 8, 50] = COLOR, 7         # a new colour in region 0
    part = build_chunks(b, (0, 0), data=d, regions=(0, 1))[(0, 0)]
    full = build_chunks(b, (0, 0), data=d)[(0, 0)]
    s = splice(old, part, 0, 1)
    assert np.array_equal(s.vertices, full.vertices) and np.array_equal(s.quads, full.quads)
    assert s.colors is not None and np.array_equal(s.colors, full.colors)
    assert 7 in s.colors
