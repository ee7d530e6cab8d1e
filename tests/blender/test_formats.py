"""File › Import › Minecraft World / MagicaVoxel and File › Export › MagicaVoxel in
the real bpy (and, through tests/run.py, the real Blender): the operators write into
the scene's world (or a new empty world beside the source), the scene then shows
that world, and a .vox goes out and in again voxel for voxel."""
from __future__ import annotations

import numpy as np
import pytest

from tests.formats import mcfiles as mc
from tests.formats import voxfiles as vf


def _save(tmp_path):
    secs = {0: np.full((16, 16, 16), "minecraft:air", object)}
    secs[0][3, 4, 5] = "minecraft:bricks"           # y 3, z 4, x 5
    save = tmp_path / "My World"
    mc.write_region(save / "region", {(0, 0): mc.chunk_nbt(0, 0, secs),
                                      (1, 0): mc.chunk_nbt(1, 0, secs)}, 2)
    mc.level_dat(save, 3953)
    return save


def test_import_minecraft_operator(addon, tmp_path):
    bpy = addon
    from voxel_addon.blender import session
    from voxel_addon.core.blocks import REGISTRY
    save = _save(tmp_path)
    bpy.context.scene.voxel.path = ""
    r = bpy.ops.import_scene.voxel_minecraft(filepath=str(save / "level.dat"))
    assert r == {"FINISHED"}
    path = bpy.context.scene.voxel.path
    assert path == str(save) + ".sqlite"              # a new world beside the save
    w = session.world(path)
    assert w.file.generator == "empty" and sorted(w.file.chunk_keys()) == [(0, -1), (1, -1)]
    assert REGISTRY[w.get_block(5, -1 - 4, 3 + 64)].name == "bricks"
    # again into the same world: refused without Replace, done with it
    with pytest.raises(RuntimeError, match="Replace"):
        bpy.ops.import_scene.voxel_minecraft(filepath=str(save / "region" / "r.0.0.mca"))
    r = bpy.ops.import_scene.voxel_minecraft(filepath=str(save / "region" / "r.0.0.mca"),
                                             replace=True, use_y_min=True, y_min=0)
    assert r == {"FINISHED"}
    assert REGISTRY[w.get_block(5, -5, 3)].name == "bricks"


def test_import_minecraft_with_resources(addon, tmp_path):
    """The stack given in the operator is checked (a bad pack: one line, nothing made)
    and kept in the world, bottom first; the import keeps states."""
    import json
    bpy = addon
    from tests.mcres import packfiles as pf
    from voxel_addon.blender import session
    save = _save(tmp_path)
    jar = pf.write(tmp_path / "client.jar", jar=True)
    bpy.context.scene.voxel.path = ""
    with pytest.raises(RuntimeError, match="nope.zip"):
        bpy.ops.import_scene.voxel_minecraft(filepath=str(save / "level.dat"),
                                             resources=f"{jar}; {tmp_path / 'nope.zip'}")
    assert not (tmp_path / "My World.sqlite").exists()
    r = bpy.ops.import_scene.voxel_minecraft(filepath=str(save / "level.dat"),
                                             resources=str(jar))
    assert r == {"FINISHED"}
    w = session.world(bpy.context.scene.voxel.path)
    assert json.loads(w.file.meta["mc_resources"]) == [str(jar.resolve())]
    assert "minecraft:bricks" in json.loads(w.file.meta["mc_states"])


def test_vox_import_and_export_operators(addon, tmp_path):
    bpy = addon
    from voxel_addon.blender import session
    from voxel_addon.formats import vox
    from voxel_addon.world import World
    world = tmp_path / "w.sqlite"
    World.create(world, seed=0, generator="flat", loader=False).close()
    bpy.context.scene.voxel.path = str(world)
    rng = np.random.default_rng(3)
    pal = rng.integers(0, 256, (255, 3))
    vs = [(x, y, z, int(rng.integers(1, 256))) for x in range(4) for y in range(3)
          for z in range(5) if (x + y + z) % 2]
    src = tmp_path / "m.vox"
    src.write_bytes(vf.file(vf.model((4, 3, 5), vs) + vf.rgba(pal)))
    r = bpy.ops.import_scene.voxel_vox(filepath=str(src), location=(10, 20, 70))
    assert r == {"FINISHED"}
    out = tmp_path / "out.vox"
    r = bpy.ops.export_scene.voxel_vox(filepath=str(out), box=(10, 20, 70, 14, 23, 75))
    assert r == {"FINISHED"}
    scene = vox.read(out.read_bytes())
    xyz, col, size = vox.voxels(scene)
    got = {tuple(p.tolist()): tuple(scene.palette[c, :3].tolist()) for p, c in zip(xyz, col)}
    assert got == {(x, y, z): tuple(int(v) for v in pal[i - 1]) for x, y, z, i in vs}
    assert session.world(str(world)).file.generator == "flat"   # the scene's own world
    with pytest.raises(RuntimeError, match="missing.vox"):
        bpy.ops.import_scene.voxel_vox(filepath=str(tmp_path / "missing.vox"))


def test_stamp_is_one_undo_step(bpy, tmp_path):
    """voxel.stamp (a click of the edit tool with Stamp on) places the model centred
    on the cell, its bottom at the cell's z, as one stroke: one Ctrl+Z removes it."""
    import voxel_addon
    from voxel_addon.blender import session, strokes
    from voxel_addon.core import colors
    from voxel_addon.core.blocks import REGISTRY
    bpy.ops.wm.read_factory_settings(use_empty=True)
    voxel_addon.register()
    try:
        sc = bpy.context.scene
        sc.voxel.path, sc.voxel.seed, sc.voxel.generator = str(tmp_path / "w.sqlite"), 3, "flat"
        assert bpy.ops.voxel.world_new() == {"FINISHED"}
        sc.voxel_edit.step = 0
        src = tmp_path / "tree.vox"
        vs = [(1, 1, z, 3) for z in range(4)] + [(x, y, 4, 7) for x in range(3) for y in range(3)]
        src.write_bytes(vf.file(vf.model((3, 3, 5), vs)))
        r = bpy.ops.voxel.stamp("EXEC_DEFAULT", True, filepath=str(src), location=(20, 30, 64))
        assert r == {"FINISHED"} and sc.voxel_edit.step == 1
        w = session.world(sc.voxel.path)
        color = REGISTRY.id("color")
        pal = colors.parse(w.file.meta)
        assert w.get_block(20, 30, 64) == color and w.get_block(19, 29, 68) == color
        assert tuple(pal[w.chunk_at(1, 1).data[20 & 15, 30 & 15, 64]]) == (255, 255, 153)  # default palette index 3
        sc.voxel_edit.step = 0                     # Ctrl+Z
        strokes.on_undo_redo(sc)
        assert w.get_block(20, 30, 64) == 0 and w.get_block(19, 29, 68) == 0
    finally:
        sc.property_unset("voxel")
        sc.property_unset("voxel_edit")
        voxel_addon.unregister()


def test_a_stamp_adds_to_the_palette_another_process_grew(bpy, tmp_path):
    """Blender read the palette when it opened the world; a command-line import then
    added its colour (index 1). The stamp's colour went to index 1 too, and its
    palette, written with the stroke, gave the other model the stamp's colour."""
    import os
    import subprocess
    import voxel_addon
    from tests import host
    from voxel_addon.blender import session
    from voxel_addon.core import colors
    from voxel_addon.formats import vox
    for me, rgb in (("red", (250, 0, 0)), ("blue", (0, 0, 250))):
        pal = np.zeros((256, 3), np.uint8)
        pal[1] = rgb
        (tmp_path / f"{me}.vox").write_bytes(vox.write(np.ones((2, 2, 2), np.uint8), pal))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    voxel_addon.register()
    sc = bpy.context.scene
    try:
        sc.voxel.path, sc.voxel.seed, sc.voxel.generator = str(tmp_path / "w.sqlite"), 3, "flat"
        assert bpy.ops.voxel.world_new() == {"FINISHED"}
        w = session.world(sc.voxel.path)
        w.get_block(40, 0, 100)                     # the session has read the file
        r = subprocess.run(host.python_cmd("-m", "voxel_addon", "import", "--world",
                                           sc.voxel.path, "--from", tmp_path / "red.vox",
                                           "--at", 0, 0, 100),
                           env=dict(os.environ, PYTHONPATH=str(host.ROOT), VOXEL_OPENCL="0"),
                           capture_output=True, text=True, timeout=120, cwd=host.ROOT)
        assert r.returncode == 0, r.stderr[-2000:]
        assert bpy.ops.voxel.stamp("EXEC_DEFAULT", True, filepath=str(tmp_path / "blue.vox"),
                                   location=(41, 1, 100)) == {"FINISHED"}
        session._poll()                              # the other process's chunks
        pal = colors.parse(w.file.meta)
        assert pal[w.chunk_at(2, 0).data[41 & 15, 1, 100]].tolist() == [0, 0, 250]
    finally:
        sc.property_unset("voxel")
        sc.property_unset("voxel_edit")
        voxel_addon.unregister()
    from voxel_addon.world import World
    with World.open(tmp_path / "w.sqlite", loader=False, readonly=True) as w2:
        pal = colors.parse(w2.file.meta)
        assert pal[w2.chunk_at(0, 0).data[1, 1, 101]].tolist() == [250, 0, 0]
        assert pal[w2.chunk_at(2, 0).data[41 & 15, 1, 100]].tolist() == [0, 0, 250]
