"""Bake -> Blender objects -> glTF: the Khronos validator finds 0 errors, Blender
re-imports the same triangles; the CLI command end to end; Blender-side materials."""
from __future__ import annotations

import os
import subprocess

import numpy as np
import pytest

from tests.host import python_cmd
from voxel_addon import bake

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def _baked(small_world, **kw):
    from voxel_addon.world import World
    with World.open(small_world, readonly=True, loader=False) as w:
        return bake.bake_world(w, -5, -5, 24, 22, **kw)


def _triangles(bpy, objs):
    n = 0
    for o in objs:
        if o.type == "MESH":
            n += sum(len(p.vertices) - 2 for p in o.data.polygons)
    return n


@pytest.mark.parametrize("per,instances", [("region", False), ("chunk", True)])
def test_glb_validates_and_reimports(bpy, small_world, validate, tmp_path, per, instances):
    from voxel_addon.blender import bake as BB
    bk = _baked(small_world, per=per, instances=instances)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="gltf", hours=20.0)
    assert len([o for o in objs if o.name.startswith(("chunk_", "voxels_"))]) == len(bk.parts)
    out = tmp_path / "x.glb"
    BB.export_glb(out, objs, instances=instances)
    rep = validate(out)
    assert rep["issues"]["numErrors"] == 0, rep["issues"]["messages"][:5]
    assert rep["info"]["hasTextures"]
    mesh_tris = bk.triangles
    if not instances:
        assert rep["info"]["totalTriangleCount"] == mesh_tris
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=str(out))
    imported = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    if instances:  # the plants come back as instanced copies of a prototype
        meshes = [o for o in imported if o.name.startswith(("chunk_", "voxels_"))]
        assert _triangles(bpy, meshes) == mesh_tris
        plants = sum(len(v) for v in bk.plants.values())
        assert len(imported) - len(meshes) >= plants
    else:
        assert _triangles(bpy, imported) == mesh_tris
    mats = {m.name for o in imported for m in o.data.materials}
    assert {"voxel_lamp_red_gltf", "voxel_leaves_gltf", "voxel_water_gltf"} <= mats
    assert any(a.name.lower().startswith("color") or a.name == "shade"
               for o in imported for a in o.data.color_attributes)


def test_blender_objects_carry_light_and_time_of_day(bpy, small_world):
    from voxel_addon.blender import bake as BB
    bk = _baked(small_world)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="blender", hours=21.5)
    me = objs[0].data
    assert len(me.polygons) == bk.parts[0].quads
    light = np.empty(4 * len(me.vertices), np.float32)
    me.color_attributes["light"].data.foreach_get("color", light)
    assert np.allclose(light.reshape(-1, 4)[:, :3], bk.parts[0].light, atol=1e-6)
    day = np.empty(4 * len(me.vertices), np.float32)
    me.color_attributes["daylight"].data.foreach_get("color", day)
    assert np.allclose(day.reshape(-1, 4)[:, 0], bk.parts[0].daylight, atol=1e-6)
    uv = np.empty(2 * len(me.loops), np.float32)
    me.uv_layers["UVMap"].data.foreach_get("uv", uv)
    assert np.allclose(uv.reshape(-1, 2), bk.parts[0].uvs)
    g = bpy.data.node_groups[BB.GROUP]
    assert g.nodes["Hours"].outputs[0].default_value == pytest.approx(21.5)
    BB.set_hours(26.0)
    assert g.nodes["Hours"].outputs[0].default_value == pytest.approx(2.0)
    for m in me.materials:
        assert any(n.type == "GROUP" and n.node_tree == g for n in m.node_tree.nodes)
        tex = [n for n in m.node_tree.nodes if n.type == "TEX_IMAGE"][0]
        assert tex.interpolation == "Closest" and tex.extension == "REPEAT"
        assert tex.image.packed_file is not None
    water = bpy.data.materials["voxel_water"]
    assert water.surface_render_method == "BLENDED"
    leaves = bpy.data.materials["voxel_leaves"].node_tree
    assert any(n.type == "MATH" and n.operation == "ROUND" for n in leaves.nodes)
    # the texture really is the block's texture (rows flipped to Blender's bottom-up)
    from voxel_addon import textures
    img = bpy.data.images["voxel_grass_side"]
    px = np.empty(16 * 16 * 4, np.float32)
    img.pixels.foreach_get(px)
    got = np.rint(px.reshape(16, 16, 4)[::-1] * 255).astype(np.uint8)
    assert np.array_equal(got, textures.image("grass_side")[0])


def test_cli_bake(small_world, validate, tmp_path):
    out = tmp_path / "cli.glb"
    env = dict(os.environ, PYTHONPATH=ROOT)
    r = subprocess.run(python_cmd("-m", "voxel_addon", "bake", "--world", str(small_world),
                        "--region", "0", "0", "16", "16", "--out", str(out), "--time", "22:00"),
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.strip().splitlines() == [str(out)]   # the exporter's log stays off stdout
    assert validate(out)["issues"]["numErrors"] == 0
    for bad, msg in ((["--region", "5", "0", "5", "9"], "empty region"),
                     (["--region", "0", "0", "4", "4", "--time", "25:99"], ""),
                     (["--region", "0", "0", "4", "4", "--world", str(tmp_path / "no.sqlite")],
                      "does not exist"),
                     (["--region", "0", "0", "4", "4", "--out", "/proc/no/b.glb"], "cannot create folder")):
        args = ["--world", str(small_world), "--out", str(tmp_path / "b.glb")] + bad
        r = subprocess.run(python_cmd("-m", "voxel_addon", "bake", *args), cwd=ROOT,
                           env=env, capture_output=True, text=True, timeout=120)
        assert r.returncode == 2, r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and msg in r.stderr
    assert not (tmp_path / "b.glb").exists()
