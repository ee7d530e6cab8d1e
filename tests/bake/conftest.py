"""Fixtures for bake tests: a small world file with every kind of block, bpy, the validator."""
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DECOR = [(3, 3, 7, "lamp_red"), (5, 5, 7, "glass"), (6, 5, 7, "glass"), (8, 8, 7, "flowers"),
         (9, 8, 7, "wheat"), (10, 10, 7, "cactus"), (12, 3, 7, "log"), (12, 3, 8, "log"),
         (12, 3, 9, "leaves"), (2, 10, 6, "water"), (3, 10, 6, "water"), (14, 14, 7, "ore"),
         (1, 1, 7, "glowing_mushroom"), (20, 4, 7, "tall_grass"), (21, 4, 7, "mushroom"),
         (-3, -3, 7, "lamp_blue"), (17, 17, 7, "snow"), (18, 17, 7, "sand"),
         (8, 10, 7, "flowers"), (8, 12, 7, "flowers"), (21, 6, 7, "tall_grass")]


@pytest.fixture(scope="session")
def small_world(tmp_path_factory):
    from voxel_addon.world import World
    path = tmp_path_factory.mktemp("bake") / "w.sqlite"
    w = World.create(path, seed=3, generator="flat", loader=False,
                     params={"layers": [["stone", 4], ["dirt", 2], ["grass", 1]]})
    try:
        for x, y, z, n in DECOR:
            w.set_block(x, y, z, n)
    finally:
        w.close()
    return path


@pytest.fixture(scope="session")
def validate():
    """validate(path) -> the Khronos validator's report (dict)."""
    import json
    node = shutil.which("node")
    mod = ROOT / ".tools" / "node_modules" / "gltf-validator"
    if not node or not mod.is_dir():
        pytest.skip("glTF validator missing (python build.py setup installs it into .tools)")

    def run(path):
        r = subprocess.run([node, str(ROOT / "tools" / "validate_gltf.mjs"), str(path)],
                           capture_output=True, text=True, timeout=120)
        assert r.stdout, r.stderr
        return json.loads(r.stdout)
    return run


@pytest.fixture(scope="session")
def reference_blocks(tmp_path_factory):
    """The bench's 48×48 reference region: Overworld seed 2019, [-24, 24)²."""
    from voxel_addon import bake
    from voxel_addon.world import World
    path = tmp_path_factory.mktemp("ref") / "ref.sqlite"
    with World.create(path, seed=2019, generator="overworld", loader=False) as w:
        return bake.region_of(w, -24, -24, 24, 24)
