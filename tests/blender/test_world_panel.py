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


def test_view_panel_says_loading_until_every_wanted_chunk_is_drawn(bpy):
    """ui/view.chunks_line: never done for a view with no chunk wanted yet (the
    stream not started: the frame is sky) nor with chunks still to come (issue 28)."""
    from voxel_addon.blender.ui.view import chunks_line
    assert chunks_line({"drawn": 0, "wanted": 0}) == "chunks 0 / 0  loading…"
    assert chunks_line({"drawn": 0, "wanted": 81}) == "chunks 0 / 81  loading…"
    assert chunks_line({"drawn": 80, "wanted": 81}).endswith("loading…")
    assert chunks_line({"drawn": 81, "wanted": 81}) == "chunks 81 / 81"


def test_world_panel_says_numpy_while_opencl_builds(bpy, cl_device, monkeypatch):
    """During the live view's OpenCL warm-up a new world would generate with NumPy."""
    import threading
    from voxel_addon import opencl
    from voxel_addon.blender.ui.world import backend_line
    monkeypatch.setattr(opencl, "_warm", dict.fromkeys(opencl._warm))  # never warmed
    gate = threading.Event()
    assert opencl.warm(lambda: gate.wait(30))
    try:
        assert backend_line() == ("info", "Generates with", "NumPy (CPU) until OpenCL is built")
    finally:
        gate.set()
        opencl._warm["thread"].join(30)
    assert backend_line() == ("info", "Generates with", "OpenCL")


def test_a_stored_generator_keeps_its_meaning_when_generators_are_added(bpy, scene, monkeypatch):
    """A .blend stores the enum's item number: numbered by place in the list, a
    generator added in front of the others would turn a saved 'empty' into another."""
    from voxel_addon import generation
    from voxel_addon.blender.ui import world
    scene.voxel.generator = "empty"
    stored = scene.voxel.get("generator")  # what the .blend keeps
    monkeypatch.setattr(generation, "GENERATORS", {"cave": "flat:FlatGenerator",
                                                   **generation.GENERATORS})
    monkeypatch.setitem(world.NUMBERS, "cave", max(world.NUMBERS.values()) + 1)
    assert scene.voxel.get("generator") == stored
    assert scene.voxel.generator == "empty"
    numbers = [i[3] for i in world._generators(None, bpy.context)]
    assert len(set(numbers)) == len(numbers)
