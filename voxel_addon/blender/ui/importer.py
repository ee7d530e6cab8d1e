"""File › Import › Voxel World (.sqlite): a region of a world file as baked objects,
run as a modal job (blender/job.py) after the file browser; the region mode and
bake options sit in the file browser's side panel."""
from __future__ import annotations

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, IntProperty,
                       IntVectorProperty, StringProperty)
from bpy_extras.io_utils import ImportHelper

from ...meshing import METHODS
from ..job import FileJob, Job, region_of_mode

MODES = [("region", "Region", "The block columns [X0, X1) × [Y0, Y1) below"),
         ("origin", "Around the Origin", "A square of Size × Size blocks centred on (0, 0)"),
         ("generated", "Generated Chunks", "Every chunk the file already holds")]
PER = [("region", "One Object", "A single mesh object"),
       ("chunk", "Per Chunk", "An object per 16×16 chunk"),
       ("tile", "Per Tile", "An object per Tile × Tile blocks (big regions)")]
METHOD_ITEMS = [(m, m.replace("_", " ").title(), f"face aggregation: {m}") for m in METHODS]
LIGHT = [("atlas", "Atlas", "Light in a texture on a second UV set; merged quads stay whole"),
         ("vertex", "Per Vertex", "Light in colour attributes (quads split where it varies)")]


class IMPORT_SCENE_OT_voxel_world(FileJob, bpy.types.Operator, ImportHelper):
    bl_idname = "import_scene.voxel_world"
    bl_label = "Import Voxel World"
    bl_description = "Bake a region of a voxel world file into mesh objects"
    bl_options = {"REGISTER", "UNDO"}

    filename_ext = ".sqlite"
    filter_glob: StringProperty(default="*.sqlite;*.db", options={"HIDDEN"})
    mode: EnumProperty(name="Area", items=MODES, default="region")
    region: IntVectorProperty(name="Region", size=4, default=(-32, -32, 32, 32),
                              description="X0, Y0, X1, Y1 (X1, Y1 excluded)")
    size: IntProperty(name="Size", default=64, min=1, max=4096)
    per: EnumProperty(name="Objects", items=PER, default="chunk")
    tile: IntProperty(name="Tile", default=64, min=16, max=1024)
    light: EnumProperty(name="Light", items=LIGHT, default="atlas")
    method: EnumProperty(name="Merge", default="greedy", items=METHOD_ITEMS)
    instances: BoolProperty(name="Plants as Instances", default=False)
    hours: FloatProperty(name="Time of Day", default=12.0, min=0.0, max=24.0)

    def draw(self, context):
        col = self.layout.column()
        col.prop(self, "mode")
        if self.mode == "region":
            col.prop(self, "region")
        elif self.mode == "origin":
            col.prop(self, "size")
        draw_options(col, self)

    def make_job(self, context) -> Job:
        return job_for(self.filepath, self, mode=self.mode, region=self.region, size=self.size)


def job_for(path, s, *, mode="region", region=None, size=64, style="blender", generate=True):
    """The Job for world file `path` with the bake settings of `s` (the import
    operator or the scene's Bake settings)."""
    from .. import session
    world = session.world(path)
    box = region_of_mode(world, mode, region, size)
    return Job(world, box, per=s.per, method=s.method, instances=s.instances, light=s.light,
               style=style, hours=s.hours, tile=getattr(s, "tile", 64), generate=generate)


def menu_import(self, context):
    self.layout.operator(IMPORT_SCENE_OT_voxel_world.bl_idname, text="Voxel World (.sqlite)")


CLASSES = [IMPORT_SCENE_OT_voxel_world]
MENUS = {"TOPBAR_MT_file_import": menu_import}


def draw_options(col, owner) -> None:
    """The bake options shared by File › Import and the Bake panel (owner: the
    operator or scene.voxel_bake)."""
    col.prop(owner, "per")
    if owner.per == "tile":
        col.prop(owner, "tile")
    col.prop(owner, "light")
    col.prop(owner, "method")
    col.prop(owner, "instances")
    col.prop(owner, "hours")
