"""Run in a fresh process by test_view.py (bpy and other GL contexts of the pytest
process stay apart): render a reference scene on Blender's GL context and check that
Blender still draws right afterwards.

    python tests/blender/view_job.py OUT_DIR SCENE W H [--dirty]

Writes OUT_DIR/view.npy (the frame), before.npy / after.npy (Blender's own draws
before and after our frames), wb_before.png / wb_after.png (Workbench renders) and
info.json. --dirty runs the pipeline on Blender's context without glstate.kept() (to
show that the checks catch a pipeline that leaves its GL state behind).
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


def main():
    out, scene, w, h = Path(sys.argv[1]), sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
    dirty = "--dirty" in sys.argv
    import bpy  # noqa: F401
    import gpu
    from voxel_addon.blender import offscreen
    from voxel_addon.light import daytime
    from voxel_addon.meshing import scenes
    from voxel_addon.render import Camera, Settings, source

    offscreen.start_gpu()
    info = {"backend": gpu.platform.backend_type_get(), "renderer": gpu.platform.renderer_get(),
            "version": gpu.platform.version_get()}
    probe = gpu.types.GPUOffScreen(32, 16)
    data = gpu.types.Buffer("FLOAT", 4 * 4 * 4, [c / 255 for _ in range(16) for c in IMG])
    tex = gpu.types.GPUTexture((4, 4), format="RGBA8", data=data)
    workbench(out / "wb_before.png")

    sc = scenes.SCENES[scene]
    area = source.scene_area(scene)
    cam, hours = Camera(*sc.camera), daytime.parse_time(sc.time)
    # our frames run between Blender's draws into the same bound framebuffer, as a
    # draw handler's would: Blender must find its framebuffer, program, textures and
    # blend/cull state as it left them (it skips binds it thinks are redundant).
    # The View (its GPUOffScreen) is made outside: Blender itself loses its bound
    # framebuffer when an offscreen is created inside a bind.
    v = None
    if dirty:
        global _DIRTY_OFF
        _DIRTY_OFF = gpu.types.GPUOffScreen(w, h)
    else:
        v = offscreen.View(Settings())
        v.set_area(area)
        v.render(cam, hours, (w, h))  # first frame: programs compile, meshes upload
    with probe.bind():
        before = blender_draw(probe, tex)
        frame, shown = _frames(v, area, cam, hours, (w, h), info)
        after = blender_draw(probe, tex)
    if v is not None:
        v.release()
    np.save(out / "view.npy", frame)
    if shown is not None:
        np.save(out / "shown.npy", shown)
    workbench(out / "wb_after.png")
    np.save(out / "before.npy", before)
    np.save(out / "after.npy", after)
    (out / "info.json").write_text(json.dumps(info))


def _frames(v, area, cam, hours, size, info):
    if v is None:
        return _dirty_frame(area, cam, hours, size), None
    ms = []
    for _ in range(2):
        frame = v.render(cam, hours, size)
        ms.append(v.ms)
    info.update(v.info, ms=min(ms), cpu_ms=v.r.stats["cpu_ms"])
    return frame, _offscreen_pixels(v.off)  # what a draw handler would show


def _offscreen_pixels(off):
    buf = off.texture_color.read()
    buf.dimensions = off.width * off.height * 4
    return np.array(buf.to_list(), np.uint8).reshape(off.height, off.width, 4)[::-1, :, :3]


_DIRTY_OFF = None


def _dirty_frame(area, cam, hours, size):
    """The pipeline straight on Blender's context, no state kept: what must be caught."""
    import gpu
    import moderngl
    from _moderngl import DefaultLoader
    from voxel_addon.render import Settings
    from voxel_addon.render.pipeline import Renderer
    off = _DIRTY_OFF
    with off.bind():
        ctx = moderngl.create_context(context=DefaultLoader())
        r = Renderer(ctx, Settings())
        r.set_area(area.blocks, area.light, area.cx0, area.cy0, ring=True, light_at=area.light_at)
        return r.render(cam, hours, size)


if __name__ == "__main__":
    main()
