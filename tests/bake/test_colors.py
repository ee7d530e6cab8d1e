"""Coloured voxels through the bake: one material per colour (the neutral tile times
the voxel's own colour), in Blender and in the .glb (baseColorFactor), for both light
modes; faces of different colours never share a quad."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import bake
from voxel_addon.core import colors
from voxel_addon.core.blocks import REGISTRY

COLOR = REGISTRY.id("color")
RGB = [(200, 30, 40), (20, 180, 60), (250, 250, 250)]


@pytest.fixture(scope="module")
def colour_world(tmp_path_factory):
    from voxel_addon.world import World
    path = tmp_path_factory.mktemp("colors") / "w.sqlite"
    with World.create(path, seed=0, generator="flat", loader=False,
                      params={"layers": [["stone", 3]]}) as w:
        pal, idx = colors.add(colors.parse(w.file.meta), RGB)
        w.file.set_meta(colors.KEY, colors.dump(pal))
        xyz = np.array([(x, y, 3) for x in range(6) for y in range(4)])
        w.set_blocks(xyz, np.full(len(xyz), COLOR), idx[(xyz[:, 0] // 2) % 3])
        w.flush()
    return path


def _baked(path, **kw):
    from voxel_addon.world import World
    with World.open(path, readonly=True, loader=False) as w:
        return bake.bake_world(w, -2, -2, 10, 8, **kw)


@pytest.mark.parametrize("light", ["atlas", "vertex"])
def test_one_material_per_colour(colour_world, light):
    bk = _baked(colour_world, light=light)
    tints = {s.tint for s in bk.materials if s.tint is not None}
    assert tints == {tuple(c / 255 for c in rgb) for rgb in RGB}
    for p in bk.parts:
        sel = p.block == COLOR
        assert sel.any()
        # top faces: x 0..1 red, 2..3 green, 4..5 white, never merged across
        pos = p.positions.reshape(-1, 4, 3)
        for k in np.flatnonzero(sel & (p.face == 5)):
            xs = pos[k, :, 0]
            spec = bk.materials[p.material[k]]
            assert spec.tint == tuple(c / 255 for c in RGB[int(xs.min()) // 2 % 3])
            assert xs.max() - xs.min() <= 2


def test_glb_keeps_colours(bpy, colour_world, tmp_path):
    from voxel_addon.bake import glb
    from voxel_addon.blender import bake as BB
    bk = _baked(colour_world)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="gltf")
    out = tmp_path / "c.glb"
    BB.export_glb(out, objs)
    doc, _ = glb.read(out)
    got = {tuple(round(v, 3) for v in m["pbrMetallicRoughness"].get("baseColorFactor", [1] * 4)[:3])
           for m in doc["materials"] if m["name"].startswith("voxel_color_")}
    lin = lambda c: c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4
    assert got == {tuple(round(lin(c / 255), 3) for c in rgb) for rgb in RGB}
