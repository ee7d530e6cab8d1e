"""The World panel's contents (ui/world.lines, what VOXEL_PT_world.draw lays out) in
the real bpy: the New World settings only while the file is missing; an open world
shows its own seed and generator, not the New settings."""
from __future__ import annotations

import pytest


@pytest.fixture
def scene(bpy, tmp_path):
    import voxel_addon
    voxel_addon.register()
    sc = bpy.context.scene
    sc.voxel.path = str(tmp_path / "w.sqlite")
    yield sc
    sc.property_unset("voxel")
    voxel_addon.unregister()


def _backend():
    """What the panel must name: OpenCL here (CI has pocl), NumPy with VOXEL_OPENCL=0."""
    from voxel_addon import opencl
    return ("info", "Generates with",
            "NumPy (CPU), no OpenCL" if opencl.switched_off() else "OpenCL")


def test_world_panel_shows_new_settings_or_the_open_worlds_own(bpy, scene):
    from voxel_addon.blender import session
    from voxel_addon.blender.ui.world import lines
    v = scene.voxel
    v.seed, v.generator = 5, "overworld"
    assert lines(v) == [("label", "New World:", "ADD"), ("prop", "seed"), ("prop", "generator"),
                        _backend()]
    assert bpy.ops.voxel.world_new() == {"FINISHED"}
    v.seed, v.generator = 9, "flat"  # the next New's settings, not this world's
    got = lines(v)
    assert ("info", "Seed", "5") in got and ("info", "Generator", "Overworld") in got, got
    assert _backend() in got, got
    assert not [x for x in got if x[0] == "prop"] and ("recreate",) in got, got
    session.close(v.path)  # the file is there, not open: neither New settings nor info
    got = lines(v)
    assert got[0][0] == "label" and got[0][1].startswith("Not open") and got[1:] == [("recreate",)]
    assert bpy.ops.voxel.world_open(filepath=v.path) == {"FINISHED"}
    assert ("info", "Generator", "Overworld") in lines(v)
