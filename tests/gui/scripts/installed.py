"""GUI test script: the extension zip with its bundled wheels, installed into a fresh
user folder of the real Blender, works from those wheels: it generates a world
(OpenCL), edits it, renders a view (moderngl on Blender's GL context), bakes and
exports a .glb. (Showing it live: test_first_minute.py, from the same zip.)"""
import math
import os
import sys

import bpy

MOD = "bl_ext.user_default.voxel_worlds"


def run(gui):
    p = gui.params
    r = bpy.ops.extensions.package_install_files(filepath=p["zip"], repo="user_default",
                                                 enable_on_install=True)
    assert r == {"FINISHED"}, r
    assert MOD in bpy.context.preferences.addons, "not enabled"
    yield 0.2
    user = os.path.realpath(os.environ["BLENDER_USER_RESOURCES"])
    import numpy
    out = {"numpy": numpy.__version__, "python": sys.version.split()[0],
           "blender": bpy.app.version_string, "modules": {}}
    ocl = sys.modules.get(MOD + ".voxel_addon.opencl") or __import__(
        MOD + ".voxel_addon.opencl", fromlist=["x"])
    out["opencl"] = ocl.describe()  # imports pyopencl: must be the extension's wheel
    import moderngl
    import pyopencl
    import zstandard
    for m in (pyopencl, moderngl, zstandard):
        out["modules"][m.__name__] = os.path.realpath(m.__file__)
    out["user"] = user

    sc = bpy.context.scene
    sc.voxel.path, sc.voxel.seed, sc.voxel.generator = p["world"], 7, "overworld"
    assert bpy.ops.voxel.world_new() == {"FINISHED"}
    w = sys.modules[MOD + ".voxel_addon.blender.session"].world(p["world"])
    # opening a world starts the kernels' warm-up (NumPy meanwhile): OpenCL after it
    out["warm_started"] = ocl.warm_state()["started"]
    while ocl.warming():
        yield 0.1
    out["backend"] = w.generator.backend
    with gui.context(gui.area("VIEW_3D")):  # the edit tool's script form: one stroke
        out["edit"] = sorted(bpy.ops.voxel.edit(location=(3, 4, 200), block="glass"))
    blocks = sys.modules[MOD + ".voxel_addon.core.blocks"]
    out["edited"] = blocks.REGISTRY[w.get_block(3, 4, 200)].name
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    sc.collection.objects.link(cam)
    sc.camera = cam
    cam.location = (8.0, 8.0, 140.0)
    cam.rotation_euler = (math.radians(70.0), 0.0, math.radians(-90.0))
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = 160, 90, 100
    sc.voxel_bake.hours = 12.0
    yield None
    with gui.context(gui.area("VIEW_3D")):
        out["render"] = sorted(bpy.ops.voxel.render_view())
    im = bpy.data.images["Voxel View"]
    px = numpy.empty(im.size[0] * im.size[1] * 4, numpy.float32)
    im.pixels.foreach_get(px)
    px = px.reshape(im.size[1], im.size[0], 4)[::-1, :, :3]  # top row first
    out["view"] = {"size": list(im.size), "top": px[:10].mean((0, 1)).tolist(),
                   "bottom": px[-10:].mean((0, 1)).tolist(), "std": float(px.std())}
    yield None
    b = sc.voxel_bake
    b.region_min, b.region_max = (0, 0), (16, 16)
    before = set(bpy.data.objects)
    with gui.context(gui.area("VIEW_3D")):
        out["bake"] = sorted(bpy.ops.voxel.bake())
    baked = [o for o in bpy.data.objects if o not in before and o.type == "MESH"]
    out["baked"] = {"objects": len(baked), "triangles": sum(
        sum(len(poly.vertices) - 2 for poly in o.data.polygons) for o in baked)}
    b.glb_path = p["glb"]
    with gui.context(gui.area("VIEW_3D")):
        out["export"] = sorted(bpy.ops.voxel.export_glb())
    gui.result.update(out)
    yield from gui.screenshot("installed")
