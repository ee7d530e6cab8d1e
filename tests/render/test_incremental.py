"""Chunks in and out one at a time (Renderer.update_chunks / remove_chunks) draw the
same frame as the one-shot full rebuild; an update builds only its chunks' batches
again; cameras from host matrices (perspective and
orthographic) draw what the parametric camera draws, and orthographic frames look
like orthographic projections."""
from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest

from voxel_addon import light, meshing
from voxel_addon.core import chunk
from voxel_addon.core.blocks import REGISTRY as R
from voxel_addon.render import Camera, Settings
from voxel_addon.render import camera as C

SIZE = (96, 64)


class Chunk(NamedTuple):
    key: tuple
    mesh: object
    light: np.ndarray


def _area():
    """3 x 3 chunks from (-1, -1): terrain with water, glass, leaves and plants, lamps."""
    rng = np.random.default_rng(11)
    b = chunk.empty(width=50, depth=50)  # 48 + ring
    t = np.arange(50)
    hgt = (58 + 4 * np.sin(t / 5)[:, None] + 3 * np.cos(t / 7)[None]).astype(int)
    for x in range(50):
        for y in range(50):
            b[x, y, :hgt[x, y]] = R.id("stone")
            b[x, y, hgt[x, y]] = R.id("grass")
    b[10:22, 12:30, 55:62][b[10:22, 12:30, 55:62] == 0] = R.id("water")
    b[30:34, 5:40, 62:66] = R.id("glass")
    b[rng.random(b.shape) < 0.0008] = R.id("leaves")
    plant = next(i for i, x in enumerate(R.blocks) if x.double_sided)
    top = hgt + 1
    for x, y in rng.integers(1, 49, (40, 2)):
        if b[x, y, top[x, y]] == 0:
            b[x, y, top[x, y]] = plant
    b[25, 25, top[25, 25]] = R.id("lamp_red")
    L = light.solve(b)[1:-1, 1:-1]
    meshes = meshing.build_chunks(b, (-1, -1), backend="numpy")
    lights = {(cx, cy): L[16 * (cx + 1):16 * (cx + 2), 16 * (cy + 1):16 * (cy + 2)]
              for cx, cy in meshes}
    return b, L, meshes, lights


@pytest.fixture(scope="module")
def area():
    return _area()


def _renderer(gl, **kw):
    from voxel_addon.render.pipeline import Renderer
    return Renderer(gl, Settings(**{"msaa": 1, "waving": False, **kw}))


CAMS = [Camera(-12, -14, 80, 45, -25), Camera(8, 8, 100, 200, -60), Camera(30, -10, 66, 120, -5)]


def _frames(r, hours=12.0):
    out = []
    for cam in CAMS:
        out.append(r.render(cam, hours, SIZE))
        out.append(r.stats.snapshot()["triangles"])
    return out


def test_incremental_equals_full_rebuild(gl, area):
    b, L, meshes, lights = area
    full = _renderer(gl)
    # (closed=False: the meshes with their real ring, as update_chunks gets them)
    full.set_area(b, L, -1, -1, ring=True, backend="numpy", closed=False)
    want = _frames(full)
    full.release()
    assert want[1] > 0 and want[0].std() > 10

    rng = np.random.default_rng(5)
    keys = list(meshes)
    r = _renderer(gl)
    # arrive in a shuffled order, in small batches, with frames in between
    order = [keys[i] for i in rng.permutation(len(keys))]
    for i in range(0, len(order), 2):
        r.update_chunks(Chunk(k, meshes[k], lights[k]) for k in order[i:i + 2])
        r.render(CAMS[0], 12.0, SIZE)
    # wrong data first (another chunk's mesh, no light), then replaced by the right one
    wrong = order[:3]
    r.update_chunks(Chunk(k, meshes[order[-1]], None) for k in wrong)
    r.render(CAMS[1], 12.0, SIZE)
    r.update_chunks(Chunk(k, meshes[k], lights[k]) for k in wrong)
    # some leave and come back; a chunk that is not shown is ignored on removal
    gone = order[2:6]
    r.remove_chunks(gone + [(40, 40)])
    mid = r.render(CAMS[0], 12.0, SIZE)
    assert set(r.geo.keys) == set(keys) - set(gone)
    r.update_chunks(Chunk(k, meshes[k], lights[k]) for k in reversed(gone))
    assert _same(_frames(r), want)
    assert not np.array_equal(mid, want[0])  # removing chunks did change the frame
    # set_area on a renderer that shows something else is the same full rebuild
    r.remove_chunks([keys[0]])
    r.update_chunks([Chunk((5, 5), meshes[keys[1]], lights[keys[1]])])
    r.set_area(b, L, -1, -1, ring=True, backend="numpy", closed=False)
    assert set(r.geo.keys) == set(keys)
    assert _same(_frames(r), want)
    r.release()


def _same(got, want):
    for g, w in zip(got, want):
        if isinstance(g, np.ndarray):
            if not np.array_equal(g, w):
                return False
        elif g != w:
            return False
    return True


def test_an_update_builds_only_its_batches(gl, area):
    """Chunks far apart land in different batches: updating one builds its batch again
    (new vertex buffers) and leaves the others' buffers as they were."""
    from voxel_addon.render.geometry import BATCH
    b, L, meshes, lights = area
    r = _renderer(gl)
    k0 = (-1, -1)
    far = (k0[0] + 3 * BATCH, k0[1])
    r.update_chunks(Chunk(k, m, lights[k]) for k, m in meshes.items())
    r.update_chunks([Chunk(far, meshes[k0], None)])
    r.render(CAMS[0], 12.0, SIZE)
    geo = r.geo
    before = {k: list(bt.meshes) for k, bt in geo._batches.items()}
    assert len(before) >= 2
    r.update_chunks([Chunk(k0, meshes[(0, 0)], lights[k0])])
    r.render(CAMS[0], 12.0, SIZE)
    mine = (k0[0] // BATCH, k0[1] // BATCH)
    for k, bt in geo._batches.items():
        same = [x is y for x, y in zip(bt.meshes, before[k])]
        assert all(same) if k != mine else not any(s for s, m in zip(same, bt.meshes) if m), k
    r.release()


def test_chunks_one_by_one_draw_the_frame_of_one_upload(gl, area):
    """Chunks arriving one by one (far copies too, removed again) draw the frame of one
    upload of them all."""
    b, L, meshes, lights = area
    r = _renderer(gl)
    r.update_chunks(Chunk(k, m, lights[k]) for k, m in meshes.items())
    want = _frames(r)
    r.release()
    r = _renderer(gl)
    many = {(cx + 10 * i, cy): m for i in range(4) for (cx, cy), m in meshes.items()}
    for k, m in many.items():  # far away copies, each with a frame
        r.update_chunks([Chunk(k, m, None)])
        r.render(CAMS[1], 12.0, SIZE)
    r.update_chunks(Chunk(k, m, lights[k]) for k, m in meshes.items())
    r.remove_chunks([k for k in many if k not in meshes])
    assert len(r.geo.keys) == len(meshes)
    assert _same(_frames(r), want)
    r.release()


def test_light_window_follows_the_camera(gl):
    """The light window is around the camera's chunk: a chunk's light is in the volume
    when the camera is near it and open daylight far away; a chunk whose light changes
    is uploaded again."""
    n = 5
    b = chunk.empty(width=16 * n + 2, depth=16 * n + 2)
    b[:, :, :60] = R.id("stone")
    meshes = meshing.build_chunks(b, (0, 0), backend="numpy")
    dark = np.zeros((16, 16, 256), np.uint16)
    r = _renderer(gl, light_radius=1)
    r.update_chunks(Chunk(k, m, dark) for k, m in meshes.items())
    r.render(Camera(8, 8, 80, 45, -30), 12.0, SIZE)
    assert r.vol.n == 3 and r.vol.lo == (0, 0) and r.vol.hi == (32, 32)
    assert r.vol.resident((1, 1)) and not r.vol.resident((4, 4))
    r.render(Camera(72, 72, 80, 45, -30), 12.0, SIZE)
    assert r.vol.lo == (48, 48) and r.vol.hi == (80, 80) and r.vol.resident((4, 4))
    # the camera's chunk gets new light: uploaded before the next frame
    lit = np.full((16, 16, 256), 0xF000, np.uint16)
    r.update_chunks([Chunk((4, 4), meshes[4, 4], lit)])
    assert not r.vol.resident((4, 4))
    r.render(Camera(72, 72, 80, 45, -30), 12.0, SIZE)
    assert r.vol.resident((4, 4))
    r.release()


def test_prepare_leaves_the_callers_camera_alone(gl, area):
    b, L, meshes, lights = area
    r = _renderer(gl)
    r.set_area(b, L, -1, -1, ring=True, backend="numpy")
    cam = Camera(-12, -14, 80, 45, -25, fov=50.0, aspect=3.0, near=0.5, far=99.0)
    keep = (cam.x, cam.y, cam.z, cam.yaw, cam.pitch, cam.fov, cam.aspect, cam.near, cam.far)
    r.render(cam, 12.0, SIZE)
    assert keep == (cam.x, cam.y, cam.z, cam.yaw, cam.pitch, cam.fov, cam.aspect, cam.near, cam.far)
    r.release()


def test_from_matrices_is_the_same_camera():
    rng = np.random.default_rng(2)
    for _ in range(50):
        cam = Camera(*rng.uniform(-500, 500, 2), rng.uniform(0, 256), rng.uniform(-180, 180),
                     rng.uniform(-89, 89), rng.uniform(20, 110), rng.uniform(0.5, 3),
                     rng.uniform(0.05, 1), rng.uniform(100, 2000))
        m = Camera.from_matrices(cam.view(), cam.proj())
        for f in ("x", "y", "z", "yaw", "pitch", "fov", "aspect", "near", "far"):
            assert np.isclose(getattr(m, f), getattr(cam, f), rtol=1e-7, atol=1e-6), f
        assert not m.ortho
        vp, inv = m.matrices()
        assert np.allclose(vp, cam.matrices()[0], atol=1e-9)
        assert np.allclose(inv @ vp, np.eye(4), atol=1e-6)
        assert np.allclose(m.corners(50.0), cam.corners(50.0), atol=1e-6)
        assert np.allclose(m.forward, cam.forward)
        assert m.fitted(2.0, 30.0, 5.0) is m  # the host's projection stays as given


def test_from_matrices_orthographic():
    view = C.look_at((10.0, 20.0, 200.0), (0.3, 0.2, -1.0))
    proj = C.ortho(-30, 30, -20, 20, -50.0, 400.0)
    m = Camera.from_matrices(view, proj)
    assert m.ortho and np.isclose(m.near, -50) and np.isclose(m.far, 400)
    assert np.allclose((m.x, m.y, m.z), (10, 20, 200)) and np.isclose(m.aspect, 1.5)
    c = np.array(m.corners(100.0, 10.0))
    # parallel rays: both planes are the same rectangle, shifted along the forward axis
    shift = c[4:] - c[:4]
    assert np.allclose(shift, shift[0]) and np.allclose(shift[0], 90 * m.forward)
    assert np.isclose(np.linalg.norm(c[1] - c[0]), 60)
    assert np.isclose(np.linalg.norm(c[2] - c[0]), 40)


def test_from_matrices_draws_the_same_frame(gl, area):
    b, L, meshes, lights = area
    r = _renderer(gl, ssao=True)
    r.set_area(b, L, -1, -1, ring=True, backend="numpy")
    for cam in CAMS:
        want = r.render(cam, 9.0, SIZE).astype(int)
        f = cam.fitted(SIZE[0] / SIZE[1], r.s.fov, r.s.distance * 16 * 1.5 + 256.0)
        got = r.render(Camera.from_matrices(f.view(), f.proj()), 9.0, SIZE).astype(int)
        assert np.abs(got - want).max() <= 2 and np.abs(got - want).mean() < 0.05
    r.release()


def _ortho_top(cx, cy, half_h, z=150.0, aspect=1.0):
    view = C.look_at((cx, cy, z), (0.0, 0.0, -1.0))
    return Camera.from_matrices(view, C.ortho(-half_h * aspect, half_h * aspect,
                                              -half_h, half_h, 1.0, 300.0))


def test_orthographic_from_above_shows_footprints(gl):
    """Straight down through parallel rays a pillar covers exactly its footprint (a
    perspective view would show it larger and its sides): 4 pixels a block."""
    b = chunk.empty(width=34, depth=34)
    b[:, :, :60] = R.id("stone")
    b[:, :, 60] = R.id("grass")
    b[13:21, 9:17, 61:100] = R.id("stone")  # 8 x 8 blocks, 39 high: x 12..20, y 8..16
    r = _renderer(gl, debug="depth")
    r.set_area(b, light.solve(b), 0, 0, ring=True, backend="numpy")
    cam = _ortho_top(16, 16, 16)
    img = r.render(cam, 12.0, (128, 128)).astype(int)[..., 0]
    top = img == img.max()  # the nearest surface: the pillar's top
    rows, cols = np.nonzero(top)
    # image row 0 = y 32 (top), column 0 = x 0: 4 pixels a block
    assert top.sum() == 32 * 32, top.sum()
    assert (cols.min(), cols.max() + 1) == (48, 80) and (rows.min(), rows.max() + 1) == (64, 96)
    # every other pixel is the ground, at one depth (no sides, no perspective)
    assert len(np.unique(img[~top])) == 1 and img[~top][0] < img.max()
    r.s.debug = "normal"
    nrm = r.render(cam, 12.0, (128, 128)).astype(float) / 255
    assert np.allclose(nrm.reshape(-1, 3).mean(0), [0.5, 0.5, 1.0], atol=0.01)  # only +z faces
    r.release()


def test_orthographic_frames_with_every_effect_look_sane(gl, area):
    """An oblique orthographic view with shadows, fog, SSAO and god rays on: sky above,
    lit ground below, shadows from the pillar, nothing black or NaN; parallel vertical
    edges stay parallel (the pillar is as wide at its top as at its foot)."""
    b = chunk.empty(width=50, depth=50)
    b[:, :, :60] = R.id("stone")
    b[:, :, 60] = R.id("grass")
    b[22:28, 22:28, 61:90] = R.id("stone")
    eye = np.array([24.0, -60.0, 110.0])
    view = C.look_at(eye, np.array([24.0, 24.0, 60.0]) - eye)
    cam = Camera.from_matrices(view, C.ortho(-36, 36, -24, 24, -100.0, 400.0))
    out = {}
    for shadows in (False, True):
        r = _renderer(gl, ssao=True, shadows=shadows, godrays=True, fog=True)
        r.set_area(b, light.solve(b), -1, -1, ring=True, backend="numpy")
        out[shadows] = r.render(cam, 9.0, (96, 64)).astype(float)
        r.s.debug = "albedo"
        alb = r.render(cam, 9.0, (96, 64)).astype(float)
        r.release()
    img = out[True]
    assert np.isfinite(img).all() and img.mean() > 40
    sky, ground = img[:3].reshape(-1, 3).mean(0), img[-10:].reshape(-1, 3).mean(0)
    assert sky[2] > sky[0] + 20, "a blue sky above"
    assert abs(ground - sky).sum() > 30, "the ground is not sky"
    darker = (out[False] - out[True]).mean(-1) > 30
    assert darker.sum() > 20 and darker[:20].sum() == 0, "the pillar casts a shadow on the ground"
    # the pillar in the albedo view: stone is grey, grass green; its width per row
    grey = (np.abs(alb[..., 1] - alb[..., 0]) < 12) & (alb.mean(-1) > 30)  # sky: black
    # (rows above the area's closed stone side, seen at the bottom)
    cols = [np.flatnonzero(row) for row in grey[:54, 20:76]]
    widths = [c.max() - c.min() + 1 for c in cols if len(c) > 3]
    assert len(widths) > 10 and max(widths) - min(widths) <= 2, widths


def test_frame_tells_a_host_what_to_composite(gl, area):
    """prepare() returns what a host compositing the frame itself reads: the final
    colour, the opaque depth and, when peeling drew water, its depth in front of it."""
    b, L, meshes, lights = area
    r = _renderer(gl)
    r.set_area(b, L, -1, -1, ring=True, backend="numpy")
    cam = Camera(16, 20, 75, 0, -89)  # straight down onto the pool
    f = r.prepare(cam, 12.0, SIZE)
    r.submit(f)
    assert f.layers == 3 and not f.use_oit and f.color.size == SIZE
    d = r.dev.read(f.depth)[..., 0]
    w = r.dev.read(f.blend_depth)[..., 0]
    water = w < 1.0
    assert water.sum() > 50 and (w[water] < d[water]).all()  # the surface lies in front
    r.s.transparency = "oit"
    f = r.prepare(cam, 12.0, SIZE)
    r.submit(f)
    assert f.use_oit and f.layers == 0 and f.blend_depth is None
    r.release()


def test_a_host_folding_the_final_pass_gets_its_picture(gl, area):
    """The Blender viewport's composite does the final pass itself at full quality
    (submit(f, final=False); shaders/viewport.frag with FOLD, from `Frame.final`'s
    inputs): into a plain target (no sRGB encoding) it writes what the final pass
    writes, distance blur and tone curve included, and alpha 1 wherever it drew."""
    from voxel_addon.blender.liveview import composite
    from voxel_addon.render.device import State
    b, L, meshes, lights = area
    r = _renderer(gl, dof=True, distance=1)  # near blur: the fold must mix it in
    r.set_area(b, L, -1, -1, ring=True, backend="numpy")
    cam = CAMS[0]
    f = r.prepare(cam, 12.0, SIZE)
    r.submit(f)
    ref = r.dev.read(f.color)[..., :3].astype(int)
    f = r.prepare(cam, 12.0, SIZE)
    r.submit(f, final=False)
    assert composite.folds(f, SIZE) and not composite.folds(f, (SIZE[0] * 2, SIZE[1] * 2))
    dev = r.dev
    prog, tex = composite.program(dev, f, SIZE, keep=True)
    assert "blurred" in tex  # the distance blur is part of what is folded
    color, depth = dev.texture(SIZE, "rgba8"), dev.texture(SIZE, "r32f")
    t = dev.target([color, depth])
    with dev.begin(t, State(), clear=True):
        dev.use(prog, tex, {"host_vp": np.eye(4), "sky": True})
        dev.draw()
    out = dev.read(color)
    assert (out[..., 3] == 255).all()
    d = np.abs(out[..., :3].astype(int) - ref)
    assert d.max() <= 1, d.max()
    assert ref.std() > 10  # a picture, not a flat colour
    dev.release(t, color, depth)
    r.release()


def test_from_matrices_takes_blender_matrices():
    """Blender's region_3d.view_matrix / window_matrix are mathutils.Matrix (rows as
    rows): they go in as they are."""
    pytest.importorskip("bpy")  # brings mathutils
    import mathutils
    cam = Camera(12.0, -30.0, 90.0, 60.0, -25.0, 50.0, 1.6, 0.5, 800.0)
    V = mathutils.Matrix([list(r) for r in cam.view()])
    P = mathutils.Matrix([list(r) for r in cam.proj()])
    m = Camera.from_matrices(V, P)
    assert np.allclose(m.matrices()[0], cam.matrices()[0], atol=1e-5)
    assert np.allclose((m.x, m.y, m.z, m.yaw, m.pitch, m.fov), (12, -30, 90, 60, -25, 50),
                       atol=1e-4)
    box = C.ortho(-8, 8, -5, 5, -100, 100)
    o = Camera.from_matrices(V, mathutils.Matrix([list(r) for r in box]))
    assert o.ortho and np.isclose(o.near, -100, atol=1e-3) and np.isclose(o.far, 100, atol=1e-3)



def test_view_camera_is_from_matrices():
    """The live view's camera (blender/liveview/options.view_camera: closed form for a
    region's rigid view, the projection's part kept per window matrix) is the general
    Camera.from_matrices of the same matrices: eye, angles, clip range, and the
    frame's matrix and its inverse; perspective and orthographic, mathutils or tuples."""
    pytest.importorskip("bpy")  # brings mathutils
    import mathutils
    from voxel_addon.blender.liveview.options import view_camera
    far = 16 * 16 * 1.5 + 256.0
    for i, (yaw, pitch) in enumerate(((30.0, -20.0), (200.0, -75.0), (-95.0, 10.0))):
        cam = Camera(5.0 * i - 40.0, 12.0, 70.0 + i, yaw, pitch, 50.0, 1.7, 0.5, 800.0)
        for proj in (cam.proj(), C.ortho(-30, 30, -18, 18, -500, 500)):
            V = mathutils.Matrix([list(r) for r in cam.view()])
            W = mathutils.Matrix([list(r) for r in proj])
            got = view_camera(tuple(map(tuple, V)), tuple(map(tuple, W)), far)
            again = view_camera(V, W, far)  # (the projection's part kept)
            ref = Camera.from_matrices(V, got.proj_m)
            for c in (got, again):
                assert np.allclose((c.x, c.y, c.z, c.yaw, c.pitch, c.fov, c.aspect, c.near, c.far),
                                   (ref.x, ref.y, ref.z, ref.yaw, ref.pitch, ref.fov, ref.aspect,
                                    ref.near, ref.far), atol=1e-6)
                vp, inv = c.matrices()
                assert np.allclose(vp, ref.proj_m @ ref.view_m, atol=1e-9)
                assert np.allclose(inv @ vp, np.eye(4), atol=1e-6)
            assert got.ortho == (proj[3][3] == 1.0) and np.isclose(got.far, far)


def test_region_height_is_one_for_all_shown(gl, area):
    """Chunks of another region height are refused while others are shown, and taken
    once nothing is (the region table starts over)."""
    b, L, meshes, lights = area
    other = meshing.build_chunks(b, (-1, -1), backend="numpy", region_h=32)
    r = _renderer(gl)
    r.update_chunks(Chunk(k, m, lights[k]) for k, m in meshes.items())
    with pytest.raises(ValueError, match="region height"):
        r.update_chunks([Chunk((0, 0), other[0, 0], lights[0, 0])])
    want = _frames(r)
    r.remove_chunks(list(meshes))
    r.update_chunks(Chunk(k, m, lights[k]) for k, m in other.items())
    assert r.geo.nreg == 8
    got = _frames(r)
    # other merges and finer culling: other triangle counts, the same picture
    assert got[1] > 0 and np.abs(got[0].astype(int) - want[0]).mean() < 0.5
    r.release()
