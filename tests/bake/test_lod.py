"""Large bakes with levels of detail (issue 30 e): the near square in full, the far
levels beyond as one object each, meeting without overlap or gap; the .glb with both
is validator-clean."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon.bake import lod

X, Y, NEAR, FAR = 5.0, 7.0, 1, 8


@pytest.fixture(scope="module")
def baked(tmp_path_factory):
    from voxel_addon.world import World
    path = tmp_path_factory.mktemp("lod") / "w.sqlite"
    with World.create(path, seed=4, generator="overworld", loader=False) as w:
        return lod.bake_lod(w, X, Y, NEAR, FAR, detail=8, light="vertex")


def covered(fp, pts):
    """Which xy points lie under some ground triangle of FP."""
    tri = fp.positions[fp.ground][:, :, :2]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    out = []
    for p in pts:
        def side(u, v):
            return (v[:, 0] - u[:, 0]) * (p[1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (p[0] - u[:, 0])
        s1, s2, s3 = side(a, b), side(b, c), side(c, a)
        inside = ((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0))
        out.append(bool((inside & (np.abs(s1) + np.abs(s2) + np.abs(s3) > 0)).any()))
    return np.array(out)


def test_near_in_full_far_levels_around_it(baked):
    bk, far = baked
    x0, y0, x1, y1 = lod.near_box(X, Y, NEAR)
    assert bk.region == (x0, y0, x1, y1) == (-16, -16, 32, 32)
    assert len({p.level for p in far}) == len(far) >= 2
    assert [p.name for p in far] == [f"far_level{p.level}" for p in far]
    for p in far:
        c = p.positions[p.ground].mean(axis=1)
        assert not ((c[:, 0] > x0) & (c[:, 0] < x1) & (c[:, 1] > y0) & (c[:, 1] < y1)).any()
        assert p.normals[:, 2].min() >= 0 and 0 <= p.albedo.min() and p.albedo.max() <= 1
        # a vertex sits on its sample column's centre: columns every 2^level blocks
        assert not np.any((p.positions[:, :2] - 0.5) % 2 ** p.level)
    # no gap: points just outside the near square, and out in the ring, lie under
    # some level's ground
    ring = [(x0 - 1.3, 3.1), (x1 + 1.2, 10.4), (7.7, y0 - 0.6), (-3.3, y1 + 2.1),
            (x1 + 60.5, y1 + 50.2), (x0 - 90.1, 0.3)]
    hit = np.zeros(len(ring), bool)
    for p in far:
        hit |= covered(p, ring)
    assert hit.all(), hit
    # the ring reaches FAR chunks out (whole tiles: a coarse one may reach beyond)
    allp = np.concatenate([p.positions for p in far])
    assert allp[:, 0].min() <= 16 * -FAR + 1 and allp[:, 0].max() >= 16 * (FAR + 1) - 1
    assert allp[:, 1].min() <= 16 * -FAR + 1 and allp[:, 1].max() >= 16 * (FAR + 1) - 1


def test_bad_distances_are_one_line_errors(tmp_path):
    from voxel_addon.core.errors import VoxelError
    from voxel_addon.world import World
    with World.create(tmp_path / "w.sqlite", seed=0, generator="flat", loader=False) as w:
        with pytest.raises(VoxelError, match="near < far"):
            lod.bake_lod(w, 0, 0, 4, 2)


def test_the_lod_glb_is_valid(bpy, baked, tmp_path, validate):
    from voxel_addon.bake import glb
    from voxel_addon.blender import bake as BB
    bk, far = baked
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="gltf") + BB.far_objects(far, style="gltf")
    out = tmp_path / "lod.glb"
    BB.export_glb(out, objs)
    report = validate(out)
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    doc, _ = glb.read(out)
    names = {n["name"] for n in doc["nodes"]}
    assert {p.name for p in far} <= names
    # in Blender's own style too: one object per level, water on its own material
    obs = BB.far_objects(far, style="blender")
    assert len(obs) == len(far) and all(len(o.data.polygons) == p.triangles
                                        for o, p in zip(obs, far))


def test_cli_lod(tmp_path, capsys):
    from voxel_addon.cli import main
    from voxel_addon.bake import glb
    from voxel_addon.world import World
    w = tmp_path / "w.sqlite"
    with World.create(w, seed=4, generator="flat", loader=False):
        pass
    out = tmp_path / "o.glb"
    assert main(["bake", "--world", str(w), "--out", str(out), "--lod", "0", "0", "3", "2"]) == 2
    assert "NEAR < FAR" in capsys.readouterr().err
    assert main(["bake", "--world", str(w), "--out", str(out)]) == 2
    assert main(["bake", "--world", str(w), "--out", str(out), "--lod", "0", "0", "0", "2",
                 "--light", "vertex"]) == 0
    doc, _ = glb.read(out)
    assert "far_level1" in {n["name"] for n in doc["nodes"]}
