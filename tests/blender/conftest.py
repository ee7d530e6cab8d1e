"""`addon`: the add-on registered on an empty factory scene (a module may define its own)."""
import pytest


@pytest.fixture
def addon(bpy):
    import voxel_addon
    bpy.ops.wm.read_factory_settings(use_empty=True)
    voxel_addon.register()
    yield bpy
    voxel_addon.unregister()
