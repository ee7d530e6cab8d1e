"""Day and night of one light-atlas bake, rendered by Blender (Cycles, CPU): every
pixel of the baked surface equals texture × eq. 4.1 of the light read bilinearly
from the unit-grid corners (light.sample, NumPy) at that time of day — the Voxel
Shade node group, the atlas image and its UVs checked end to end."""
from __future__ import annotations

import numpy as np
import pytest

from voxel_addon import bake
from voxel_addon.core.blocks import REGISTRY

N = 16          # pixels per side; the camera sees 8×8 blocks, 2 pixels per block
EPS = 1 / 64    # off texel borders of the 16×16 block textures


def _render(bpy, path):
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(str(path))
    px = np.array(img.pixels[:], np.float64).reshape(N, N, 4)
    bpy.data.images.remove(img)
    return px


def _srgb_to_linear(c):
    c = c / 255.0
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


def test_day_and_night_render_of_the_atlas(bpy, tmp_path):
    from voxel_addon import textures
    from voxel_addon.blender import bake as BB
    from voxel_addon.core import chunk as C
    from voxel_addon.light import daytime, sample, shade, solve
    b = np.zeros((8, 8, 256), np.uint16, order="F")
    b[:, :, :10] = REGISTRY.id("stone")
    b[3, 3, 10] = REGISTRY.id("lamp_red")
    bk = bake.bake_blocks(b)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    objs = BB.build(bk, style="blender", hours=12.0)
    sc = bpy.context.scene
    sc.render.engine = "CYCLES"
    sc.cycles.device, sc.cycles.samples, sc.cycles.use_denoising = "CPU", 1, False
    sc.cycles.max_bounces = 0
    for o in objs:  # only what the camera sees: the emission, not light between faces
        o.visible_diffuse = o.visible_glossy = o.visible_transmission = False
    sc.world = None
    sc.render.filter_size = 0.01  # one sample at each pixel centre
    sc.render.resolution_x = sc.render.resolution_y = N
    sc.render.image_settings.file_format = "OPEN_EXR"  # linear
    cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
    cam.data.type, cam.data.ortho_scale = "ORTHO", 8.0
    cam.location = (4 + EPS, 4 + EPS, 30)
    sc.collection.objects.link(cam)
    sc.camera = cam
    pad = bake.PAD
    padded = C.empty(np.uint16, 8 + 2 * pad, 8 + 2 * pad)
    padded[pad:pad + 8, pad:pad + 8] = b
    lit = solve(padded)
    tex = _srgb_to_linear(textures.image("stone")[0][..., :3].astype(np.float64))
    up = np.array([[0.0, 0.0, 1.0]])
    shots = {}
    for hours in (12.0, 0.0):
        BB.set_hours(hours)
        sc.render.filepath = str(tmp_path / f"h{int(hours)}.exr")
        px = _render(bpy, sc.render.filepath)
        shots[hours] = px
        checked = 0
        for j in range(N):
            for i in range(N):
                x, y = (i + 0.5) / 2 + EPS, (j + 0.5) / 2 + EPS
                if 3 <= x < 4 and 3 <= y < 4:
                    continue  # the lamp's own top (glow)
                x0, y0 = np.floor(x), np.floor(y)
                corners = np.array([[x0 + a, y0 + c, 10] for c in (0, 1) for a in (0, 1)])
                s = sample(lit, corners + (pad, pad, 0), np.repeat(up, 4, 0))
                fx, fy = x - x0, y - y0
                w = np.array([(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy])
                light = w @ s
                f = shade(np.ones((1, 3)), light[None, :3], np.zeros(1), light[None, 3], up,
                          daytime.at(hours))[0]
                t = tex[15 - int((y % 1) * 16), int((x % 1) * 16)]
                assert px[j, i, :3] == pytest.approx(t * f, rel=2e-3, abs=1e-4), (hours, i, j)
                checked += 1
        assert checked == N * N - 4
    # the same bake: noon is brighter than midnight, where the red lamp dominates
    far = shots[12.0][12:, 12:, :3].mean((0, 1)), shots[0.0][12:, 12:, :3].mean((0, 1))
    assert (far[0] > 2 * far[1]).all()
    near = shots[0.0][4:6, 6:8, :3].mean((0, 1))
    assert near[0] > 2 * near[1]
