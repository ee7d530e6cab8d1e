"""File › Import › Minecraft World in the real Blender window, then the imported build
in the live voxel view (the README's picture comes from this screenshot)."""
from __future__ import annotations

import numpy as np

from tests.formats import mcfiles as mc
from voxel_addon.textures import image


def _mean(name):
    rgba = image(name)[0].astype(float)
    return rgba[..., :3].mean((0, 1))


def test_minecraft_import_into_the_live_view(gui, tmp_path):
    save = mc.demo_build(tmp_path / "Demo")
    res = gui("minecraft_view.py", timeout=400, level=str(save / "level.dat"))
    r = res.result
    assert r["started"] == ["RUNNING_MODAL"], r
    assert r["world"] == str(save) + ".sqlite", r
    from voxel_addon.world import World
    with World.open(r["world"], readonly=True, loader=False) as w:
        assert w.file.chunk_count() == 9 and w.file.generator == "empty"
    img = res.image("minecraft").astype(float)
    x, y, wd, ht = r["rect"]
    h = img.shape[0]
    view = img[h - (y + ht):h - y, x:x + wd]
    # the build's materials show: planks (brown), grass (green), lava (orange)
    px = view.reshape(-1, 3)
    brown = (px[:, 0] > px[:, 1] + 15) & (px[:, 1] > px[:, 2] + 10) & (px[:, 0] > 90)
    green = (px[:, 1] > px[:, 0] + 15) & (px[:, 1] > px[:, 2] + 15)
    assert brown.mean() > 0.01 and green.mean() > 0.10, (brown.mean(), green.mean())
