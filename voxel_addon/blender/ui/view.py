"""View section: render the open world through the pipeline, from the scene camera,
on Blender's own GL context, into an image datablock (issue 6)."""
from __future__ import annotations

import math

import bpy

IMAGE = "Voxel View"


def camera_of(obj):
    """A render Camera at a Blender camera object (1 block = 1 unit, z up), and its
    vertical field of view in degrees."""
    from ...render import Camera
    m = obj.matrix_world
    f = -m.col[2].xyz.normalized()  # cameras look down their local -z
    yaw = math.degrees(math.atan2(f.y, f.x))
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, f.z))))
    p = m.translation
    return Camera(p.x, p.y, p.z, yaw, pitch), math.degrees(obj.data.angle_y)


class VOXEL_OT_render_view(bpy.types.Operator):
    bl_idname = "voxel.render_view"
    bl_label = "Render Voxel View"
    bl_description = ("Render the world from the scene camera with the voxel pipeline "
                      f"into the image '{IMAGE}' (time of day from Bake & Export)")

    def execute(self, context):
        from .. import offscreen, session
        from ...core.errors import VoxelError
        from ...render import Settings, source
        sc = context.scene
        try:
            if sc.camera is None or sc.camera.type != "CAMERA":
                raise VoxelError("the scene has no camera")
            cam, fov = camera_of(sc.camera)
            r = sc.render
            w = max(8, r.resolution_x * r.resolution_percentage // 100)
            h = max(8, r.resolution_y * r.resolution_percentage // 100)
            s = Settings(fov=fov)
            world = session.world(sc.voxel.path)
            area = source.world_area(world, cam.x, cam.y, s.distance, s.light_radius)
            view = offscreen.View(s)
            try:
                view.set_area(area)
                img = view.render(cam, sc.voxel_bake.hours, (w, h))
            finally:
                view.release()
        except VoxelError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        im = bpy.data.images.get(IMAGE)
        if im is None or tuple(im.size) != (w, h):
            if im is not None:
                bpy.data.images.remove(im)
            im = bpy.data.images.new(IMAGE, w, h, alpha=False)
        im.pixels.foreach_set(offscreen.image_pixels(img))
        im.update()
        self.report({"INFO"}, f"rendered {w}x{h} into image '{IMAGE}'")
        return {"FINISHED"}


class VOXEL_PT_view(bpy.types.Panel):
    bl_idname = "VOXEL_PT_view"
    bl_label = "View"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Voxel"
    bl_order = 20

    def draw(self, context):
        self.layout.operator(VOXEL_OT_render_view.bl_idname, icon="RENDER_STILL")


CLASSES = [VOXEL_OT_render_view, VOXEL_PT_view]
