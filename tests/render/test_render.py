"""Real frames on the real GL (Mesa llvmpipe through EGL): properties that must hold."""
from __future__ import annotations

import numpy as np

from voxel_addon import light
from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.render import Camera, Settings

SIZE = (96, 64)



def renderer(gl, blocks, **kw):
    """(No clouds: their shadows and shapes would move the numbers these tests compare;
    tests/render/test_sky.py has theirs.)"""
    from voxel_addon.render.pipeline import Renderer
    r = Renderer(gl, Settings(**{"msaa": 1, "dof": False, "godrays": False, "clouds": False, **kw}))
    r.set_area(blocks, light.solve(blocks), 0, 0)
    return r


def floor(top="stone", n=2):
    b = chunk.empty(width=16 * n, depth=16 * n)
    b[:, :, :60] = R.id("stone")
    b[:, :, 60] = R.id(top)
    return b


def lum(img):
    return img.astype(float).mean(-1)


def test_sky_colour_follows_time_of_day(gl):
    r = renderer(gl, floor())
    up = Camera(16, 16, 70, 0, 60)
    noon, night, dawn = (r.render(up, h, SIZE) for h in (12.0, 0.0, 6.5))
    assert lum(noon).mean() > 3 * lum(night).mean() + 20
    b, g, rr = (noon[..., i].mean() for i in (2, 1, 0))
    assert b > rr + 20, "noon sky is blue"
    assert lum(night).mean() < 40
    # (the eye adapts: the dawn sky, redder, is not darker than noon's on screen)
    assert dawn[..., 0].mean() > noon[..., 0].mean() * 0.8
    r.release()


def test_lamp_lights_its_surroundings_at_night(gl):
    b = floor()
    b[16, 16, 61] = R.id("lamp_red")
    r = renderer(gl, b, shadows=False)
    img = r.render(Camera(16.5, 4, 66, 90, -25), 0.0, SIZE).astype(float)
    # ground near the lamp (image centre, a bit below) vs ground far to the side
    near = img[30:40, 34:62]   # the ground around the lamp (lamp at the centre)
    far = img[56:64, 0:12]     # ground far to the side
    assert near[..., 0].mean() > far[..., 0].mean() + 15
    assert near[..., 0].mean() > near[..., 2].mean() + 10, "the lamp is red"
    r.release()


def at(img, cam, p, r=1):
    """Mean luminance of the pixels around world point p (after cam was rendered)."""
    h, w = img.shape[:2]
    c = cam.fitted(w / h, cam.fov, cam.far).view_proj() @ np.r_[p, 1.0]
    col, row = int((c[0] / c[3] * .5 + .5) * w), int((.5 - c[1] / c[3] * .5) * h)
    assert r <= row < h - r and r <= col < w - r, (p, row, col)
    return lum(img[row - r:row + r + 1, col - r:col + r + 1]).mean()


def _wall():
    b = floor()
    b[8:24, 16, 61:70] = R.id("stone")  # an east-west wall, 9 high, on ground z = 61
    return b


def test_wall_casts_a_shadow_at_noon(gl):
    # noon sun: elevation 70 deg toward -y, so the shadow reaches 9 * tan(20 deg) = 3.3 to +y
    cam = Camera(16, 16.5, 80, 90, -89)     # straight down onto the wall
    r = renderer(gl, _wall(), shadows=True, fog=False)
    on = r.render(cam, 12.0, SIZE)
    r.s.shadows = False
    off = r.render(cam, 12.0, SIZE)
    r.release()
    shade, beyond, sunny = (at(on, cam, (x, y, 61)) for x, y in ((16, 18.5), (16, 22.5), (16, 13)))
    top = at(on, cam, (16, 16.5, 70), 0)
    assert shade < beyond - 30 and shade < sunny - 30, (shade, beyond, sunny)
    assert top > shade + 30, "the wall's own top is in the sun"
    assert abs(at(off, cam, (16, 18.5, 61)) - at(off, cam, (16, 22.5, 61))) < 8


def test_morning_shadow_falls_west(gl):
    # 09:00: the sun stands to +x (and a little -y); the shadow falls to -x, +y
    cam = Camera(16, 16.5, 80, 90, -89)
    # the samples lie ~22 blocks from the camera, where the 50-block fade (§5.4.1) has
    # already halved the shadow: this test is about direction, so no fade here
    r = renderer(gl, _wall(), shadows=True, fog=False, shadow_fade=1000.0)
    img = r.render(cam, 9.0, SIZE)
    r.release()
    west, east, south = (at(img, cam, (x, y, 61)) for x, y in ((5, 18.5), (27, 18.5), (5, 13)))
    assert west < east - 30 and west < south - 30, (west, east, south)


def test_shadows_fade_out_by_the_fade_distance(gl):
    # the same wall seen from 25 and from ~75 blocks (camera-to-fragment distance)
    near, far = Camera(16, 16.5, 86, 90, -89), Camera(16, -40, 110, 90, -40)
    r = renderer(gl, _wall(), shadows=True, fog=False)
    a, b = r.render(near, 12.0, SIZE), r.render(far, 12.0, SIZE)
    r.release()
    d_near = at(a, near, (16, 22.5, 61)) - at(a, near, (16, 18.5, 61))
    d_far = at(b, far, (16, 22.5, 61)) - at(b, far, (16, 18.5, 61))
    # (near: ~25 blocks, the shadow already half faded)
    assert d_near > 20 and abs(d_far) < 4, (d_near, d_far)


def _pool(under):
    b = floor()
    b[8:24, 8:24, 60] = R.id(under)
    b[8:24, 8:24, 61:63] = R.id("water")
    b[:, :, 61:63][b[:, :, 61:63] == 0] = R.id("stone")  # pool walls
    return b


def test_water_shows_what_is_behind_it(gl):
    cam = Camera(16, 16, 72, 0, -89)
    imgs = {}
    for under in ("sand", "stone"):
        for layers in (0, 2):
            r = renderer(gl, _pool(under), peel_layers=layers, shadows=False)
            imgs[under, layers] = r.render(cam, 12.0, SIZE).astype(float)[24:40, 40:56]
            r.release()
    # the bottom shows through water: sand and stone bottoms differ under water
    assert abs(imgs["sand", 2] - imgs["stone", 2]).mean() > 10
    # and the water tints it: with layers the pool is bluer than without
    for u in ("sand", "stone"):
        tint = lambda x: x[..., 2].mean() - x[..., 0].mean()  # noqa: E731
        assert tint(imgs[u, 2]) > tint(imgs[u, 0]) + 5


def test_empty_peel_layers_are_skipped_without_changing_the_picture(gl, monkeypatch):
    """Peel layers are drawn and shaded only behind a layer that got samples (the
    device's counters, conditional rendering): the same picture as every layer run."""
    from voxel_addon.render.device import mgl
    b = floor()
    for y0 in (10, 20):  # two water boxes in a row: four surfaces along the view
        b[12:20, y0:y0 + 4, 61:64] = R.id("water")
    side, top = Camera(16, 2, 64, 90, -8), Camera(16, 16, 80, 0, -89)  # 4 layers, 1
    pics = {}
    for skip in (False, True):
        if skip:
            monkeypatch.undo()
        else:  # a device without counters runs every layer
            monkeypatch.setattr(mgl.MglDevice, "counter", lambda self, key: None)
        for layers in (1, 3):
            r = renderer(gl, b, peel_layers=layers, shadows=False)
            pics[skip, layers] = r.render(side, 12.0, SIZE).astype(int)
            # the top view right after the side view: layers left empty in this frame
            # keep nothing of the frame before
            pics[skip, layers, "top"] = r.render(top, 12.0, SIZE).astype(int)
            r.release()
    assert abs(pics[False, 3] - pics[False, 1]).mean() > 0.5, "layers 2-3 are in view"
    assert abs(pics[False, 3] - pics[False, 3, "top"]).mean() > 0.5
    for k in pics:
        assert (pics[k] == pics[(False, *k[1:])]).all(), k


def test_debug_views_differ(gl):
    b = floor(top="grass")
    b[12:20, 20:24, 61:66] = R.id("stone")
    b[5, 5, 61] = R.id("lamp_blue")
    cam = Camera(16, 2, 68, 90, -25)
    out = {}
    for view in ("none", "albedo", "normal", "depth", "light", "aggregation", "culling"):
        r = renderer(gl, b, debug=view)
        out[view] = r.render(cam, 12.0, SIZE).astype(float)
        r.release()
    names = list(out)
    for i, a in enumerate(names):
        for bname in names[i + 1:]:
            assert abs(out[a] - out[bname]).mean() > 3, (a, bname)
    # the ground is a +z face: normal view encodes it as (0.5, 0.5, 1)
    ground = out["normal"][56:64, 40:56] / 255
    assert np.allclose(ground.mean((0, 1)), [0.5, 0.5, 1.0], atol=0.06)
    # depth view: nearer is brighter
    assert out["depth"][60:64].mean() > out["depth"][34:38].mean()
    # light view has no texture detail: flat ground is nearly uniform
    assert out["light"][56:64, 30:66].std() < out["none"][56:64, 30:66].std()


def test_msaa_smooths_edges(gl):
    b = floor()
    b[14:18, 14:18, 61:70] = R.id("stone")
    cam = Camera(16, 2, 66, 90, 0)
    vals = {}
    for ms in (1, 4):
        r = renderer(gl, b, msaa=ms, fog=False, shadows=False)
        img = lum(r.render(cam, 12.0, SIZE))
        r.release()
        # pixels between their left and right neighbours by a margin on both sides: the
        # pillar's vertical edges (the sky's gradient runs the other way)
        x = img[:, 30:66]
        lo, hi = np.minimum(x[:, :-2], x[:, 2:]), np.maximum(x[:, :-2], x[:, 2:])
        mid = x[:, 1:-1]
        vals[ms] = int(((mid > lo + 6) & (mid < hi - 6)).sum())
    assert vals[4] > vals[1] + 10, ("multisampling adds intermediate edge shades", vals)


def test_ssao_darkens_an_inner_corner(gl):
    b = floor()
    b[:, 20:, 61:72] = R.id("stone")  # a wall along x: floor and wall meet at y = 20
    cam = Camera(16, 2, 70, 90, -25)
    imgs = {}
    for on in (False, True):
        r = renderer(gl, b, ssao=on, shadows=False, fog=False)
        imgs[on] = r.render(cam, 12.0, SIZE)
        r.release()
    corner = [at(imgs[on], cam, (16, 19.8, 61.2), 0) for on in (False, True)]
    open_floor = [at(imgs[on], cam, (16, 12, 61)) for on in (False, True)]
    # (3 levels: the tone curve's shoulder compresses the corner's mid-tones a little)
    assert corner[1] < corner[0] - 3, corner
    assert abs(open_floor[1] - open_floor[0]) < 1.5, open_floor


def test_god_rays_brighten_around_the_sun(gl):
    from voxel_addon.light import daytime
    hours = 7.5
    sx, sy, sz = daytime.at(hours).sun_dir
    yaw, pitch = np.degrees(np.arctan2(sy, sx)), np.degrees(np.arcsin(sz))
    b = floor()
    cam = Camera(16, 16, 66, yaw, pitch)
    away = Camera(16, 16, 66, yaw + 180, pitch)
    out = {}
    for on in (False, True):
        r = renderer(gl, b, godrays=on, fog=False)
        out[on] = lum(r.render(cam, hours, SIZE)), lum(r.render(away, hours, SIZE))
        r.release()
    ring = np.zeros(out[True][0].shape, bool)  # around the sun's disc at the image centre
    yy, xx = np.mgrid[:SIZE[1], :SIZE[0]]
    d = np.hypot(yy - SIZE[1] / 2, xx - SIZE[0] / 2)
    ring[(d > 6) & (d < 20)] = True
    assert out[True][0][ring].mean() > out[False][0][ring].mean() + 5
    assert np.abs(out[True][1] - out[False][1]).max() < 1, "no sun in view: no rays"


def test_waving_moves_plants_only_when_on(gl):
    b = floor(top="grass")
    b[4:28, 4:28, 61] = R.id("tall_grass")
    cam = Camera(16, 2, 66, 90, -30)
    for on in (True, False):
        r = renderer(gl, b, waving=on, shadows=False)
        r.s.time = 0.0
        a = lum(r.render(cam, 12.0, SIZE))
        r.s.time = 1.3
        c = lum(r.render(cam, 12.0, SIZE))
        r.release()
        moved = np.abs(a - c).mean()
        assert (moved > 1.0) if on else (moved == 0.0), (on, moved)


def test_culling_draws_the_frame_of_drawing_everything(gl):
    """Culled region batches (geometry.py) give the frame of drawing every region, with
    shadows and peeling, and fewer triangles."""
    import numpy as _np
    b = floor("grass", n=10)  # 3 x 3 batches
    b[90:100, 90:100, 61:64] = R.id("water")
    b[85, 85, 61] = next(i for i, x in enumerate(R.blocks) if x.double_sided)  # a plant
    b[100, 88, 61:66] = R.id("leaves")
    b[10, 10, 61:80] = R.id("stone")  # behind the camera: culled
    imgs, stats = [], []
    for cull in (True, False):
        r = renderer(gl, b, waving=False)
        if not cull:
            r.geo.cull = lambda vp, g=r.geo, **kw: _np.ones(g._boxes.shape[1], bool)
        imgs.append(r.render(Camera(80, 80, 72, 45, -30), 12.0, SIZE))
        stats.append((r.stats["triangles"], r.stats["shadow_triangles"], r.stats["draw_calls"]))
        r.release()
    assert stats[0][0] < stats[1][0] and 0 < stats[0][1] < stats[0][0], stats
    assert np.array_equal(imgs[0], imgs[1])


def test_nothing_to_show_is_just_sky(gl):
    from voxel_addon.render.pipeline import Renderer
    r = Renderer(gl, Settings(msaa=1))
    r.set_meshes({})
    img = r.render(Camera(0, 0, 80, 0, 10), 12.0, SIZE)
    assert r.stats["triangles"] == 0
    sky = img[:8].reshape(-1, 3).mean(0)
    assert sky[2] > sky[0] + 20 and img.std(axis=(0, 1)).max() < 40  # a blue sky, no geometry
    r.release()


def test_rebuilding_targets_and_renderers_raises_no_gl_error(gl):
    """Size, MSAA and transparency switches rebuild the targets, and a released renderer
    makes way for a new one, without leaving a GL error behind."""
    b = floor("grass")
    b[10:20, 10:20, 61:63] = R.id("water")
    gl.error  # (reading it clears it)
    r = renderer(gl, b)
    for size, kw in ((SIZE, {}), ((64, 40), {}), ((64, 40), {"transparency": "oit"}),
                     ((64, 40), {"msaa": 4})):
        for k, v in kw.items():
            setattr(r.s, k, v)
        r.render(Camera(2, 2, 72, 45, -30), 12.0, size)
        assert gl.error == "GL_NO_ERROR", (size, kw)
    r.release()
    r = renderer(gl, b)
    r.render(Camera(2, 2, 72, 45, -30), 12.0, SIZE)
    assert gl.error == "GL_NO_ERROR"
    r.release()


def test_all_air_is_sky(gl):
    r = renderer(gl, chunk.empty(width=32, depth=32))  # nothing but air: sky only
    img = r.render(Camera(8, 8, 80, 0, 10), 12.0, SIZE)
    assert r.stats["triangles"] == 0 and img.std(axis=(0, 1)).max() < 40
    r.release()


def test_color_blocks_show_their_palette_colour(gl):
    """The `color` block (issue 21): its small data indexes the world's palette and the
    face shows the texture tinted by that colour (noon from above: the left half red,
    the right half blue; another palette recolours them)."""
    from voxel_addon.render.pipeline import Renderer
    b = floor("stone", n=2)
    d = np.zeros_like(b)
    b[:, :, 60] = R.id("color")
    d[:16, :, 60], d[16:, :, 60] = 1, 2
    r = Renderer(gl, Settings(msaa=1, dof=False, godrays=False, shadows=False))
    r.set_area(b, light.solve(b), 0, 0, data=d)
    r.set_palette(np.array([[255, 255, 255], [230, 30, 20], [20, 40, 230]], np.uint8))
    cam = Camera(16, 16, 90, 90, -89.9)
    img = r.render(cam, 12.0, SIZE).astype(int)
    left, right = img[20:44, 10:36].reshape(-1, 3).mean(0), img[20:44, 60:86].reshape(-1, 3).mean(0)
    assert left[0] > left[2] + 40 and right[2] > right[0] + 40, (left, right)
    r.set_palette(np.array([[255, 255, 255], [20, 200, 20], [20, 200, 20]], np.uint8))
    img = r.render(cam, 12.0, SIZE).astype(int)
    left = img[20:44, 10:36].reshape(-1, 3).mean(0)
    assert left[1] > left[0] + 40, left
    r.release()
