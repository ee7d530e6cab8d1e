"""Bake section: region, one object per chunk or per region, plants as instances,
time of day of the baked light, bake to objects and export .glb (SPEC F9, F10)."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntVectorProperty, StringProperty


def _hours_changed(self, context):
    if bpy.data.node_groups.get("Voxel Shade") is not None:
        from .. import bake
        bake.set_hours(self.hours)


class VoxelBakeSettings(bpy.types.PropertyGroup):
    region_min: IntVectorProperty(name="From", size=2, default=(-16, -16),
                                  description="First block column (X0, Y0), included")
    region_max: IntVectorProperty(name="To", size=2, default=(16, 16),
                                  description="Last block column (X1, Y1), excluded")
    per: EnumProperty(name="Objects", default="region",
                      items=[("region", "One per Region", "A single mesh object"),
                             ("chunk", "One per Chunk", "An object per 16×16 chunk")])
    method: EnumProperty(name="Merge", default="greedy",
                         items=[(m, m.replace("_", " ").title(), f"face aggregation: {m}")
                                for m in ("none", "lines", "squares", "squares_ext", "greedy")])
    light: EnumProperty(name="Light", default="atlas",
                        items=[("atlas", "Atlas", "Light in a texture on a second UV set; "
                                "merged quads stay whole"),
                               ("vertex", "Per Vertex", "Light in colour attributes; quads "
                                "split where light varies (tools without a second UV set)")])
    instances: BoolProperty(name="Plants as Instances", default=False,
                            description="Plants as instances of one mesh per type")
    hours: FloatProperty(name="Time of Day", default=12.0, min=0.0, max=24.0,
                         update=_hours_changed,
                         description="Hours (0 midnight, 12 noon) of the baked light; animatable")
    glb_path: StringProperty(name="glTF", subtype="FILE_PATH", default="//voxels.glb")


def _region(s):
    return (*s.region_min, *s.region_max)


def _progress(context):
    wm = context.window_manager
    wm.progress_begin(0, 100)

    def say(stage, frac):
        wm.progress_update(int(100 * frac))
    return say, wm.progress_end


def _bake(op, context, style):
    from .. import bake as BB, session
    from ... import bake
    from ...core.errors import VoxelError
    s, w = context.scene.voxel_bake, context.scene.voxel
    say, end = _progress(context)
    try:
        world = session.world(w.path)
        bk = bake.bake_world(world, *_region(s), per=s.per, method=s.method,
                             instances=s.instances, light=s.light, progress=say)
        return BB.build(bk, style=style, hours=s.hours, progress=say), bk
    except VoxelError as e:
        op.report({"ERROR"}, str(e))
        return None, None
    finally:
        end()


class VOXEL_OT_bake(bpy.types.Operator):
    bl_idname = "voxel.bake"
    bl_label = "Bake to Objects"
    bl_description = "Bake the region into mesh objects with textures and light attributes"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        objs, bk = _bake(self, context, "blender")
        if objs is None:
            return {"CANCELLED"}
        self.report({"INFO"}, f"baked {len(objs)} objects, {bk.triangles} triangles")
        return {"FINISHED"}


class VOXEL_OT_export_glb(bpy.types.Operator):
    bl_idname = "voxel.export_glb"
    bl_label = "Export .glb"
    bl_description = "Bake the region and export it as glTF binary (light at the time of day)"

    def execute(self, context):
        from .. import bake as BB
        s = context.scene.voxel_bake
        objs, _ = _bake(self, context, "gltf")
        if objs is None:
            return {"CANCELLED"}
        path = bpy.path.abspath(s.glb_path)
        coll = objs[0].users_collection[0] if objs else None
        try:
            BB.export_glb(path, objs, instances=s.instances)
        finally:  # the export copy is temporary: the scene keeps only explicit bakes
            _remove(objs, coll)
        self.report({"INFO"}, f"wrote {path}")
        return {"FINISHED"}


def _remove(objs, coll):
    meshes = {o.data for o in objs if o.data is not None}
    for o in objs:
        bpy.data.objects.remove(o)
    for m in meshes:
        if m.users == 0:
            bpy.data.meshes.remove(m)
    if coll is not None:
        for c in list(coll.children):
            for o in list(c.objects):
                bpy.data.objects.remove(o)
            bpy.data.collections.remove(c)
        bpy.data.collections.remove(coll)


class VOXEL_PT_bake(bpy.types.Panel):
    bl_idname = "VOXEL_PT_bake"
    bl_label = "Bake & Export"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Voxel"
    bl_order = 50

    def draw(self, context):
        s = context.scene.voxel_bake
        col = self.layout.column()
        col.prop(s, "region_min")
        col.prop(s, "region_max")
        col.prop(s, "per")
        col.prop(s, "method")
        col.prop(s, "light")
        col.prop(s, "instances")
        col.prop(s, "hours")
        col.operator(VOXEL_OT_bake.bl_idname, icon="MESH_CUBE")
        col.separator()
        col.prop(s, "glb_path")
        col.operator(VOXEL_OT_export_glb.bl_idname, icon="EXPORT")


CLASSES = [VoxelBakeSettings, VOXEL_OT_bake, VOXEL_OT_export_glb, VOXEL_PT_bake]
SCENE_PROPS = {"voxel_bake": VoxelBakeSettings}
