"""For the job scripts run in a fresh Blender process: the add-on registered from the
checkout and a new flat world (seed 5) open in the current scene."""
from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:  # the jobs run as scripts: the checkout is importable
    sys.path.insert(0, str(ROOT))


def flat_scene(out: Path):
    """Register voxel_addon and create OUT/w.sqlite as a flat world; the scene."""
    import bpy
    import voxel_addon
    voxel_addon.register()
    sc = bpy.context.scene
    v = sc.voxel
    v.path, v.seed, v.generator = str(out / "w.sqlite"), 5, "flat"
    assert bpy.ops.voxel.world_new() == {"FINISHED"}
    return sc
