"""The extension shell: zip builds and validates with Blender's own tool, installs into
the real bpy, registers its panel/operators/settings, and unregisters cleanly."""
from __future__ import annotations

import importlib.util
import os
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PANELS = ("VOXEL_PT_world", "VOXEL_PT_bake")
OPS = ("world_new", "world_open", "world_recreate", "bake", "export_glb")


def _tool():
    spec = importlib.util.spec_from_file_location("voxel_ext_tool", ROOT / "tools" / "extension.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _registered(bpy) -> dict:
    return {"panels": [hasattr(bpy.types, p) for p in PANELS],
            "ops": [hasattr(bpy.ops.voxel, o) and _op_exists(bpy, o) for o in OPS],
            "scene": hasattr(bpy.types.Scene, "voxel") and hasattr(bpy.types.Scene, "voxel_bake")}


def _op_exists(bpy, name) -> bool:
    try:
        getattr(bpy.ops.voxel, name).get_rna_type()
        return True
    except KeyError:
        return False


def _none(state):
    return not any(state["panels"]) and not any(state["ops"]) and not state["scene"]


def _all(state):
    return all(state["panels"]) and all(state["ops"]) and state["scene"]


@pytest.fixture(scope="module")
def zip_path(bpy, tmp_path_factory):
    scripts = Path(bpy.utils.system_resource("SCRIPTS"))
    ext = scripts / "addons_core" / "bl_pkg" / "cli" / "blender_ext.py"
    os.environ.setdefault("VOXEL_BLENDER_EXT", str(ext))
    return _tool().build(tmp_path_factory.mktemp("dist"))


def test_zip_contents(zip_path):
    names = zipfile.ZipFile(zip_path).namelist()
    assert "blender_manifest.toml" in names and "__init__.py" in names
    assert "voxel_addon/blender/ui/world.py" in names
    assert not [n for n in names if "__pycache__" in n or n.endswith(".pyc")]
    init = zipfile.ZipFile(zip_path).read("__init__.py").decode()
    assert "from .voxel_addon import register, unregister" in init
    man = zipfile.ZipFile(zip_path).read("blender_manifest.toml").decode()
    assert 'id = "voxel_worlds"' in man and 'blender_version_min = "4.3.0"' in man


def test_repo_package_registers_and_unregisters(bpy):
    import voxel_addon
    assert _none(_registered(bpy))
    voxel_addon.register()
    try:
        assert _all(_registered(bpy))
        s = bpy.context.scene.voxel
        assert s.generator in ("overworld", "flat") and s.seed == 2019
    finally:
        voxel_addon.unregister()
    assert _none(_registered(bpy))


def test_zip_installs_enables_and_operates(bpy, zip_path, tmp_path):
    import addon_utils
    repos = [r.module for r in bpy.context.preferences.extensions.repos]
    assert "user_default" in repos
    mod = "bl_ext.user_default.voxel_worlds"
    r = bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default",
                                                 enable_on_install=True)
    try:
        assert r == {"FINISHED"}
        assert mod in bpy.context.preferences.addons.keys()
        assert _all(_registered(bpy))
        # the operators run from the installed copy: create, reopen and recreate a world
        s = bpy.context.scene.voxel
        s.path = str(tmp_path / "w.sqlite")
        s.seed, s.generator = 7, "flat"
        assert bpy.ops.voxel.world_new() == {"FINISHED"}
        assert (tmp_path / "w.sqlite").exists()
        s.seed = 1
        assert bpy.ops.voxel.world_open("EXEC_DEFAULT", filepath=s.path) == {"FINISHED"}
        assert s.seed == 7
        assert bpy.ops.voxel.world_recreate("EXEC_DEFAULT") == {"FINISHED"}
    finally:
        addon_utils.disable(mod)
        assert _none(_registered(bpy))
        idx = repos.index("user_default")
        bpy.ops.extensions.package_uninstall(repo_index=idx, pkg_id="voxel_worlds")
    assert mod not in bpy.context.preferences.addons.keys()
