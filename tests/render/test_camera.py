"""Region culling: the fast plane test equals the thesis's brute-force 8-corner clip test."""
import numpy as np

from voxel_addon.render import camera as C

_CORNERS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], float)


def brute(mvp, lo, hi):
    pts = lo[:, None, :] + (hi - lo)[:, None, :] * _CORNERS[None]
    clip = (np.c_[pts.reshape(-1, 3), np.ones(len(pts) * 8)] @ mvp.T).reshape(-1, 8, 4)
    x, y, z, w = np.moveaxis(clip, -1, 0)
    return ~((x < -w).all(1) | (x > w).all(1) | (y < -w).all(1) | (y > w).all(1)
             | (z < -w).all(1) | (z > w).all(1))


def test_culling_equals_brute_force():
    rng = np.random.default_rng(0)
    culled = 0
    for _ in range(40):
        cam = C.Camera(*rng.uniform(-50, 50, 2), rng.uniform(0, 200), rng.uniform(0, 360),
                       rng.uniform(-89, 89))
        lo = rng.uniform(-300, 300, (2000, 3))
        hi = lo + rng.uniform(0, 40, (2000, 3))
        got = C.visible(cam.view_proj(), lo, hi)
        assert (got == brute(cam.view_proj(), lo, hi)).all()
        culled += (~got).sum()
    assert culled > 10000  # the cameras do cull


def test_closed_form_matrices_match_numpy():
    rng = np.random.default_rng(1)
    for _ in range(50):
        cam = C.Camera(*rng.uniform(-1e4, 1e4, 2), rng.uniform(0, 256), rng.uniform(-720, 720),
                       rng.uniform(-90, 90), rng.uniform(20, 110), rng.uniform(0.5, 3),
                       rng.uniform(0.05, 1), rng.uniform(100, 2000))
        vp, inv = cam.matrices()
        assert np.allclose(vp, cam.proj() @ cam.view())
        assert np.allclose(inv, np.linalg.inv(vp), rtol=1e-6, atol=1e-9 * np.abs(inv).max())
        # what lies ahead of the camera lands in the middle of the screen
        p = vp @ np.r_[cam.pos + cam.forward * (cam.near + 5.0), 1.0]
        assert np.allclose(p[:2] / p[3], 0.0, atol=1e-6) and -1 < p[2] / p[3] < 1


def test_shadow_matrix_matches_numpy_reference():
    """The light matrix in Python floats equals the NumPy formulation: ortho fitted to
    the frustum corners (from the inverse view-projection) in light space, the near
    plane reaching back to the top of the area."""
    from voxel_addon.render import Settings, shadow
    s = Settings()
    area = (-3, -2, 4, 5)
    rng = np.random.default_rng(3)
    for _ in range(20):
        cam = C.Camera(*rng.uniform(-40, 40, 2), rng.uniform(60, 120), rng.uniform(0, 360),
                       rng.uniform(-80, 80), 70.0, rng.uniform(1, 2), 0.1, 600.0)
        d = rng.normal(size=3)
        d[2] = abs(d[2]) + 0.1
        d /= np.linalg.norm(d)
        got, texel, bias = shadow.fit(cam, d, area, s.shadow_fade, s.shadow_size)
        near_cam = C.Camera(cam.x, cam.y, cam.z, cam.yaw, cam.pitch, cam.fov, cam.aspect,
                            cam.near, s.shadow_fade + 2.0)
        corners = C.frustum_corners(np.linalg.inv(near_cam.view_proj()))
        assert np.allclose(sorted(near_cam.corners()), sorted(map(tuple, corners)), atol=1e-6)
        view = C.look_at(corners.mean(0), -d)
        lc = corners @ view[:3, :3].T + view[:3, 3]
        lo, hi = lc.min(0), lc.max(0)
        box = np.array([[x, y, z, 1.0] for x in (-48, 64) for y in (-32, 80) for z in (0, 256)])
        top = max(hi[2], (box @ view[2]).max())
        near, far = -top - 1.0, -lo[2] + 1.0
        want = C.ortho(lo[0], hi[0], lo[1], hi[1], near, far) @ view
        assert np.allclose(got, want, atol=1e-9)
        assert np.isclose(texel, max(hi[0] - lo[0], hi[1] - lo[1]) / s.shadow_size)
        assert np.isclose(bias, 0.05 / (far - near))


def test_batches_draw_every_visible_region_once(gl):
    """Region batches (geometry.py) against brute force: for random cameras, every
    quad of every chunk region whose own box may be in view is drawn, each once, and
    what is drawn lies between the first and the last visible region of its batch."""
    from collections import Counter
    from voxel_addon import meshing
    from voxel_addon.core import chunk
    from voxel_addon.core.blocks import REGISTRY as R
    from voxel_addon.render.device.mgl import MglDevice
    from voxel_addon.render.geometry import PASSES, Geometry
    rng = np.random.default_rng(7)
    b = chunk.empty(width=16 * 6 + 2, depth=16 * 6 + 2)
    b[:, :, :40] = R.id("stone")
    b[:, :, 40:200][rng.random((98, 98, 160)) < 0.002] = R.id("stone")  # scattered regions
    b[rng.random(b.shape) < 0.0005] = R.id("water")
    meshes = meshing.build_chunks(b, (-3, -3), backend="numpy")
    dev = MglDevice(gl)
    geo = Geometry(dev)
    geo.set_chunks(meshes)
    geo.commit()
    words = {}  # device mesh -> its words (read back)
    h = geo.region_h
    checked = culled = 0
    for _ in range(30):
        cam = C.Camera(*rng.uniform(-80, 80, 2), rng.uniform(0, 250), rng.uniform(0, 360),
                       rng.uniform(-89, 89), rng.uniform(30, 100), rng.uniform(0.5, 2.5))
        vp = cam.view_proj()
        drawn = geo.batches(geo.cull(vp), PASSES)
        for p, name in enumerate(PASSES):
            got = []
            for mesh, first, n, origin in drawn[name] or ():
                if id(mesh) not in words:
                    words[id(mesh)] = np.frombuffer(mesh.vbo.read(), np.uint32).reshape(-1, 2)
                w = words[id(mesh)][4 * first:4 * (first + n)]
                ox, oy = origin[0] // 16 + (w[:, 1] & 3), origin[1] // 16 + ((w[:, 1] >> 2) & 3)
                got += list(zip(ox.tolist(), oy.tolist(), ((w[:, 1] >> 4) & 255).tolist(),
                                w[:, 0].tolist()))
            want, every = [], []
            for (cx, cy), m in meshes.items():
                for r in range(geo.nreg):
                    f, n = m.ranges[r, p]
                    v = [(cx, cy, r, x) for x in m.vertices[f:f + n].tolist()]
                    every += v
                    box = C.visible(vp, np.array([[cx * 16 - .5, cy * 16 - .5, r * h - .5]]),
                                    np.array([[cx * 16 + 16.5, cy * 16 + 16.5, r * h + h + .5]]))
                    if box[0]:
                        want += v
            cg, cw, call = Counter(got), Counter(want), Counter(every)
            assert not cw - cg, (name, "a visible region was not drawn")
            assert not cg - call, (name, "drawn twice, or not a shown quad")
            checked += len(every) // 4
            culled += (len(every) - len(got)) // 4
    assert checked > 1000 and 0 < culled < checked
    geo.release()
    dev.close()


def test_batches_are_the_runs_of_visible_rows(gl):
    """Geometry.batches against a plain loop over its rows: for random visibility
    masks, one draw per maximal run of visible rows of one batch, in order; with an
    eye the same draws, nearest first (by their first row's box)."""
    from voxel_addon import meshing
    from voxel_addon.core import chunk
    from voxel_addon.core.blocks import REGISTRY as R
    from voxel_addon.render.device.mgl import MglDevice
    from voxel_addon.render.geometry import PASSES, Geometry
    rng = np.random.default_rng(3)
    b = chunk.empty(width=16 * 5 + 2, depth=16 * 5 + 2)
    b[:, :, :30] = R.id("stone")
    b[:, :, 30:120][rng.random((82, 82, 90)) < 0.003] = R.id("stone")
    b[rng.random(b.shape) < 0.0005] = R.id("water")
    b[:, :, 30][rng.random((82, 82)) < 0.3] = R.id("tall_grass")  # (cutout2: double-sided)
    dev = MglDevice(gl)
    geo = Geometry(dev)
    geo.set_chunks(meshing.build_chunks(b, (-2, -2), backend="numpy"))
    geo.commit()
    n = geo.cull(np.eye(4)).size
    runs = 0
    for share in (0.0, 0.1, 0.5, 0.9, 1.0):
        vis = rng.random(n) < share
        got = geo.batches(vis, PASSES)
        eye = rng.uniform(-40, 100, 3)
        near = geo.batches(vis, PASSES, "near", eye=eye)
        for p, name in enumerate(PASSES):
            want, prev, at = [], None, {}
            t = geo._rows[p]
            for j, (bi, q, c, box) in enumerate(zip(*t.tolist()) if t is not None else ()):
                if not vis[box]:
                    prev = None
                    continue
                b = geo._list[bi]
                if prev == bi:
                    m, f, k, o = want[-1]
                    want[-1] = (m, f, q + c - f, o)
                else:
                    want.append((b.meshes[p], q, c, b.origin))
                    at[id(b.meshes[p]), q] = geo._boxes[:3, box]  # (the first row's box)
                prev = bi
            runs += len(want)
            assert (got[name] or []) == want, (name, share)
            # with an eye: the same ranges, nearest first
            key = [(id(m), f, k) for m, f, k, _ in want]
            mine = [(id(m), f, k) for m, f, k, _ in near[name] or []]
            assert sorted(mine) == sorted(key), (name, share)
            d = [float(((at[m, f] - eye) ** 2).sum()) for m, f, _ in mine]
            assert all(a <= b * (1 + 1e-5) + 1e-3 for a, b in zip(d, d[1:])), (name, share)
        # a reach for the plants: theirs only from boxes within it, the others' as they were
        c, eye = geo._boxes, np.array([*rng.uniform(-20, 40, 2), 60.0])
        gap = np.maximum(np.abs(c[:2] - eye[:2, None]) - c[3:5], 0.0)
        within = (gap ** 2).sum(0) <= 24.0 ** 2
        assert 0 < within.sum() < within.size
        reach = geo.batches(vis, PASSES, "reach", eye=eye, reach={"cutout2": 24.0})
        plain = geo.batches(vis & within, PASSES, "within", eye=eye)
        every = geo.batches(vis, PASSES, "every", eye=eye)
        def same(a, b):
            return sorted((id(m), f, k) for m, f, k, _ in a or []) == \
                sorted((id(m), f, k) for m, f, k, _ in b or [])
        for name in PASSES:
            assert same(reach[name], (plain if name == "cutout2" else every)[name]), (name, share)
        assert every["cutout2"] or share == 0.0  # (plants shown)
        away = geo.batches(vis, PASSES, "reach", eye=eye + (500.0, 0.0, 0.0), reach={"cutout2": 24.0})
        assert away["cutout2"] is None  # (not the last answer)
        assert same(away["opaque"], reach["opaque"])
    assert runs > 50
    geo.release()
    dev.close()
