"""Run in a fresh process by test_view.py: the add-on's "Render Voxel View" operator
on a new flat world, from a scene camera, into its image datablock.

    python tests/blender/op_job.py OUT_DIR [FAR]

FAR: the View panel's far distance, with the camera looking 2 degrees down (the
far ring fills the band below the horizon that the near chunks leave to the sky).

Writes OUT_DIR/op.npy (the image's pixels, (h, w, 4) float, bottom row first) and
OUT_DIR/op.json (the operator's result and the image size).
"""
from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from flat_scene import flat_scene  # noqa: E402


def main():
    out = Path(sys.argv[1])
    far = int(sys.argv[2]) if len(sys.argv) > 2 else None
    import bpy
    import voxel_addon
    sc = flat_scene(out)
    sc.voxel_bake.hours = 12.0
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    sc.collection.objects.link(cam)
    sc.camera = cam
    # 20 blocks above the flat ground, looking along +x, 20 degrees down
    cam.location = (8.0, 8.0, 90.0)
    cam.rotation_euler = (math.radians(70.0 if far is None else 88.0), 0.0, math.radians(-90.0))
    if far is not None:
        sc.voxel_view.distance, sc.voxel_view.far = 2, far
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 96, 54, 100
    res = bpy.ops.voxel.render_view()
    im = bpy.data.images["Voxel View"]
    px = np.empty(im.size[0] * im.size[1] * 4, np.float32)
    im.pixels.foreach_get(px)
    np.save(out / "op.npy", px.reshape(im.size[1], im.size[0], 4))
    (out / "op.json").write_text(json.dumps({"result": sorted(res), "size": list(im.size)}))
    voxel_addon.unregister()


if __name__ == "__main__":
    main()
