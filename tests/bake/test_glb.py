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


def _python(*args):
    """`python ARGS` in this test's kind of host (tests.host once the real-Blender
    layer has it: inside Blender, sys.executable cannot import bpy)."""
    try:
        from tests.host import python_cmd
    except ImportError:
        import sys
        return [sys.executable, *map(str, args)]
    return python_cmd(*args)


def _triangles(bpy, objs):
    n = 0
    for o in objs:
        if o.type == "MESH":
            n += sum(len(p.vertices) - 2 for p in o.data.polygons)
    return n


def _export(bpy, BB, objs, out, capfd, instances=False):
    """Export and return the exporter's warnings and errors about the scene (its log
    lines "HH:MM:SS | WARNING: ..."; not a distro's note that Draco is missing)."""
    capfd.readouterr()
    BB.export_glb(out, objs, instances=instances)
    log = capfd.readouterr()
    return [ln for ln in (log.out + log.err).splitlines()
            if "| WARNING" in ln or "| ERROR" in ln]


@pytest.mark.parametrize("per,instances,light", [("region", False, "atlas"),
                                                 ("chunk", True, "atlas"),
                                                 ("region", False, "vertex")])
def test_glb_validates_and_reimports(bpy, small_world, validate, tmp_path, capfd, per, instances,
                                     light):
    from voxel_addon.bake import glb
    from voxel_addon.blender import bake as BB
    bk = _baked(small_world, per=per, instances=instances, light=light)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="gltf", hours=20.0)
    assert len([o for o in objs if o.name.startswith(("chunk_", "voxels_"))]) == len(bk.parts)
    out = tmp_path / "x.glb"
    assert _export(bpy, BB, objs, out, capfd, instances) == []  # no exporter warnings
    rep = validate(out)
    assert rep["issues"]["numErrors"] == 0, rep["issues"]["messages"][:5]
    assert rep["issues"]["numWarnings"] == 0, rep["issues"]["messages"][:5]
    assert rep["info"]["hasTextures"]
    doc, _ = glb.read(out)
    mats = {m["name"]: m for m in doc["materials"]}
    assert mats["voxel_leaves_gltf"]["alphaMode"] == "MASK"
    assert mats["voxel_water_gltf"]["alphaMode"] == "BLEND"
    assert "alphaMode" not in mats["voxel_stone_gltf"]
    prims = [p for me in doc["meshes"] if not me["name"].startswith("plant_")
             for p in me["primitives"]]
    attrs = {k for p in prims for k in p["attributes"]}
    if light == "atlas":  # light on TEXCOORD_1 as the occlusion map, no vertex colours
        assert "TEXCOORD_1" in attrs and not any(k.startswith("COLOR") for k in attrs)
        used = {doc["materials"][p["material"]]["name"] for p in prims}
        assert all(mats[n]["occlusionTexture"]["texCoord"] == 1 for n in used)
        for n in used:  # the atlas is sampled without mipmaps (no bleeding between patches)
            tex = doc["textures"][mats[n]["occlusionTexture"]["index"]]
            assert doc["samplers"][tex["sampler"]]["minFilter"] == 9729
    else:
        assert attrs >= {"COLOR_0", "TEXCOORD_0"} and "TEXCOORD_1" not in attrs
        assert "COLOR_1" not in attrs  # only the colours the material uses
    # glowing blocks keep their emission (texture glow mask x strength)
    assert mats["voxel_lamp_red_gltf"]["emissiveFactor"] == [1, 1, 1]
    assert mats["voxel_ore_gltf"]["emissiveFactor"] == pytest.approx([0.6] * 3)
    if instances:
        assert "EXT_mesh_gpu_instancing" in doc["extensionsUsed"]
        inst = [n for n in doc["nodes"] if "EXT_mesh_gpu_instancing" in n.get("extensions", {})]
        assert len(inst) == sum(len(v) > 1 for v in bk.plants.values()) >= 2
    mesh_tris = bk.triangles
    if not instances:
        assert rep["info"]["totalTriangleCount"] == mesh_tris
    exported = {m.name for o in objs if o.type == "MESH" for m in o.data.materials
                if o.name.startswith(("chunk_", "voxels_", "plant_"))}
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
    assert mats == exported  # same materials back
    assert {"voxel_lamp_red_gltf", "voxel_leaves_gltf", "voxel_water_gltf"} <= mats
    leaves = bpy.data.materials["voxel_leaves_gltf"]
    assert leaves.surface_render_method == "DITHERED" or leaves.blend_method in ("CLIP", "HASHED")
    if light == "vertex":
        assert any(a.name.lower().startswith("color") or a.name == "shade"
                   for o in imported for a in o.data.color_attributes)
    else:
        assert all(len(o.data.uv_layers) == 2 for o in imported
                   if o.name.startswith(("chunk_", "voxels_")))


def test_emission_strength_above_one_is_kept(bpy, tmp_path, capfd):
    """A glow above 1 (brighter than lit) goes out as KHR_materials_emissive_strength."""
    from voxel_addon.bake import MaterialSpec, glb
    from voxel_addon.blender import bake as BB
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bk = bake.bake_blocks(_lamp(), light="vertex")
    spec = bk.materials[bk.parts[0].material[0]]
    bk.materials[bk.parts[0].material[0]] = MaterialSpec(spec.name, spec.texture, spec.layer,
                                                         spec.render, 4.0, spec.double_sided)
    objs = BB.build(bk, style="gltf")
    out = tmp_path / "glow.glb"
    assert _export(bpy, BB, objs, out, capfd) == []
    doc, _ = glb.read(out)
    m = [m for m in doc["materials"] if m["name"].startswith("voxel_lamp_red")][0]
    strength = m["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"]
    assert strength * max(m["emissiveFactor"]) == pytest.approx(4.0)
    assert "KHR_materials_emissive_strength" in doc["extensionsUsed"]


def _lamp():
    b = np.zeros((3, 3, 256), np.uint16, order="F")
    from voxel_addon.core.blocks import REGISTRY
    b[1, 1, 0] = REGISTRY.id("lamp_red")
    return b


def test_blender_objects_carry_light_and_time_of_day(bpy, small_world):
    from voxel_addon.blender import bake as BB
    bk = _baked(small_world, light="vertex")
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
    for m in me.materials:  # per-vertex light comes from the colour attributes
        attrs = {n.layer_name for n in m.node_tree.nodes if n.type == "VERTEX_COLOR"}
        assert attrs == {"light", "daylight"}
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
    rep = validate(out)
    assert rep["issues"]["numErrors"] == 0 and rep["issues"]["numWarnings"] == 0
    out2 = tmp_path / "cli_vertex.glb"
    r = subprocess.run(_python("-m", "voxel_addon", "bake", "--world", str(small_world),
                               "--region", "-20", "0", "20", "16", "--out", str(out2),
                               "--light", "vertex", "--per", "tile"),
                       cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    from voxel_addon.bake import glb
    doc, _ = glb.read(out2)
    assert [m["name"] for m in doc["meshes"]] == ["tile_-20_0"]  # one 64×64 tile
    attrs = {k for me in doc["meshes"] for p in me["primitives"] for k in p["attributes"]}
    assert "COLOR_0" in attrs and "TEXCOORD_1" not in attrs
    for bad, msg in ((["--region", "5", "0", "5", "9"], "empty region"),
                     (["--region", "0", "0", "4", "4", "--time", "25:99"], ""),
                     (["--region", "0", "0", "4", "4", "--world", str(tmp_path / "no.sqlite")],
                      "no world file"),
                     (["--region", "0", "0", "4", "4", "--out", "/proc/no/b.glb"], "cannot create folder")):
        args = ["--world", str(small_world), "--out", str(tmp_path / "b.glb")] + bad
        r = subprocess.run(python_cmd("-m", "voxel_addon", "bake", *args), cwd=ROOT,
                           env=env, capture_output=True, text=True, timeout=120)
        assert r.returncode == 2, r.stderr
        assert len(r.stderr.strip().splitlines()) == 1 and msg in r.stderr
    assert not (tmp_path / "b.glb").exists()


def test_blender_objects_read_the_light_atlas(bpy, small_world):
    """light="atlas": merged quads, a second UV set, the float atlas image (RGB block
    light, A daylight) feeding the shared Voxel Shade group; Hours still mixes."""
    from voxel_addon.blender import bake as BB
    bk = _baked(small_world)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="blender", hours=6.0)
    me = objs[0].data
    assert len(me.polygons) == bk.parts[0].quads and not me.color_attributes
    uv = np.empty(2 * len(me.loops), np.float32)
    me.uv_layers[BB.LIGHT_UV].data.foreach_get("uv", uv)
    assert np.allclose(uv.reshape(-1, 2), bk.parts[0].uv2)
    img = bpy.data.images[f"voxel_light_{bk.region[0]}_{bk.region[1]}"]
    H, W = bk.atlas.shape[:2]
    assert tuple(img.size) == (W, H) and img.is_float and img.alpha_mode == "CHANNEL_PACKED"
    px = np.empty(W * H * 4, np.float32)
    img.pixels.foreach_get(px)
    assert np.allclose(px.reshape(H, W, 4), bk.atlas, atol=1e-6)
    g = bpy.data.node_groups[BB.GROUP]
    for m in me.materials:
        nodes = m.node_tree.nodes
        grp = [n for n in nodes if n.type == "GROUP" and n.node_tree == g][0]
        src = {lk.to_socket.name: (lk.from_node.image, lk.from_socket.name)
               for lk in m.node_tree.links if lk.to_node == grp}
        assert src == {"Light": (img, "Color"), "Daylight": (img, "Alpha")}
        tex = [n for n in nodes if n.type == "TEX_IMAGE" and n.image == img][0]
        assert tex.interpolation == "Linear"
        uvn = tex.inputs["Vector"].links[0].from_node
        assert uvn.uv_map == BB.LIGHT_UV
    assert g.nodes["Hours"].outputs[0].default_value == pytest.approx(6.0)
