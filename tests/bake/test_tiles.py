"""bake.tiles (one .glb per tile, cluster tasks): a tile baked on its own from its cut
(its blocks plus a ring of context) equals that tile's part of the whole region's bake,
light included: lamps and coloured voxels sit right by the tile edges."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import bake
from voxel_addon.bake import tiles

# tiles start at x -60, 4 and y -61, 3: the lamps at (3, 3) and (-3, -3) sit by the edges
REGION = (-60, -61, 40, 30)
FIELDS = ("positions", "normals", "uvs", "light", "daylight", "block", "face")


@pytest.mark.parametrize("light, instances", [("atlas", False), ("vertex", True)])
def test_tile_equals_its_part_of_the_region(small_world, tmp_path, light, instances):
    import shutil
    from voxel_addon.world import World
    shutil.copy(small_world, tmp_path / "w.sqlite")
    with World.open(tmp_path / "w.sqlite", loader=False) as w:
        w.set_block(5, 2, 7, "color", 3)  # a tinted voxel by the x = 4 edge
        w.set_block(-60, 2, 7, "lamp_green")  # light into the tile below, none at the region's edge
        whole = bake.bake_world(w, *REGION, per="tile", light=light, instances=instances)
        cuts = [tiles.cut(w, REGION, t) for t in tiles.plan(*REGION)]
    assert [c["name"] for c in cuts] == [f"tile_{x}_{y}" for y in (-61, 3) for x in (-60, 4)]
    parts = {p.name: p for p in whole.parts}
    assert set(parts) == {c["name"] for c in cuts}
    lit = 0
    for c in cuts:
        bk = tiles.bake(c, light=light, instances=instances)
        assert bk.region[:2] == tuple(int(v) for v in c["name"].split("_")[1:])
        (p,) = bk.parts
        q = parts[p.name]
        for f in FIELDS:
            assert np.array_equal(getattr(p, f), getattr(q, f)), (p.name, f)
        # the same material for each quad (indices may differ: tints are per bake)
        assert [bk.materials[i] for i in p.material] == [whole.materials[i] for i in q.material]
        lit += int((p.light > 0).any())
        for name, xyz in bk.plants.items():
            x0, y0, x1, y1 = bk.region
            sel = (whole.plants[name][:, 0] >= x0) & (whole.plants[name][:, 0] < x1) & \
                (whole.plants[name][:, 1] >= y0) & (whole.plants[name][:, 1] < y1)
            assert np.array_equal(xyz, whole.plants[name][sel])
    assert lit >= 2  # block light on both sides of an edge


def test_plan_covers_the_region_once():
    cover = np.zeros((130, 70), int)
    for name, x0, y0, x1, y1 in tiles.plan(-65, 10, 65, 80):
        assert name == f"tile_{x0}_{y0}" and x1 - x0 <= 64 and y1 - y0 <= 64
        cover[x0 + 65:x1 + 65, y0 - 10:y1 - 10] += 1
    assert (cover == 1).all()
