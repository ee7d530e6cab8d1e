"""Exact coverage, OpenCL == NumPy, aggregation quality and input checks for meshing."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import meshing
from voxel_addon.core.blocks import REGISTRY
from voxel_addon.core.errors import VoxelError
from voxel_addon.meshing import scenes

from .helpers import covered_by_quads, covered_by_triangles, exposed, random_window


@pytest.fixture(scope="module")
def landscape():
    return scenes.blocks("landscape")


def _cases(landscape):
    yield "random-context", random_window(1), "context"
    yield "random-air", random_window(2, shape=(7, 6, 256)), "air"
    yield "landscape-chunk", np.asfortranarray(landscape[16:34, 0:18]), "context"
    yield "landscape-air", np.asfortranarray(landscape[20:44, 3:27]), "air"


@pytest.mark.parametrize("method", meshing.METHODS)
def test_exact_coverage(method, landscape):
    for name, b, border in _cases(landscape):
        want = exposed(b, border)
        q = meshing.quads(b, border=border, method=method)
        got = covered_by_quads(q)
        assert got == want, f"{name}: quads differ from the brute-force faces"
        assert max(got.values()) == 1
        # the quad's block is the block of every voxel it covers
        off = 1 if border == "context" else 0
        ids = b[q["x"] + off, q["y"] + off, q["z"]]
        assert (ids == q["block"]).all()
        side = np.where(q["face"] < 6, q["face"], np.where(q["face"] >= 8, q["face"] - 8, 0))
        assert (q["layer"] == REGISTRY.face_texture[q["block"], side]).all()
        assert covered_by_triangles(meshing.to_mesh(q)) == want, f"{name}: triangles"


def test_merged_quads_hold_one_block(landscape):
    b = np.asfortranarray(landscape[16:34, 0:18])
    q = meshing.quads(b, method="greedy")
    t = {0: (1, 2), 1: (0, 2), 2: (0, 1)}
    for r in q[(q["face"] < 6) & ((q["w"] > 1) | (q["h"] > 1))]:
        t1, t2 = t[int(r["face"]) // 2]
        sl = [slice(int(r[c]) + 1, int(r[c]) + 2) if c != "z" else slice(int(r[c]), int(r[c]) + 1)
              for c in "xyz"]
        for ax, n in ((t1, int(r["w"])), (t2, int(r["h"]))):
            sl[ax] = slice(sl[ax].start, sl[ax].start + n)
        assert (b[tuple(sl)] == r["block"]).all()


def test_tiled_methods_stay_in_8x8(landscape):
    b = np.asfortranarray(landscape[16:34, 16:34])
    for m in ("lines", "squares", "squares_ext"):
        q = meshing.quads(b, method=m)
        assert q["w"].max() <= 8 and q["h"].max() <= 8


def test_split_keeps_regions_apart(landscape):
    b = np.asfortranarray(landscape[0:18, 0:18])
    q = meshing.quads(b, method="greedy", split=16)
    cube = q[q["face"] < 4]      # side faces extend along z (their h)
    assert ((cube["z"] // 16) == ((cube["z"] + cube["h"] - 1) // 16)).all()
    assert covered_by_quads(q) == exposed(b, "context")


@pytest.mark.parametrize("method", meshing.METHODS)
def test_opencl_equals_numpy(method, greedy_path, landscape):
    cases = [random_window(5), random_window(6, band=(0, 256)),
             np.asfortranarray(landscape[16:34, 16:34]), scenes.blocks("cave")[0:18, 16:34]]
    for b in cases:
        a = meshing.quads(b, method=method)
        c = meshing.quads(b, method=method, backend="opencl")
        assert a.dtype == c.dtype and np.array_equal(a, c)
    b = random_window(7, shape=(21, 13, 256))
    assert np.array_equal(meshing.quads(b, border="air", method=method),
                          meshing.quads(b, border="air", method=method, backend="opencl"))


def test_greedy_landscape_ratio(landscape):
    opaque = REGISTRY.render[np.arange(len(REGISTRY))] == 1
    naive = meshing.quads(landscape, method="none")
    greedy = meshing.quads(landscape, method="greedy")
    n = opaque[naive["block"]].sum()
    g = opaque[greedy["block"]].sum()
    assert n > 10_000
    assert g <= 0.40 * n, f"greedy keeps {g / n:.0%} of naive opaque triangles"
    # the thesis's ordering of the methods holds on the same scene
    counts = {m: len(meshing.quads(landscape, method=m)) for m in meshing.METHODS}
    assert counts["greedy"] < counts["lines"] < counts["none"]
    assert counts["squares_ext"] < counts["squares"] < counts["none"]


def test_bad_input_is_a_voxel_error():
    b = np.zeros((18, 18, 256), np.uint16)
    with pytest.raises(VoxelError, match="method"):
        meshing.quads(b, method="fancy")
    with pytest.raises(VoxelError, match="border"):
        meshing.quads(b, border="wrap")
    with pytest.raises(VoxelError, match="256"):
        meshing.quads(np.zeros((18, 18, 100), np.uint16))
    with pytest.raises(VoxelError, match="region"):
        meshing.build_chunk(b, region_h=48)
    assert len(meshing.quads(b)) == 0
