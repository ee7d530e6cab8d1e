"""File › Import › Voxel World and the bake jobs in the real bpy: the operator
imports a region (explicit, around the origin, the generated chunks), big regions
split into one object per tile in a collection, and a job stopped at any step and
cancelled leaves the scene (and bpy.data) as it was."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import bake


@pytest.fixture
def world_file(tmp_path):
    from voxel_addon.world import World
    path = tmp_path / "w.sqlite"
    with World.create(path, seed=4, generator="flat", loader=False,
                      params={"layers": [["stone", 3], ["dirt", 1], ["grass", 1]]}) as w:
        w.set_block(2, 3, 5, "lamp_red")
        w.set_block(-5, 6, 5, "flowers")
        w.set_block(-6, 6, 5, "flowers")
        w.set_block(9, -9, 5, "leaves")
    return path


def _state(bpy):
    """Everything a job could leave behind, by name."""
    kinds = ("objects", "meshes", "materials", "images", "node_groups", "collections")
    out = {k: sorted(d.name for d in getattr(bpy.data, k)) for k in kinds}
    out["scene"] = sorted(c.name for c in bpy.context.scene.collection.children)
    out["linked"] = sorted(o.name for o in bpy.context.scene.objects)
    return out


def _tris(objs):
    return sum(len(p.vertices) - 2 for o in objs if o.type == "MESH" for p in o.data.polygons)


def test_import_operator_region(addon, world_file):
    bpy = addon
    assert "voxel_world" in dir(bpy.ops.import_scene)
    r = bpy.ops.import_scene.voxel_world(filepath=str(world_file), region=(-8, -12, 20, 10),
                                         per="region", light="atlas")
    assert r == {"FINISHED"}
    coll = [c for c in bpy.context.scene.collection.children if c.name.startswith("Voxel Bake")]
    assert len(coll) == 1
    objs = list(coll[0].objects)
    from voxel_addon.blender import session
    ref = bake.bake_world(session.world(str(world_file)), -8, -12, 20, 10)
    assert _tris(objs) == ref.triangles and len(objs) == 1
    me = objs[0].data
    assert len(me.uv_layers) == 2 and {m.name for m in me.materials} >= {"voxel_lamp_red",
                                                                          "voxel_grass_top"}
    # the same region per vertex: same faces, light in colour attributes
    r = bpy.ops.import_scene.voxel_world(filepath=str(world_file), region=(-8, -12, 20, 10),
                                         per="chunk", light="vertex")
    assert r == {"FINISHED"}


def test_import_modes(addon, world_file):
    bpy = addon
    from voxel_addon.blender import job, session
    w = session.world(str(world_file))
    assert job.region_of_mode(w, "origin", size=20) == (-10, -10, 10, 10)
    bpy.ops.import_scene.voxel_world(filepath=str(world_file), mode="origin", size=20,
                                     per="chunk")
    coll = bpy.data.collections["Voxel Bake -10 -10 10 10"]
    assert sorted(o.name for o in coll.objects) == ["chunk_-1_-1", "chunk_-1_0", "chunk_0_-1",
                                                     "chunk_0_0"]
    keys = set(w.file.chunk_keys())
    assert {(-1, -1), (0, 0)} <= keys  # the import generated and stored them
    box = job.region_of_mode(w, "generated")
    xs, ys = [k[0] for k in keys], [k[1] for k in keys]
    assert box == (16 * min(xs), 16 * min(ys), 16 * max(xs) + 16, 16 * max(ys) + 16)
    assert bpy.ops.import_scene.voxel_world(filepath=str(world_file), mode="generated",
                                            per="region") == {"FINISHED"}
    assert f"voxels_{box[0]}_{box[1]}" in bpy.data.objects


def test_import_bad_input_is_one_clear_error(addon, tmp_path, world_file):
    bpy = addon
    before = _state(bpy)
    with pytest.raises(RuntimeError, match="does not exist"):
        bpy.ops.import_scene.voxel_world(filepath=str(tmp_path / "none.sqlite"))
    with pytest.raises(RuntimeError, match="empty region"):
        bpy.ops.import_scene.voxel_world(filepath=str(world_file), region=(5, 0, 5, 9))
    assert _state(bpy) == before


def test_tiles_split_a_big_region(addon, world_file):
    from voxel_addon.blender import job, session
    j = job.Job(session.world(str(world_file)), (-40, -40, 40, 24), per="tile", tile=32)
    objs = j.run()
    names = sorted(o.name for o in objs)
    assert names == sorted(f"tile_{x}_{y}" for x in (-40, -8, 24) for y in (-40, -8))
    assert all(o.users_collection == (j.collection,) for o in objs)
    assert j.collection.name in addon.context.scene.collection.children
    ref = bake.bake_world(session.world(str(world_file)), -40, -40, 40, 24)
    # tiles cut merged quads at their borders, but cover exactly the same faces
    area = sum(p.area for o in objs for p in o.data.polygons)
    quads = np.concatenate([p.positions for p in ref.parts]).reshape(-1, 4, 3)
    ref_area = np.linalg.norm(np.cross(quads[:, 1] - quads[:, 0], quads[:, 3] - quads[:, 0]),
                              axis=1).sum()
    assert area == pytest.approx(ref_area) and _tris(objs) >= ref.triangles


@pytest.mark.parametrize("stop_at", ["generate", "mesh", "atlas", "objects", "done"])
def test_cancel_leaves_the_scene_as_it_was(addon, world_file, stop_at):
    """Run the job's steps up to a stage (its work generator, as the modal timer
    does), cancel, and compare every datablock and the scene with before."""
    bpy = addon
    from voxel_addon.blender import bake as BB, job, session
    # something of the user's that must survive, incl. a shared group made earlier
    cube = bpy.data.objects.new("mine", bpy.data.meshes.new("mine"))
    bpy.context.scene.collection.objects.link(cube)
    BB.shade_group()
    before = _state(bpy)
    j = job.Job(session.world(str(world_file)), (-20, -20, 36, 30), per="chunk", instances=True)
    seen = []
    for stage, frac in j.steps():
        seen.append(stage)
        if stage == stop_at and (frac > 0 or stage in ("generate", "atlas", "done")):
            break
    assert seen[-1] == stop_at
    if stop_at in ("objects", "done"):
        assert _state(bpy) != before  # something was half-made ...
    j.cancel()
    assert _state(bpy) == before  # ... and is gone again
    assert "mine" in bpy.context.scene.objects


def test_modal_runner_steps_and_cancels(addon, world_file):
    """The modal operator's driver: short steps, then Esc (cancel) midway."""
    bpy = addon
    from voxel_addon.blender import job, session
    before = _state(bpy)
    run = job.Runner(job.Job(session.world(str(world_file)), (-30, -30, 40, 40), per="tile",
                             tile=16), budget=0.0)
    stages = []
    while not run.done and run.stage != "objects":
        run.step()
        stages.append(run.stage)
    assert stages[0] == "generate" and "light" in stages and "objects" in stages
    assert "voxel" in run.text().lower() and "esc" in run.text().lower()
    run.cancel()
    assert run.done and _state(bpy) == before
    # the same job to the end: objects in a linked collection
    run = job.Runner(job.Job(session.world(str(world_file)), (-30, -30, 40, 40), per="tile",
                             tile=16), budget=0.0)
    while not run.step():
        pass
    assert len(run.job.objects) == 25 and run.job.collection.name in \
        bpy.context.scene.collection.children


def test_bake_operators_share_the_job(addon, world_file, tmp_path):
    bpy = addon
    sc = bpy.context.scene
    sc.voxel.path = str(world_file)
    s = sc.voxel_bake
    s.region_min, s.region_max, s.per = (-4, -4), (12, 12), "region"
    assert bpy.ops.voxel.bake() == {"FINISHED"}
    assert "voxels_-4_-4" in sc.objects
    before = _state(bpy)
    s.glb_path = str(tmp_path / "o.glb")
    assert bpy.ops.voxel.export_glb() == {"FINISHED"}
    assert (tmp_path / "o.glb").stat().st_size > 0
    assert _state(bpy) == before  # the export's temporary objects are gone
    assert np.isfinite(s.hours)


def test_generate_operator_stores_chunks(addon, world_file):
    bpy = addon
    from voxel_addon.blender import session
    sc = bpy.context.scene
    sc.voxel.path = str(world_file)
    s = sc.voxel_bake
    s.region_min, s.region_max = (-70, 40), (-20, 70)
    before = _state(bpy)
    assert bpy.ops.voxel.generate() == {"FINISHED"}
    keys = set(session.world(str(world_file)).file.chunk_keys())
    want = {(cx, cy) for cx in range(-5, -1) for cy in range(2, 5)}
    assert want <= keys
    assert _state(bpy) == before  # generating adds nothing to the scene
