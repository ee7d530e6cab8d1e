"""Frame World: the 3D view looks at the open world's surface (View menu and the
View panel; firstview.py does the work)."""
from __future__ import annotations

import bpy


def _target(world) -> tuple[float, float] | None:
    """The origin, or the middle of the generated chunks when the origin's is not one
    of them (a world generated elsewhere); None: the origin."""
    keys = set(world.file.chunk_keys())
    # the origin's chunk made but not in the file yet counts too (in memory, or evicted
    # and being written): which of the live view's chunks reached the file first is
    # a matter of timing
    with world.locked():
        made = (0, 0) in world.chunks or (0, 0) in getattr(world, "_saving", ())
    if not keys or made or (0, 0) in keys:
        return None
    xs, ys = zip(*keys)
    return ((min(xs) + max(xs) + 1) * 8.0, (min(ys) + max(ys) + 1) * 8.0)


class VOXEL_OT_frame_world(bpy.types.Operator):
    bl_idname = "voxel.frame_world"
    bl_label = "Frame World"
    bl_description = "Look at the open world's surface from above (its origin)"
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return context.area is not None and context.area.type == "VIEW_3D"

    def execute(self, context):
        from .. import firstview, session
        from ...core.errors import VoxelError
        try:
            world = session.world(context.scene.voxel.path)
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        firstview.frame(world, context.space_data.region_3d, _target(world))
        context.area.tag_redraw()
        return {"FINISHED"}


def menu_view(self, context):
    self.layout.separator()
    self.layout.operator(VOXEL_OT_frame_world.bl_idname, icon="WORLD")


@bpy.app.handlers.persistent
def _new_file(*_):
    from .. import firstview
    firstview.forget()  # a world shown in the next file is shown for the first time


def register():
    bpy.app.handlers.load_pre.append(_new_file)


def unregister():
    from .. import firstview
    if _new_file in bpy.app.handlers.load_pre:
        bpy.app.handlers.load_pre.remove(_new_file)
    firstview.forget()


CLASSES = [VOXEL_OT_frame_world]
MENUS = {"VIEW3D_MT_view": menu_view}
