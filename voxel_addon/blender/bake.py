"""Bake results (voxel_addon.bake) -> Blender objects, materials and packed textures.

    objects = build(bk, style="blender"|"gltf", collection=None, hours=12.0)
    build_steps(...)  # the same as a generator of short steps (modal operators)
    export_glb(path, objects, instances=False)
    glb_bytes(bk, hours=12.0, instances=False)  # a fresh scene -> .glb bytes (tiles)

Materials (one per bake.MaterialSpec and light source): Principled BSDF, Base Color
from the block texture (Closest, REPEAT), alpha clip (Round) for alpha_test, blended
alpha for blend, the texture's glow mask as an emission texture for glowing blocks.
The light comes from the bake's light atlas (an image on the "LightUV" UV set,
Linear) or, for light="vertex", from colour attributes.
- style "blender": baked light stays live data. Emission = texture × the shared
  "Voxel Shade" node group, which mixes block light and daylight by the time of
  day: the group's "Hours" value node (one for all materials; set it with
  set_hours() or keyframe it) goes from day to night without re-baking. Use a
  dark world for the thesis's look.
- style "gltf": what glTF can carry, with no exporter warning: atlas -> the light
  factor at `hours` as the occlusion map on TEXCOORD_1 (glTF has no coloured light
  map: its brightest channel); vertex -> Base Color = texture × the `shade` colour
  attribute (COLOR_0, exact colour). Emissive texture × glow (strength above 1 as
  KHR_materials_emissive_strength); alpha modes written after export (bake.glb).
"""
from __future__ import annotations

import threading

import bpy
import numpy as np

from . import compat
from .nodes import GROUP, gltf_group, image, linear, node, op, set_hours, shade_group, sprite

# ---------------------------------------------------------------- materials

LIGHT_UV = "LightUV"


def light_images(bk, style: str, hours: float = 12.0):
    """The bake's light atlas as an image (None for light="vertex"): float RGBA
    (RGB block light, A daylight) for style "blender"; for "gltf" the light factor
    at `hours` as 8-bit grey (its brightest channel: glTF's occlusion map has one)."""
    from .. import bake as B
    if bk.atlas is None:
        return None
    x0, y0 = bk.region[:2]
    H, W = bk.atlas.shape[:2]
    if style == "blender":
        img = bpy.data.images.new(f"voxel_light_{x0}_{y0}", W, H, alpha=True, float_buffer=True)
        img.alpha_mode = "CHANNEL_PACKED"  # A is daylight, not coverage
        px = bk.atlas
        img.file_format = "OPEN_EXR"
    else:
        img = bpy.data.images.new(f"voxel_shade_{x0}_{y0}", W, H, alpha=False)
        grey = B.shade_atlas(bk, hours).max(axis=2)
        px = np.concatenate([np.repeat(grey[..., None], 3, 2), np.ones((H, W, 1), np.float32)], 2)
        img.file_format = "PNG"
    img.colorspace_settings.name = "Non-Color"
    img.pixels.foreach_set(np.ascontiguousarray(px, np.float32).ravel())
    if style == "blender":  # kept in the .blend; the glTF copy is encoded by the exporter
        img.pack()
    return img


def material(spec, style: str, light=None, images=None) -> bpy.types.Material:
    """The material of `spec`; `light` is the bake's light atlas image (light_images)
    or None when light travels in colour attributes; `images` the bake's sprites."""
    key = f"{spec.name}|{style}|{light.name if light is not None else '-'}"
    for m in bpy.data.materials:
        if m.get("voxel_key") == key:
            return m
    m = bpy.data.materials.new(f"voxel_{spec.name}" + ("" if style == "blender" else f"_{style}"))
    m["voxel_key"] = key
    t = compat.node_tree(m)
    t.nodes.clear()
    out = node(t, "ShaderNodeOutputMaterial", 900, 0)
    bsdf = node(t, "ShaderNodeBsdfPrincipled", 500, 0)
    t.links.new(bsdf.outputs[0], out.inputs["Surface"])
    bsdf.inputs["Roughness"].default_value = 0.9
    uv = node(t, "ShaderNodeUVMap", -700, 0, uv_map="UVMap")
    img = sprite(spec.image, images[spec.image]) if spec.image \
        else image(spec.texture)
    tex = node(t, "ShaderNodeTexImage", -450, 100, image=img,
                interpolation="Closest", extension="REPEAT")
    t.links.new(uv.outputs[0], tex.inputs[0])
    colour = tex.outputs["Color"]
    if spec.tint is not None:  # a coloured voxel: its colour times the neutral tile
        mul = node(t, "ShaderNodeMix", -150, 300, data_type="RGBA", blend_type="MULTIPLY")
        mul.inputs["Factor"].default_value = 1.0
        t.links.new(colour, mul.inputs[6])
        mul.inputs[7].default_value = (*(linear(c) for c in spec.tint), 1.0)
        colour = mul.outputs[2]
    if light is not None:
        luv = node(t, "ShaderNodeUVMap", -700, -350, uv_map=LIGHT_UV)
        ltex = node(t, "ShaderNodeTexImage", -450, -350, image=light,
                     interpolation="Linear", extension="EXTEND")
        t.links.new(luv.outputs[0], ltex.inputs[0])
    if style == "gltf":
        if light is None:
            attr = node(t, "ShaderNodeVertexColor", -450, -200, layer_name="shade")
            mul = node(t, "ShaderNodeMix", 100, 200, data_type="RGBA", blend_type="MULTIPLY")
            mul.inputs["Factor"].default_value = 1.0
            t.links.new(colour, mul.inputs[6])
            t.links.new(attr.outputs["Color"], mul.inputs[7])
            t.links.new(mul.outputs[2], bsdf.inputs["Base Color"])
        else:
            t.links.new(colour, bsdf.inputs["Base Color"])
            sep = node(t, "ShaderNodeSeparateColor", -150, -350)
            t.links.new(ltex.outputs["Color"], sep.inputs[0])
            grp = node(t, "ShaderNodeGroup", 500, -450, node_tree=gltf_group())
            t.links.new(sep.outputs[0], grp.inputs["Occlusion"])
    else:
        t.links.new(colour, bsdf.inputs["Base Color"])
        grp = node(t, "ShaderNodeGroup", -150, -250, node_tree=shade_group())
        if light is None:
            for i, name in enumerate(("light", "daylight")):
                attr = node(t, "ShaderNodeVertexColor", -450, -250 - 150 * i, layer_name=name)
                t.links.new(attr.outputs["Color"], grp.inputs[i])
        else:
            t.links.new(ltex.outputs["Color"], grp.inputs["Light"])
            t.links.new(ltex.outputs["Alpha"], grp.inputs["Daylight"])
        emi = node(t, "ShaderNodeMix", 100, -200, data_type="RGBA", blend_type="MULTIPLY")
        emi.inputs["Factor"].default_value = 1.0
        t.links.new(colour, emi.inputs[6])
        t.links.new(grp.outputs[0], emi.inputs[7])
        glow_sock = emi.outputs[2]
    if spec.glow > 0:
        gtex = node(t, "ShaderNodeTexImage", -450, -650, image=image(spec.texture, "glow"),
                     interpolation="Closest", extension="REPEAT")
        t.links.new(uv.outputs[0], gtex.inputs[0])
        if style == "gltf":
            t.links.new(gtex.outputs["Color"], bsdf.inputs["Emission Color"])
            bsdf.inputs["Emission Strength"].default_value = spec.glow
        else:
            add = node(t, "ShaderNodeMix", 300, -350, data_type="RGBA", blend_type="ADD")
            add.inputs["Factor"].default_value = spec.glow
            t.links.new(glow_sock, add.inputs[6])
            t.links.new(gtex.outputs["Color"], add.inputs[7])
            glow_sock = add.outputs[2]
    if style != "gltf":
        t.links.new(glow_sock, bsdf.inputs["Emission Color"])
        bsdf.inputs["Emission Strength"].default_value = 1.0
    if style == "gltf":  # export_glb writes alphaMode (see bake.glb: no exporter warning)
        m["voxel_alpha"] = {"alpha_test": "MASK", "blend": "BLEND"}.get(spec.render, "OPAQUE")
    elif spec.render == "alpha_test":
        rnd = op(t, "ROUND", tex.outputs["Alpha"], None, 200, -600)
        t.links.new(rnd, bsdf.inputs["Alpha"])
    elif spec.render == "blend":
        t.links.new(tex.outputs["Alpha"], bsdf.inputs["Alpha"])
    if spec.render == "blend":
        m.surface_render_method = "BLENDED"
    m.use_backface_culling = not spec.double_sided
    return m


# ---------------------------------------------------------------- meshes

def mesh(part, materials: list, style: str, hours: float = 12.0) -> bpy.types.Mesh:
    from .. import bake as B
    n = part.quads
    me = bpy.data.meshes.new(part.name)
    me.vertices.add(4 * n)
    me.vertices.foreach_set("co", part.positions.ravel())
    me.loops.add(4 * n)
    me.loops.foreach_set("vertex_index", np.arange(4 * n, dtype=np.int32))
    me.polygons.add(n)
    me.polygons.foreach_set("loop_start", np.arange(0, 4 * n, 4, dtype=np.int32))
    used = np.unique(part.material)
    for i in used:
        me.materials.append(materials[i])
    local = np.searchsorted(used, part.material).astype(np.int32)
    me.polygons.foreach_set("material_index", local)
    me.update(calc_edges=True)
    uv = me.uv_layers.new(name="UVMap")
    uv.data.foreach_set("uv", part.uvs.ravel())
    if part.uv2 is not None:  # the light lives in the atlas: no colour attributes
        me.uv_layers.new(name=LIGHT_UV).data.foreach_set("uv", part.uv2.ravel())
        return me
    one = np.ones((4 * n, 1), np.float32)
    if style == "gltf":  # only what the material uses (the exporter writes every one)
        cols = {"shade": B.shade(part, hours)}
    else:
        cols = {"light": part.light, "daylight": np.repeat(part.daylight[:, None], 3, 1)}
    for name, rgb in cols.items():
        a = me.color_attributes.new(name, "FLOAT_COLOR", "POINT")
        a.data.foreach_set("color", np.hstack([rgb, one]).ravel())
    me.color_attributes.active_color_index = 0
    me.color_attributes.render_color_index = 0
    return me


def build(bk, *, style: str = "blender", collection=None, hours: float = 12.0,
          progress=None) -> list:
    """Objects for every part of `bk` (a bake.Bake), linked into `collection`
    (default: a new "Voxel Bake" collection in the current scene)."""
    gen = build_steps(bk, style=style, collection=collection, hours=hours)
    while True:
        try:
            stage, frac = next(gen)
        except StopIteration as stop:
            return stop.value
        if progress:
            progress(stage, frac)


def build_steps(bk, *, style: str = "blender", collection=None, hours: float = 12.0,
                link: bool = True):
    """build() as a generator of short steps (yields (stage, fraction), returns the
    objects). With link=False a new collection is left out of the scene (the caller
    links it when everything is made, so a cancelled build shows nothing)."""
    if style not in ("blender", "gltf"):
        raise ValueError("style must be 'blender' or 'gltf'")
    if collection is None:
        collection = bpy.data.collections.new("Voxel Bake")
        if link:
            bpy.context.scene.collection.children.link(collection)
    light = light_images(bk, style, hours)
    mats = [material(s, style, None if s.per_vertex else light,
                     bk.images) for s in bk.materials]
    objs = []
    for i, part in enumerate(bk.parts):
        yield "objects", i / max(len(bk.parts), 1)
        ob = bpy.data.objects.new(part.name, mesh(part, mats, style, hours))
        collection.objects.link(ob)
        objs.append(ob)
    if bk.plants:
        objs += plants(bk, style, collection, hours)
    if style == "blender":
        set_hours(hours)
    return objs


def plants(bk, style, collection, hours) -> list:
    """Plants as instances: per plant type a point object (one vertex per plant) that
    instances its prototype child on every vertex (instance_type VERTS; the point
    object itself is neither drawn nor exported as a mesh). The glTF exporter writes
    them as EXT_mesh_gpu_instancing."""
    from .. import bake as B
    from ..core.blocks import REGISTRY
    out = []
    for name, xyz in bk.plants.items():
        one = np.zeros((1, 1, 256), np.uint16)
        one[0, 0, 0] = REGISTRY.id(name)
        pb = B.bake_blocks(one, per="region", light="vertex")
        pr = pb.parts[0]
        pr.daylight[:] = 1.0  # instances share one mesh: lit as in open sky
        pr.name = f"plant_{name}"
        proto = bpy.data.objects.new(pr.name, mesh(pr, [material(s, style) for s in pb.materials],
                                                   style, hours))
        pts = bpy.data.meshes.new(f"plants_{name}")
        pts.vertices.add(len(xyz))
        pts.vertices.foreach_set("co", xyz.astype(np.float32).ravel())
        ob = bpy.data.objects.new(f"plants_{name}", pts)
        ob.instance_type = "VERTS"
        ob.show_instancer_for_render = False
        ob.show_instancer_for_viewport = False
        collection.objects.link(ob)
        collection.objects.link(proto)
        proto.parent = ob
        out += [ob, proto]
    return out


def far_material(water: bool, style: str) -> bpy.types.Material:
    """The far levels' one material (two with water): Base Color from the per-vertex
    colour "far" (albedo, times the light at the bake's hour for style "gltf")."""
    name = f"voxel_far{'_water' if water else ''}_{style}"
    m = bpy.data.materials.get(name)
    if m is not None:
        return m
    m = bpy.data.materials.new(name)
    t = compat.node_tree(m)
    t.nodes.clear()
    out = node(t, "ShaderNodeOutputMaterial", 600, 0)
    bsdf = node(t, "ShaderNodeBsdfPrincipled", 300, 0)
    t.links.new(bsdf.outputs[0], out.inputs["Surface"])
    bsdf.inputs["Roughness"].default_value = 0.9
    attr = node(t, "ShaderNodeVertexColor", 0, 0, layer_name="far")
    t.links.new(attr.outputs["Color"], bsdf.inputs["Base Color"])
    if water:
        bsdf.inputs["Alpha"].default_value = 0.7
        m.surface_render_method = "BLENDED"
        if style == "gltf":
            m["voxel_alpha"] = "BLEND"
    return m


def far_objects(parts, *, style: str = "blender", collection=None, hours: float = 12.0) -> list:
    """One object per far level (bake.lod.FarPart) in `collection`."""
    from ..light import daytime, shade as eq41
    if collection is None:
        collection = bpy.data.collections.new("Voxel Far")
        bpy.context.scene.collection.children.link(collection)
    objs = []
    for fp in parts:
        albedo = np.where(fp.albedo <= 0.04045, fp.albedo / 12.92,
                          ((fp.albedo + 0.055) / 1.055) ** 2.4).astype(np.float32)
        if style == "gltf":   # open sky, no block light: eq. 4.1 at the hour
            n = len(albedo)
            albedo = np.clip(eq41(albedo, np.zeros((n, 3), np.float32), np.zeros(n, np.float32),
                                  np.ones(n, np.float32), fp.normals, daytime.at(hours)), 0, 1)
        tris = np.concatenate([fp.ground, fp.water]).astype(np.int32)
        me = bpy.data.meshes.new(fp.name)
        me.vertices.add(len(fp.positions))
        me.vertices.foreach_set("co", fp.positions.astype(np.float32).ravel())
        me.loops.add(3 * len(tris))
        me.loops.foreach_set("vertex_index", tris.ravel())
        me.polygons.add(len(tris))
        me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(tris), 3, dtype=np.int32))
        me.materials.append(far_material(False, style))
        if len(fp.water):
            me.materials.append(far_material(True, style))
            idx = np.r_[np.zeros(len(fp.ground), np.int32), np.ones(len(fp.water), np.int32)]
            me.polygons.foreach_set("material_index", idx)
        me.update(calc_edges=True)
        a = me.color_attributes.new("far", "FLOAT_COLOR", "POINT")
        a.data.foreach_set("color", np.hstack([albedo, np.ones((len(albedo), 1))]).astype(
            np.float32).ravel())
        ob = bpy.data.objects.new(fp.name, me)
        collection.objects.link(ob)
        objs.append(ob)
    return objs


def export_glb(path, objects, *, instances: bool = False) -> None:
    """Write `objects` (and nothing else) through Blender's glTF exporter, then the
    alpha modes and atlas samplers (bake.glb.touch_up). Written beside PATH and moved
    over it when whole: a full disk leaves the previous file as it was, no half .glb.
    A failure to write is an OSError (the exporter's RuntimeError carries only text)."""
    import os
    import re
    from ..bake import glb
    for ob in bpy.context.view_layer.objects:
        ob.select_set(False)
    for ob in objects:
        ob.select_set(True)
    from ..core.errors import VoxelError
    path = os.fspath(path)
    if not path or os.path.isdir(path):
        raise VoxelError(f"{path or 'no path'} is not a file name: give the .glb a name")
    part = os.path.join(os.path.dirname(path), f".{os.path.basename(path)}.{os.getpid()}.part.glb")
    try:
        try:
            bpy.ops.export_scene.gltf(filepath=part, export_format="GLB", use_selection=True,
                                      export_vertex_color="MATERIAL",
                                      export_gpu_instances=instances, export_apply=True,
                                      export_yup=True)
        except RuntimeError as e:
            m = re.search(r"\[Errno (\d+)\] ([^\n]*)", str(e))
            if m is None:
                raise
            raise OSError(int(m[1]), m[2], path) from None
        modes = {m.name: m["voxel_alpha"] for m in bpy.data.materials
                 if m.get("voxel_alpha", "OPAQUE") != "OPAQUE"}
        glb.touch_up(part, modes, plain="voxel_shade_")
        os.replace(part, path)
    finally:
        if os.path.exists(part):
            os.remove(part)


_LOCK = threading.Lock()  # bpy is one state per process: one bake at a time


def glb_bytes(bk, *, hours: float = 12.0, instances: bool = False) -> bytes | None:
    """`bk` (style "gltf") as the bytes of a self-contained .glb, built in a fresh empty
    scene so the bytes do not depend on what this process baked before (a cluster
    worker's tile equals the one-process run's); None when the bake has no objects.
    Safe from worker threads: calls are serialised."""
    import contextlib
    import io
    import os
    import tempfile
    with _LOCK:
        bpy.ops.wm.read_factory_settings(use_empty=True)
        objs = build(bk, style="gltf", hours=hours)
        if not objs:
            return None
        with tempfile.TemporaryDirectory(prefix="voxel_glb_") as d:
            path = os.path.join(d, "bake.glb")
            # the exporter logs INFO lines to stdout
            with contextlib.redirect_stdout(io.StringIO()):
                export_glb(path, objs, instances=instances)
            with open(path, "rb") as f:
                return f.read()
