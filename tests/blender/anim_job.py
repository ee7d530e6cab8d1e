"""Run in a fresh process by test_animation.py: Render Voxel Animation over 3 frames
of a flat world, the camera keyframed and the day cycle following the timeline.

    python tests/blender/anim_job.py OUT_DIR
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from flat_scene import flat_scene  # noqa: E402


def main():
    out = Path(sys.argv[1])
    import bpy
    import voxel_addon
    sc = flat_scene(out)
    vv = sc.voxel_view
    vv.follow_timeline, vv.frames_per_day, vv.hours = True, 4, 12.0  # noon, 18:00, midnight
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    sc.collection.objects.link(cam)
    sc.camera = cam
    cam.rotation_euler = (math.radians(80.0), 0.0, math.radians(-90.0))
    for f, x in ((1, 8.0), (3, 40.0)):
        cam.location = (x, 8.0, 90.0)
        cam.keyframe_insert("location", frame=f)
    sc.frame_start, sc.frame_end = 1, 3
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 64, 36, 100
    sc.render.filepath = str(out / "frames" / "f_")
    res = bpy.ops.voxel.render_animation()
    files = sorted(p.name for p in (out / "frames").glob("*.png"))
    (out / "anim.json").write_text(json.dumps({"result": sorted(res), "files": files,
                                               "frame": sc.frame_current}))
    voxel_addon.unregister()


if __name__ == "__main__":
    main()
