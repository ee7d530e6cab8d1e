"""voxel.report: puts a message into Blender's reports (the status bar shows it, the
Info editor keeps it) for code that runs outside an operator (session.tell)."""
from __future__ import annotations

import bpy
from bpy.props import EnumProperty, StringProperty


class VOXEL_OT_report(bpy.types.Operator):
    bl_idname = "voxel.report"
    bl_label = "Voxel Worlds Message"
    bl_options = {"INTERNAL"}

    kind: EnumProperty(items=[(k, k.title(), "") for k in ("INFO", "WARNING", "ERROR")],
                       default="ERROR")
    message: StringProperty()

    def execute(self, context):
        self.report({self.kind}, self.message)
        return {"FINISHED"}


CLASSES = [VOXEL_OT_report]
