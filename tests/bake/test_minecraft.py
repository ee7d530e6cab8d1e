"""A Minecraft import baked with the world's resource stack (issue 30 c): voxels the
stack knows come from their models with the stack's textures and biome tints (one
material per texture, layer and tint), the rest keeps today's look; a stack whose
files are gone bakes today's look; the .glb is validator-clean."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import bake
from voxel_addon.core.blocks import REGISTRY

from ..mcres import packfiles as pf
from ..mcres.builds import save_with_build



@pytest.fixture(scope="module")
def mc_world(tmp_path_factory):
    from voxel_addon.cli import main
    root = tmp_path_factory.mktemp("mcbake")
    jar = pf.write(root / "client.jar", jar=True)
    w = root / "w.sqlite"
    assert main(["import", "--world", str(w), "--from", str(save_with_build(root)),
                 "--resources", str(jar)]) == 0
    return w, jar


def baked(path, **kw):
    from voxel_addon.world import World
    with World.open(path, readonly=True, loader=False) as w:
        return bake.bake_world(w, 0, -16, 16, 0, **kw)


def model_part(bk):
    got = [p for p in bk.parts if p.name.startswith("minecraft_")]
    return got[0] if got else None


@pytest.mark.parametrize("light", ["atlas", "vertex"])
def test_models_with_the_stacks_textures_and_tints(mc_world, light):
    bk = baked(mc_world[0], light=light)
    p = model_part(bk)
    assert p is not None and p.uv2 is None and not bk.note
    specs = [bk.materials[i] for i in np.unique(p.material)]
    assert all(s.per_vertex for s in specs)
    by = {s.image: s for s in specs}
    assert {"minecraft:block/stone", "minecraft:block/oak_planks", "minecraft:block/glass",
            "minecraft:block/poppy", "minecraft:block/grass_block_top"} <= set(by)
    assert by["minecraft:block/glass"].render == "blend"
    # grass (x 0..1: the desert's columns) tinted by the desert's colormap pixel
    tops = {s.tint for s in specs if s.image == "minecraft:block/grass_block_top"}
    assert tops == {(0.0, 1.0, 7 / 255)}
    # the sprites' pixels are the pack's
    assert np.array_equal(bk.images["minecraft:block/stone"], pf.texture("stone"))
    # the greedy parts leave the modelled voxels out, keep the gold block (the `color`
    # block: today's look, its colour material)
    others = [q for q in bk.parts if q is not p]
    kinds = set(np.concatenate([q.block for q in others]).tolist())
    assert kinds == {REGISTRY.id("color")}
    assert {REGISTRY.id(n) for n in ("stone", "grass", "planks", "glass", "flowers")} <= \
        set(p.block.tolist())
    assert len(p.light) == 4 * p.quads and (p.daylight > 0).any()
    # the poppy's planes take its voxel's light: one value per quad
    poppy = [i for i in range(p.quads)
             if bk.materials[p.material[i]].image == "minecraft:block/poppy"]
    assert poppy
    for i in poppy:
        assert np.ptp(p.daylight[4 * i:4 * i + 4]) == 0 and np.ptp(p.light[4 * i:4 * i + 4], axis=0).max() == 0


def test_model_textures_stand_as_the_greedy_paths(mc_world):
    """On every side face the texture's v grows upward and its u to the right seen
    from outside (cross(up, normal)), as the greedy path lays its tiles (Blender's
    uv: v up), so sprites are not upside down or mirrored. (A door's and a pane's
    models mirror one side on purpose, as the game's: those are left out.)"""
    from voxel_addon.core.blocks import REGISTRY as R
    one = np.zeros((3, 3, 256), np.uint16)
    one[1, 1, 5] = R.id("stone")
    greedy = bake.bake_blocks(one, light="vertex").parts[0]
    bk = baked(mc_world[0], light="vertex")
    p = model_part(bk)

    def bk_images(part):
        return [bk.materials[m].image for m in part.material]
    for part in (greedy, p):
        pos, uv = part.positions.reshape(-1, 4, 3), part.uvs.reshape(-1, 4, 2)
        n = part.normals.reshape(-1, 4, 3)[:, 0]
        side = np.flatnonzero(np.abs(n[:, 2]) < 0.5)
        if part is p:
            mirrored = ("minecraft:block/oak_door_top", "minecraft:block/oak_door_bottom",
                        "minecraft:block/glass_pane_top", "minecraft:block/glass")
            side = [i for i in side if bk_images(part)[i] not in mirrored]
        assert len(side)
        for i in side:
            right = np.cross([0, 0, 1], n[i])
            dz, dv = pos[i, :, 2] - pos[i, 0, 2], uv[i, :, 1] - uv[i, 0, 1]
            dr, du = (pos[i] - pos[i, 0]) @ right, uv[i, :, 0] - uv[i, 0, 0]
            assert (np.sign(np.round(dz, 6)) == np.sign(np.round(dv, 6))).all(), (part.name, i)
            assert (np.sign(np.round(dr, 6)) == np.sign(np.round(du, 6))).all(), (part.name, i)


def test_the_builds_shapes_come_out_in_the_bake(mc_world):
    """Each slab, pane, door half, rail, torch and leaves block of the build: every
    quad of its shape that nothing hides (no cullface, or air there) is in the bake at
    its voxel (Minecraft (x, y, z) → voxel (x, −1−z, y + 64)), with the sprite's layer."""
    from voxel_addon.mcres import Resources, Stack
    from voxel_addon.mcres.states import parse_key
    from ..mcres import builds
    bk = baked(mc_world[0], light="vertex")
    p = model_part(bk)
    have = {}
    for i, quad in enumerate(np.round(p.positions.reshape(-1, 4, 3), 4)):
        have[frozenset(map(tuple, quad.tolist()))] = bk.materials[p.material[i]]
    blocks = {**{(x, 1, z): k for (x, z), k in builds._joined("glass_pane", builds.PANE).items()},
              **{(x, 1, z): f"minecraft:oak_slab[type={t}]" for (x, z), t in builds.SLABS.items()},
              **{(x, y, z): f"minecraft:rail[shape={sh}]" for (x, z, y), sh in builds.RAILS.items()},
              (builds.TORCH[0], 1, builds.TORCH[1]): "minecraft:torch",
              **{(x, y, z): "minecraft:oak_leaves" for x, y, z in builds.LEAVES}}
    for (x, z), (facing, hinge, opened) in builds.DOORS.items():
        for y, half in ((1, "lower"), (2, "upper")):
            blocks[x, y, z] = (f"minecraft:oak_door[facing={facing},half={half},hinge={hinge},"
                               f"open={opened}]")
    from voxel_addon.mcres.mesh import OFFSETS
    from voxel_addon.world import World
    res = Resources(Stack.open([mc_world[1]]))
    render = {"solid": "opaque", "cutout": "alpha_test", "translucent": "blend"}
    try:
        with World.open(mc_world[0], readonly=True, loader=False) as w:
            for (x, y, z), key in blocks.items():
                v = np.array([x, -1 - z, y + 64])
                sh = res.shape(*parse_key(key))
                free = [q for q in sh.quads
                        if q.cull < 0 or w.get_block(*map(int, v + OFFSETS[q.cull])) == 0]
                assert free, key
                blocks[x, y, z] = (v, free)
        for key_v, (v, free) in blocks.items():
            for q in free:
                at = frozenset(map(tuple, np.round(q.pos + v, 4).tolist()))
                assert at in have, (key_v, q.face)
                m = have[at]
                assert m.image == q.sprite and m.render == render[q.layer], (key_v, m)
    finally:
        res.close()


def test_the_floor_under_a_rail_is_lit_as_open_floor(mc_world):
    """The rails (planks cubes in today's look) pass light with the stack: the stone
    floor's top under them has the daylight of the open floor beside them."""
    from ..mcres import builds
    p = model_part(baked(mc_world[0], light="vertex"))
    c = p.positions.reshape(-1, 4, 3).mean(1)
    up = p.normals.reshape(-1, 4, 3)[:, 0, 2] > 0.5
    day = p.daylight.reshape(-1, 4).mean(1)

    def floor_top(x, z):
        at = up & np.all(np.abs(c - (x + 0.5, -1 - z + 0.5, 65)) < 1e-3, axis=1)
        assert at.sum() == 1, (x, z)
        return float(day[at][0])
    open_floor = floor_top(11, 9)
    assert open_floor > 0.5
    for (x, z, y), shape in builds.RAILS.items():
        if y == 1 and shape == "north_south":      # (not beside the block they climb)
            assert floor_top(x, z) == pytest.approx(open_floor, abs=0.02), (x, z)


def test_a_missing_stack_bakes_todays_look(mc_world, tmp_path):
    import shutil
    w, jar = mc_world
    copy = tmp_path / "w.sqlite"
    shutil.copy(w, copy)
    from voxel_addon.world import World
    with World.open(copy, loader=False) as world:
        world.file.set_meta("mc_resources", '["/nowhere/client.jar"]')
    bk = baked(copy)
    assert model_part(bk) is None and "resource stack not read" in bk.note
    assert REGISTRY.id("stone") in set(np.concatenate([p.block for p in bk.parts]).tolist())


def test_the_glb_is_valid(bpy, mc_world, tmp_path, validate):
    from voxel_addon.bake import glb
    from voxel_addon.blender import bake as BB
    bk = baked(mc_world[0])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="gltf")
    out = tmp_path / "mc.glb"
    BB.export_glb(out, objs)
    report = validate(out)
    assert report["issues"]["numErrors"] == 0, report["issues"]["messages"][:5]
    doc, _ = glb.read(out)
    names = {m["name"] for m in doc["materials"]}
    for sprite in ("grass_block_top", "oak_door_top", "oak_door_bottom", "glass_pane_top",
                   "rail", "torch", "oak_leaves"):
        assert any(n.startswith(f"voxel_mc_{sprite}") for n in names), (sprite, names)
    assert len(doc["images"]) >= 5
    # model quads carry their light per vertex (COLOR_0), never the atlas's occlusion
    mc = [m for m in doc["materials"] if m["name"].startswith("voxel_mc_")]
    assert mc and not any("occlusionTexture" in m for m in mc)
    prims = [pr for me in doc["meshes"] if me["name"].startswith("minecraft_")
             for pr in me["primitives"]]
    assert prims and all("COLOR_0" in pr["attributes"] for pr in prims)


def test_blenders_bake_job_uses_the_stack(bpy, mc_world):
    """The panel's bake (blender/job.Job) bakes the same models as bake_world."""
    from voxel_addon.blender import job
    from voxel_addon.world import World
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with World.open(mc_world[0], readonly=True, loader=False) as w:
        objs = job.Job(w, (0, -16, 16, 0), light="vertex").run()
    names = {o.name for o in objs}
    assert any(n.startswith("minecraft_") for n in names), names
    mats = {m.name for o in objs for m in o.data.materials}
    assert any(n.startswith("voxel_mc_poppy") for n in mats), mats
