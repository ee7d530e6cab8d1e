"""Run in a fresh process (bpy state stays out of the test's): a .blend whose scene
camera flies over the world in two keyframes while the day cycle follows the timeline.

    python tests/cluster/blend_job.py OUT.blend
"""
import math
import sys


def main(out):
    import bpy
    import voxel_addon
    bpy.ops.wm.read_factory_settings(use_empty=True)
    voxel_addon.register()
    sc = bpy.context.scene
    vv = sc.voxel_view
    vv.follow_timeline, vv.frames_per_day, vv.hours = True, 4, 12.0  # noon, 18:00, midnight
    vv.distance = 2
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    sc.collection.objects.link(cam)
    sc.camera = cam
    cam.rotation_euler = (math.radians(35.0), 0.0, math.radians(-60.0))
    for f, x in ((1, -10.0), (3, 22.0)):  # the camera crosses a chunk edge
        cam.location = (x, 4.0, 88.0)
        cam.keyframe_insert("location", frame=f)
    sc.frame_start, sc.frame_end = 1, 3
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 64, 36, 100
    bpy.ops.wm.save_as_mainfile(filepath=out)


if __name__ == "__main__":
    main(sys.argv[1])
