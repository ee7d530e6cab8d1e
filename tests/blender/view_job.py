"""Run in a fresh process by test_view.py (bpy and the test's own EGL context stay
apart): render the reference scenes with the live view's device (Blender's gpu module,
on whatever backend this Blender runs) and check that Blender still draws right
afterwards and finds its GPU state as it left it.

    python tests/blender/view_job.py OUT_DIR W H [--dirty]

Writes OUT_DIR/<scene>.npy (the frames), before.npy / after.npy (Blender's own draws
before and after our frames), wb_before.png / wb_after.png (Workbench renders) and
info.json (backend, the gpu.state values before and after). --dirty renders without
liveview.host.kept() (to show that the state check catches a pipeline that leaves
its state behind).
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

IMG = (200, 40, 90, 255)   # the texture Blender's IMAGE shader draws (left half)
TINT = (0.2, 0.6, 1.0, 0.5)  # UNIFORM_COLOR, alpha-blended over it (right half)


def blender_draw(off, tex):
    """Blender's own shaders into the bound offscreen off: a textured quad, then a
    colour quad alpha-blended with culling on, read back as (h, w, 4) uint8."""
    import gpu
    from gpu_extras.batch import batch_for_shader
    from mathutils import Matrix
    fb = gpu.state.active_framebuffer_get()
    fb.clear(color=(0.0, 0.0, 0.0, 1.0), depth=1.0)
    with gpu.matrix.push_pop(), gpu.matrix.push_pop_projection():
        gpu.matrix.load_identity()
        gpu.matrix.load_projection_matrix(Matrix.Identity(4))
        img = gpu.shader.from_builtin("IMAGE")
        b = batch_for_shader(img, "TRI_FAN", {"pos": ((-1, -1), (0, -1), (0, 1), (-1, 1)),
                                              "texCoord": ((0, 0), (1, 0), (1, 1), (0, 1))})
        img.bind()
        img.uniform_sampler("image", tex)
        b.draw(img)
        col = gpu.shader.from_builtin("UNIFORM_COLOR")
        gpu.state.blend_set("ALPHA")
        gpu.state.face_culling_set("BACK")
        b2 = batch_for_shader(col, "TRI_FAN", {"pos": ((-0.5, -1), (1, -1), (1, 1), (-0.5, 1))})
        col.bind()
        col.uniform_float("color", TINT)
        b2.draw(col)
    buf = fb.read_color(0, 0, off.width, off.height, 4, 0, "UBYTE")
    buf.dimensions = off.width * off.height * 4
    return np.array(buf.to_list(), np.uint8).reshape(off.height, off.width, 4)


def workbench(path):
    """A Workbench render of a flat-coloured plane filling a camera's view."""
    import bpy
    sc = bpy.data.scenes.get("wb")
    if sc is None:
        sc = bpy.data.scenes.new("wb")
        me = bpy.data.meshes.new("wb")
        me.from_pydata([(-2, -2, 0), (2, -2, 0), (2, 2, 0), (-2, 2, 0)], [], [(0, 1, 2, 3)])
        plane = bpy.data.objects.new("wb", me)
        cam = bpy.data.objects.new("wbcam", bpy.data.cameras.new("wbcam"))
        cam.location = (0, 0, 3)
        for o in (plane, cam):
            sc.collection.objects.link(o)
        sc.camera = cam
        r = sc.render
        r.engine = "BLENDER_WORKBENCH"
        r.resolution_x, r.resolution_y, r.resolution_percentage = 24, 16, 100
        r.image_settings.file_format = "PNG"
        sc.display_settings.display_device = "sRGB"
        sc.view_settings.view_transform = "Standard"
        sh = sc.display.shading
        sh.light, sh.color_type, sh.single_color = "FLAT", "SINGLE", (0.2, 0.5, 0.8)
    sc.render.filepath = str(path)
    bpy.ops.render.render(scene=sc.name, write_still=True)


# a host's state when our frames run (a draw handler finds Blender's, not the defaults)
HOST_STATE = {"blend": "ALPHA", "depth_test": "LESS_EQUAL", "depth_mask": True, "line_width": 2.0}


def main():
    out, w, h = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    dirty = "--dirty" in sys.argv
    import bpy  # noqa: F401
    import gpu
    from voxel_addon.blender.liveview import host
    from voxel_addon.blender.liveview.still import Still
    from voxel_addon.light import daytime
    from voxel_addon.meshing import scenes
    from voxel_addon.render import Camera, Settings, source

    host.start_gpu()
    info = {"backend": gpu.platform.backend_type_get(), "renderer": gpu.platform.renderer_get(),
            "version": gpu.platform.version_get(), "ms": {}}
    probe = gpu.types.GPUOffScreen(32, 16)
    data = gpu.types.Buffer("FLOAT", 4 * 4 * 4, [c / 255 for _ in range(16) for c in IMG])
    tex = gpu.types.GPUTexture((4, 4), format="RGBA8", data=data)
    workbench(out / "wb_before.png")
    stills = {}
    for name in sorted(scenes.SCENES):  # first frames: programs compile, meshes upload
        st = stills[name] = Still(Settings(msaa=1))
        st.set_area(source.scene_area(name))
        sc = scenes.SCENES[name]
        st.render(Camera(*sc.camera), daytime.parse_time(sc.time), (w, h))
    # our frames run between Blender's draws into the same bound framebuffer, as a
    # draw handler's would: Blender must draw the same after them and find its state
    with probe.bind():
        before = blender_draw(probe, tex)
        s = gpu.state
        s.blend_set(HOST_STATE["blend"])
        s.depth_test_set(HOST_STATE["depth_test"])
        s.depth_mask_set(HOST_STATE["depth_mask"])
        s.line_width_set(HOST_STATE["line_width"])
        info["state_before"] = host.state()
        for name, st in stills.items():
            sc = scenes.SCENES[name]
            cam, hours = Camera(*sc.camera), daytime.parse_time(sc.time)
            if dirty:
                img = st.r.render(cam, hours, (w, h))  # no host.kept()
            else:
                img = st.render(cam, hours, (w, h))
                info["ms"][name] = st.ms
            np.save(out / f"{name}.npy", img)
        info["state_after"] = host.state()
        s.blend_set("NONE")
        s.depth_test_set("NONE")
        s.depth_mask_set(False)
        s.line_width_set(1.0)
        after = blender_draw(probe, tex)
    for st in stills.values():
        st.release()
    workbench(out / "wb_after.png")
    np.save(out / "before.npy", before)
    np.save(out / "after.npy", after)
    (out / "info.json").write_text(json.dumps(info))


if __name__ == "__main__":
    main()
