"""Bake section: region, one object per region, chunk or tile, light atlas or per
vertex, plants as instances, time of day of the baked light, bake to objects and
export .glb (SPEC F9, F10). Both run the import's job (blender/job.py): modal from
the UI (status bar progress, Esc cancels), at once from scripts."""
from __future__ import annotations

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, IntProperty, IntVectorProperty,
                       StringProperty)

from ..job import ModalJob
from .importer import LIGHT, METHOD_ITEMS, PER, draw_options, job_for


def _hours_changed(self, context):
    if bpy.data.node_groups.get("Voxel Shade") is not None:
        from .. import bake
        bake.set_hours(self.hours)


class VoxelBakeSettings(bpy.types.PropertyGroup):
    region_min: IntVectorProperty(name="From", size=2, default=(-16, -16),
                                  description="First block column (X0, Y0), included")
    region_max: IntVectorProperty(name="To", size=2, default=(16, 16),
                                  description="Last block column (X1, Y1), excluded")
    per: EnumProperty(name="Objects", default="region", items=PER)
    tile: IntProperty(name="Tile", default=64, min=16, max=1024,
                      description="Blocks per side of one object (Objects: Per Tile)")
    method: EnumProperty(name="Merge", default="greedy", items=METHOD_ITEMS)
    light: EnumProperty(name="Light", default="atlas", items=LIGHT)
    instances: BoolProperty(name="Plants as Instances", default=False,
                            description="Plants as instances of one mesh per type")
    hours: FloatProperty(name="Time of Day", default=12.0, min=0.0, max=24.0,
                         update=_hours_changed,
                         description="Hours (0 midnight, 12 noon) of the baked light; animatable")
    glb_path: StringProperty(name="glTF", subtype="FILE_PATH", default="//voxels.glb")


def _job(context, style):
    s = context.scene.voxel_bake
    return job_for(context.scene.voxel.path, s, region=(*s.region_min, *s.region_max),
                   style=style)


class VOXEL_OT_bake(ModalJob, bpy.types.Operator):
    bl_idname = "voxel.bake"
    bl_label = "Bake to Objects"
    bl_description = "Bake the region into mesh objects with textures and baked light (Esc cancels)"
    bl_options = {"REGISTER", "UNDO"}

    def make_job(self, context):
        return _job(context, "blender")

    def invoke(self, context, event):
        return self.start(context)


class VOXEL_OT_generate(ModalJob, bpy.types.Operator):
    bl_idname = "voxel.generate"
    bl_label = "Generate Region"
    bl_description = ("Generate and store the region's chunks in the world file, in steps "
                      "(Esc stops; what is generated stays)")

    def make_job(self, context):
        from ...core.errors import VoxelError
        from .. import session
        s = context.scene.voxel_bake
        world = session.world(context.scene.voxel.path)
        if getattr(world, "readonly", False):
            raise VoxelError("the world file is open read-only")
        from ..job import Job
        return Job(world, (*s.region_min, *s.region_max), build=False)

    def invoke(self, context, event):
        return self.start(context)

    def finish(self, context, job):
        self.report({"INFO"}, f"generated {job.generated} chunks")


class VOXEL_OT_export_glb(ModalJob, bpy.types.Operator):
    bl_idname = "voxel.export_glb"
    bl_label = "Export .glb"
    bl_description = "Bake the region and export it as glTF binary (light at the time of day)"

    def make_job(self, context):
        return _job(context, "gltf")

    def invoke(self, context, event):
        return self.start(context)

    def finish(self, context, job):
        from .. import bake as BB
        s = context.scene.voxel_bake
        path = bpy.path.abspath(s.glb_path)
        try:
            BB.export_glb(path, job.objects, instances=s.instances)
        except Exception as e:  # noqa: BLE001 - a full disk or read-only folder: one line
            from .. import session
            if not session.refused(self, e, path, kept="the file there before is unchanged"):
                raise
            return {"CANCELLED"}
        finally:  # the export copy is temporary: the scene keeps only explicit bakes
            job.cancel()
        self.report({"INFO"}, f"wrote {path}")
        return None


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
        draw_options(col, s)
        col.operator(VOXEL_OT_generate.bl_idname, icon="WORLD")
        col.operator(VOXEL_OT_bake.bl_idname, icon="MESH_CUBE")
        col.separator()
        col.prop(s, "glb_path")
        col.operator(VOXEL_OT_export_glb.bl_idname, icon="EXPORT")


CLASSES = [VoxelBakeSettings, VOXEL_OT_generate, VOXEL_OT_bake, VOXEL_OT_export_glb,
           VOXEL_PT_bake]
SCENE_PROPS = {"voxel_bake": VoxelBakeSettings}
